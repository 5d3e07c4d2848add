"""Time one PPO minibatch update (batch 8,192) and the model's forward throughput (batch 128) on this machine.

``python -m np_policy.bench_update [--batch 8192] [--chunks 8192 1024] [--forward-batch 128] [--repeats 5]
[--threads N] [--json]``

The update is timed once per ``--chunks`` value (``PPOConfig.update_chunk``: samples per forward/backward pass;
the batch size itself means one pass) and printed beside the budget the issue's goal leaves: 90 minutes for the
240-epoch recipe's 240 × 80 minibatch updates is 281 ms per update even if collecting took no time.

Observations are synthetic flat vectors of the default layout (3 obstacles and 4 boundary segments used, the rest
at the −1e4 sentinel); the timing does not depend on their values.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import torch

from np_sim.config import ObservationConfig
from np_sim.observation import observation_sections, observation_size
from np_policy.config import NetworkConfig, PPOConfig
from np_policy.network import ActorCritic
from np_policy.ppo import make_optimizer, ppo_update


_RECIPE = PPOConfig()
UPDATE_BUDGET_MS = 90 * 60 * 1000 / (_RECIPE.epochs * _RECIPE.collects_per_epoch * _RECIPE.repeats
                                     * (_RECIPE.steps_per_collect // _RECIPE.batch_size))
"""The issue's 90-minute goal spread over the recipe's minibatch updates (281 ms each)."""


def synthetic_obs(config: ObservationConfig, batch: int, generator: torch.Generator) -> torch.Tensor:
    obs = torch.randn(batch, observation_size(config), generator=generator) * 5.0
    sec = observation_sections(config)
    if "obstacles" in sec:
        obs[:, sec["obstacles"][0] + 3 * 2 * config.vertices_per_obstacle: sec["obstacles"][1]] = config.sentinel
    if "boundary" in sec:
        obs[:, sec["boundary"][0] + 4 * 4: sec["boundary"][1]] = config.sentinel
    return obs


def main(batch: int = 8192, forward_batch: int = 128, repeats: int = 5, threads: int | None = None,
         chunks: tuple[int, ...] = (8192, _RECIPE.update_chunk)) -> dict:
    """Median ms per minibatch update for each chunk size and forward samples/s; returns the numbers as a dict."""
    if threads:
        torch.set_num_threads(threads)
    torch.manual_seed(0)
    g = torch.Generator().manual_seed(0)
    obs_config = ObservationConfig()
    model = ActorCritic(obs_config, NetworkConfig())
    optimizer = make_optimizer(model, PPOConfig())
    obs = synthetic_obs(obs_config, batch, g)
    data = {"obs": obs}
    data["actions"], data["log_probs"], _ = model.act(obs)
    data["advantages"], data["returns"] = torch.randn(batch, generator=g), torch.randn(batch, generator=g)

    update_ms = {}
    for chunk in chunks:
        config = PPOConfig(batch_size=batch, repeats=1, update_chunk=min(chunk, batch))
        ppo_update(model, optimizer, data, config, g)  # warm-up
        update_s = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            ppo_update(model, optimizer, data, config, g)
            update_s.append(time.perf_counter() - t0)
        update_ms[min(chunk, batch)] = 1000 * statistics.median(update_s)

    small = synthetic_obs(obs_config, forward_batch, g)
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
        "forward_batch": forward_batch,
        "forward_act_ms": 1000 * forward_s / n_calls,
        "forward_samples_per_s": forward_batch * n_calls / forward_s,
    }
    return result


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=8192, help="minibatch size of the timed PPO update")
    parser.add_argument("--chunks", type=int, nargs="+", default=[8192, _RECIPE.update_chunk],
                        help="update_chunk values to time (samples per forward/backward pass; the batch = one pass)")
    parser.add_argument("--forward-batch", type=int, default=128, help="batch of the timed act() calls (= train envs)")
    parser.add_argument("--repeats", type=int, default=5, help="timed updates (median reported)")
    parser.add_argument("--threads", type=int, default=None, help="torch intra-op threads (default: torch's)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    out = main(args.batch, args.forward_batch, args.repeats, args.threads, tuple(args.chunks))
    if args.json:
        print(json.dumps(out))
    else:
        for chunk, ms in out["update_ms_by_chunk"].items():
            print(f"PPO minibatch update, batch {out['update_batch']} in chunks of {chunk}: {ms:.0f} ms "
                  f"(budget for the 90-min recipe: {out['update_budget_ms']:.0f} ms; {out['params']} params, "
                  f"{out['torch_threads']} threads)")
        print(f"forward act(), batch {out['forward_batch']}: {out['forward_act_ms']:.2f} ms/call, "
              f"{out['forward_samples_per_s']:.0f} samples/s")
