"""Time the actor on batches: ``CompiledActor.batch`` against the two ways it chooses between.

``python -m np_policy.bench_actor [--checkpoint checkpoints/site_np_footprint.pt] [--batches 1 8 32 128]
[--repeats 20] [--rollout-clips 40] [--json]``

For each batch size B this prints the rows per second of ``CompiledActor.batch`` beside its two paths: the
compiled kernel over the batch (``_mean_actions``: the single-observation network per row, how every batch ran
before ``TORCH_BATCH``) and the torch model's ``mean_action`` on the whole batch, one thread as in a closed-loop
worker. ``batch`` should match the faster of the two at every size. The footprint planner's sampled round starts
as a batch of 32 rollouts and its rescue rounds as 128, shrinking as rollouts end. Observations are synthetic flat
vectors of the checkpoint's layout (`np_policy.bench_update.synthetic_obs`); the time does not depend on their
values.

Then the mean rollout of one env (``CompiledActor.mean_rollout``, the paper's planner and the footprint planners'
first stage) from the first frames of the first ``--rollout-clips`` difficult training clips: arcs per second of
the whole loop (network and env step) beside the network alone evaluated whole once per arc (``_mean_action``),
the figure to beat, since a rollout that evaluated the whole network at every arc could not be faster than that.
The loop computes the scene-constant geometry token once per rollout (`np_policy.inference`). Run it on an otherwise
idle machine.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from functools import partial
from pathlib import Path

import numpy as np
import torch

from np_policy.bench_update import _seconds, synthetic_obs
from np_policy.inference import TORCH_BATCH, CompiledActor, _mean_action, _mean_actions
from np_policy.planner import NeuralParkerPlanner, Policy
from np_policy.threads import threads
from np_sim.cli import cli_boundary, non_negative_int, positive_int


def _best_seconds(fn, repeats: int) -> float:
    """The fastest of ``repeats`` calls of ``fn`` after one warm-up call (s)."""
    fn()
    return min(_seconds(fn) for _ in range(repeats))


def measure(checkpoint: str | Path, batches=(1, 8, 32, 128), repeats: int = 20) -> list[dict]:
    """Rows per second of the three ways to act on a batch (module docstring), per batch size."""
    rows = []
    with threads(1):
        model = Policy.load(checkpoint).model.eval()
        actor = CompiledActor(model)
        obs = synthetic_obs(model.encoder.obs_config, max(batches), torch.Generator().manual_seed(0))
        for b in batches:
            x = obs[:b].numpy()
            batched = _best_seconds(lambda: actor.batch(x), repeats)
            compiled = _best_seconds(lambda: _mean_actions(x, actor.mats, actor.vecs, actor.sections, actor.shape,
                                                           actor.eps), repeats)
            with torch.no_grad():
                library = _best_seconds(lambda: model.mean_action(obs[:b]), repeats)
            rows.append({"batch": b, "batch_rows_per_s": b / batched, "compiled_kernel_rows_per_s": b / compiled,
                         "torch_rows_per_s": b / library, "speedup_vs_compiled_kernel": compiled / batched})
    return rows


def measure_rollout(checkpoint: str | Path, clips: int = 40, repeats: int = 5) -> dict:
    """Arcs per second of the compiled mean rollout and of the whole network per arc (module docstring), over the
    first frames of the first ``clips`` difficult training clips whose scene the compiled loop plays; each rollout
    timed from its reset state (the reset itself not timed), the best of ``repeats``."""
    from np_sim.clips import difficult_clips

    planner = NeuralParkerPlanner.from_checkpoint(checkpoint)
    rollouts, actor = planner.mean, planner.actor
    cases = [(c.frame_scene(0, pose=c.start), np.asarray(c.start, float)) for c in difficult_clips("train")[:clips]]
    cores = [(rollouts.core(scene), start) for scene, start in cases if actor.plays_rollout(rollouts.core(scene))]
    if not cores:
        raise ValueError(f"bench_actor: none of the first {clips} training clips is played by the compiled rollout")
    arcs, loop_s, network_s = 0, 0.0, 0.0
    with threads(1):
        for core, start in cores:
            n, best = _best_rollout(actor, core, start, repeats)
            obs = core.obs[0].copy()  # the end state's observation: the network's time does not depend on it
            arcs += n
            loop_s += best
            network_s += n * _best_seconds(partial(_mean_action, obs, actor.mats, actor.vecs, actor.sections,
                                                   actor.shape, actor.eps), repeats)
    return {"scenes": len(cores), "arcs": arcs, "rollout_arcs_per_s": arcs / loop_s,
            "network_alone_arcs_per_s": arcs / network_s}


def _best_rollout(actor: CompiledActor, core, start: np.ndarray, repeats: int) -> tuple[int, float]:
    """(arcs, fastest of ``repeats`` timed rollouts (s)) of the mean rollout from ``start``, after a warm-up."""
    rng, best, n = np.random.default_rng(0), math.inf, 0
    for _ in range(repeats + 1):
        core.reset_envs(np.arange(1), rng, 0, start)
        t0 = time.perf_counter()
        n = len(actor.mean_rollout(core))
        best = min(best, time.perf_counter() - t0)
    return n, best


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring); returns the figures of `measure` ('batches') and
    of `measure_rollout` ('mean_rollout', None with ``--rollout-clips 0``)."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.bench_actor", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--checkpoint", type=Path, default=Path("checkpoints/site_np_footprint.pt"))
    parser.add_argument("--batches", type=positive_int, nargs="+", default=[1, 8, 32, 128])
    parser.add_argument("--repeats", type=positive_int, default=20, help="timed calls per figure (best kept)")
    parser.add_argument("--rollout-clips", type=non_negative_int, default=40,
                        help="difficult training clips whose first frame the mean-rollout figure plays (0: none)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)
    rows = measure(args.checkpoint, tuple(args.batches), args.repeats)
    rollout = measure_rollout(args.checkpoint, args.rollout_clips, min(args.repeats, 5)) if args.rollout_clips else None
    figures = {"batches": rows, "mean_rollout": rollout}
    if args.json:
        print(json.dumps(figures))
        return figures
    print(f"actor of {args.checkpoint}, rows per second (best of {args.repeats}); batches of {TORCH_BATCH} or "
          f"more go to torch:")
    print(f"{'batch':>6} {'CompiledActor.batch':>20} {'compiled kernel':>16} {'torch, 1 thread':>16} "
          f"{'batch / compiled':>17}")
    for r in rows:
        print(f"{r['batch']:>6} {r['batch_rows_per_s']:>20,.0f} {r['compiled_kernel_rows_per_s']:>16,.0f} "
              f"{r['torch_rows_per_s']:>16,.0f} {r['speedup_vs_compiled_kernel']:>16.2f}x")
    if rollout is not None:
        print(f"mean rollout on {rollout['scenes']} training-clip first frames ({rollout['arcs']} arcs): "
              f"{rollout['rollout_arcs_per_s']:,.0f} arcs/s with the env's step, against "
              f"{rollout['network_alone_arcs_per_s']:,.0f} arcs/s for the whole network alone per arc (to beat)")
    return figures


if __name__ == "__main__":
    main()
