"""Time one PPO minibatch update (batch 8,192), its lower bound, and the model's forward throughput on this machine.

``python -m np_policy.bench_update [--batch 8192] [--chunks 8192 1024] [--scenes 81] [--forward-batch 128]
[--repeats 5] [--threads N] [--json]``

The update is timed once per ``--chunks`` value (``PPOConfig.update_chunk``: samples per forward/backward pass;
the batch size itself means one pass) and printed beside the budget the issue's goal leaves: 90 minutes for the
240-epoch recipe's 240 × 80 minibatch updates is 281 ms per update even if collecting took no time.

The recipe's chunk is timed once more with ``shared_geometry`` (the geometry branch once per distinct
scene of a chunk) and printed beside the figure to beat, the same chunk with the branch run per sample.

It then bounds the update from below: the floating-point work of one update (``torch.utils.flop_counter``), this
machine's float32 matrix-product rate (a 2,048³ ``torch.mm``), and the time the update spends inside matrix
products (``torch.profiler``), each scaled to the recipe's 19,200 updates. A wall-clock goal below the
matrix-product time cannot be met by removing overhead; only fewer or cheaper FLOPs (network, recipe, precision)
can meet it.

Observations are synthetic flat vectors of the default layout (3 obstacles and 4 boundary segments used, the rest
at the −1e4 sentinel); their slot part is drawn from ``--scenes`` distinct rows, as a minibatch of the Factorial
training set holds at most its 81 scenes. The timing depends on the values only through that count.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import torch
from torch.profiler import ProfilerActivity, profile
from torch.utils.flop_counter import FlopCounterMode

from np_sim.config import ObservationConfig
from np_sim.observation import observation_sections, observation_size
from np_policy.config import NetworkConfig, PPOConfig
from np_policy.network import ActorCritic
from np_policy.ppo import make_optimizer, ppo_update
from np_sim.cli import cli_boundary, positive_int


_RECIPE = PPOConfig()
RECIPE_UPDATES = _RECIPE.total_updates * _RECIPE.repeats * (_RECIPE.steps_per_collect // _RECIPE.batch_size)
"""Minibatch updates in the 240-epoch recipe (240 epochs × 4 collects × 10 repeats × 2 minibatches = 19,200)."""
UPDATE_BUDGET_MS = 90 * 60 * 1000 / RECIPE_UPDATES
"""The issue's 90-minute goal spread over the recipe's minibatch updates (281 ms each)."""
MATRIX_PRODUCTS = ("aten::mm", "aten::addmm", "aten::bmm", "aten::baddbmm")


def _seconds(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def sgemm_gflops(size: int = 2048, repeats: int = 5) -> float:
    """This machine's float32 matrix-product rate: GFLOP/s of a ``size``³ ``torch.mm`` (best of ``repeats``)."""
    a, b = torch.randn(size, size), torch.randn(size, size)
    a @ b
    best = min(_seconds(lambda: a @ b) for _ in range(repeats))
    return 2 * size**3 / best / 1e9


def update_work(model, optimizer, data, config: PPOConfig, generator: torch.Generator) -> tuple[float, float]:
    """(GFLOP of one minibatch update, ms it spends inside matrix products) — the update's lower bound."""
    with FlopCounterMode(display=False) as flops:
        ppo_update(model, optimizer, data, config, generator)
    with profile(activities=[ProfilerActivity.CPU]) as prof:
        ppo_update(model, optimizer, data, config, generator)
    matmul_us = sum(e.self_cpu_time_total for e in prof.key_averages() if e.key in MATRIX_PRODUCTS)
    return flops.get_total_flops() / 1e9, matmul_us / 1000


def synthetic_obs(config: ObservationConfig, batch: int, generator: torch.Generator,
                  scenes: int | None = None) -> torch.Tensor:
    """(batch, obs_size) random observations; with ``scenes`` their slot part repeats that many distinct rows."""
    obs = torch.randn(batch, observation_size(config), generator=generator) * 5.0
    sec = observation_sections(config)
    if scenes and "obstacles" in sec and "boundary" in sec:
        scene_rows = obs[:scenes, sec["obstacles"][0]:sec["boundary"][1]].clone()
        obs[:, sec["obstacles"][0]:sec["boundary"][1]] = scene_rows[torch.arange(batch) % len(scene_rows)]
    if "obstacles" in sec:
        obs[:, sec["obstacles"][0] + 3 * 2 * config.vertices_per_obstacle: sec["obstacles"][1]] = config.sentinel
    if "boundary" in sec:
        obs[:, sec["boundary"][0] + 4 * 4: sec["boundary"][1]] = config.sentinel
    return obs


def _update_ms(model, optimizer, data, config: PPOConfig, g: torch.Generator, repeats: int,
               shared_geometry: bool = False) -> float:
    ppo_update(model, optimizer, data, config, g, shared_geometry)  # warm-up
    return 1000 * statistics.median(_seconds(lambda: ppo_update(model, optimizer, data, config, g, shared_geometry))
                                    for _ in range(repeats))


def measure(batch: int = 8192, forward_batch: int = 128, repeats: int = 5, threads: int | None = None,
            chunks: tuple[int, ...] = (8192, _RECIPE.update_chunk), scenes: int = 81) -> dict:
    """Median ms per minibatch update for each chunk size (and the recipe's chunk with the geometry branch shared
    per scene) and forward samples/s; returns the numbers as a dict."""
    if threads:
        torch.set_num_threads(threads)
    torch.manual_seed(0)
    g = torch.Generator().manual_seed(0)
    obs_config = ObservationConfig()
    model = ActorCritic(obs_config, NetworkConfig())
    optimizer = make_optimizer(model, PPOConfig())
    obs = synthetic_obs(obs_config, batch, g, scenes)
    data = {"obs": obs}
    data["actions"], data["log_probs"], _ = model.act(obs)
    data["advantages"], data["returns"] = torch.randn(batch, generator=g), torch.randn(batch, generator=g)

    update_ms = {min(chunk, batch): _update_ms(model, optimizer, data, PPOConfig(
        batch_size=batch, repeats=1, update_chunk=min(chunk, batch)), g, repeats) for chunk in chunks}
    bound_chunk = min(_RECIPE.update_chunk, batch)
    bound_config = PPOConfig(batch_size=batch, repeats=1, update_chunk=bound_chunk)
    per_scene_ms = _update_ms(model, optimizer, data, bound_config, g, repeats, shared_geometry=True)
    per_sample_ms = update_ms.get(bound_chunk) or _update_ms(model, optimizer, data, bound_config, g, repeats)
    update_gflop, matmul_ms = update_work(model, optimizer, data, bound_config, g)
    peak = sgemm_gflops()

    small = synthetic_obs(obs_config, forward_batch, g, scenes)
    model.act(small)
    n_calls, forward_s = 0, 0.0
    t0 = time.perf_counter()
    while forward_s < 2.0:
        model.act(small)
        n_calls += 1
        forward_s = time.perf_counter() - t0
    result = {
        "torch_threads": torch.get_num_threads(),
        "params": sum(p.numel() for p in model.parameters()),
        "update_batch": batch,
        "update_ms_by_chunk": update_ms,
        "update_budget_ms": UPDATE_BUDGET_MS,
        "scenes": scenes,
        "update_ms_per_sample_geometry": per_sample_ms,
        "update_ms_shared_geometry": per_scene_ms,
        "bound_chunk": bound_chunk,
        "update_gflop": update_gflop,
        "sgemm_gflops": peak,
        "update_at_sgemm_rate_ms": 1000 * update_gflop / peak,
        "update_matmul_ms": matmul_ms,
        "recipe_updates": RECIPE_UPDATES,
        "forward_batch": forward_batch,
        "forward_act_ms": 1000 * forward_s / n_calls,
        "forward_samples_per_s": forward_batch * n_calls / forward_s,
    }
    return result


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring); prints and returns the figures of `measure`."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.bench_update", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batch", type=positive_int, default=8192, help="minibatch size of the timed PPO update")
    parser.add_argument("--chunks", type=positive_int, nargs="+", default=[8192, _RECIPE.update_chunk],
                        help="update_chunk values to time (samples per forward/backward pass; the batch = one pass)")
    parser.add_argument("--scenes", type=positive_int, default=81,
                        help="distinct scenes (slot rows) in the synthetic minibatch (Factorial's training set: 81)")
    parser.add_argument("--forward-batch", type=positive_int, default=128,
                        help="batch of the timed act() calls (= train envs)")
    parser.add_argument("--repeats", type=positive_int, default=5, help="timed updates (median reported)")
    parser.add_argument("--threads", type=positive_int, default=None,
                        help="torch intra-op threads (default: torch's)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    out = measure(args.batch, args.forward_batch, args.repeats, args.threads, tuple(args.chunks), args.scenes)
    if args.json:
        print(json.dumps(out))
    else:
        for chunk, ms in out["update_ms_by_chunk"].items():
            print(f"PPO minibatch update, batch {out['update_batch']} in chunks of {chunk}: {ms:.0f} ms "
                  f"(budget for the 90-min recipe: {out['update_budget_ms']:.0f} ms; {out['params']} params, "
                  f"{out['torch_threads']} threads)")
        print(f"with the geometry branch once per scene ({out['scenes']} scenes), chunks of {out['bound_chunk']}: "
              f"{out['update_ms_shared_geometry']:.0f} ms (to beat: {out['update_ms_per_sample_geometry']:.0f} ms, "
              f"the branch per sample)")
        to_min = out["recipe_updates"] / 60_000
        print(f"lower bound at chunk {out['bound_chunk']}: {out['update_gflop']:.1f} GFLOP per update; at this "
              f"machine's sgemm rate ({out['sgemm_gflops']:.0f} GFLOP/s, 2048³) {out['update_at_sgemm_rate_ms']:.0f} "
              f"ms; measured inside matrix products {out['update_matmul_ms']:.0f} ms. Over the recipe's "
              f"{out['recipe_updates']:,} updates: >= {out['update_at_sgemm_rate_ms'] * to_min:.0f} min at the sgemm "
              f"rate, {out['update_matmul_ms'] * to_min:.0f} min in matrix products, before any env step "
              f"(goal: 90 min in all)")
        print(f"forward act(), batch {out['forward_batch']}: {out['forward_act_ms']:.2f} ms/call, "
              f"{out['forward_samples_per_s']:.0f} samples/s")
    return out


if __name__ == "__main__":
    main()
