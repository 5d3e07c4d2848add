"""Time NeuralParker planning queries on the Factorial frozen test starts (speed goal: median ≤ 1 ms).

``python -m np_policy.bench_planner [--checkpoint checkpoints/factorial_np_seed0.pt] [--episodes N] [--seed S]
[--samples N] [--json]``

Each query is ``NeuralParkerPlanner.plan(scene, start)`` (mean action in the loop, the checkpoint's connector),
timed by the planner itself (``Plan.plan_time_s``: env reset to the returned plan). The first query of every scene
is played once untimed (scene packing and numba dispatch warm-up), as a planner serving a map would. Printed beside
the figures: the goal (≤ 1 ms median) and the paper's C++ figure (0.37 ms). Also printed: arcs per query and the
compiled policy's time per call, to show where the time goes. ``--samples N`` times the best-of-N planner
(`np_policy.sampling`: the mean rollout and N sampled rollouts, then the choice) instead; the 1 ms goal is the
paper's planner's. Run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from np_policy.config import PAPER
from np_policy.planner import NeuralParkerPlanner
from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.cli import cli_boundary, non_negative_int, positive_int
from np_sim.env import ParkingEnv

GOAL_MEDIAN_MS = 1.0
PAPER_CPP_MS = 0.37


def measure(checkpoint: str | Path, episodes: int | None = None, seed: int = 0, samples: int = 0) -> dict:
    """Median / p90 plan time (ms), success and arcs per query over ``episodes`` seeded frozen starts (all
    1,080 by default), and the compiled policy's µs per call on the observations those queries saw; ``samples``
    > 0 times the best-of-N planner."""
    config = dataclasses.replace(PAPER, samples=samples)
    planner = NeuralParkerPlanner.from_checkpoint(checkpoint, config, benchmark="factorial")
    scenes = load_benchmark("factorial", "test")
    starts = frozen_starts("factorial")
    pairs = [(i, j) for i in range(len(scenes)) for j in range(starts.shape[1])]
    if episodes is not None and episodes < len(pairs):
        chosen = np.random.default_rng(seed).choice(len(pairs), size=episodes, replace=False)
        pairs = [pairs[k] for k in sorted(chosen)]
    for i in sorted({i for i, _ in pairs}):
        planner.plan(scenes[i], starts[i, 0])
    times, arcs, success = [], [], []
    for i, j in pairs:
        plan = planner.plan(scenes[i], starts[i, j])
        times.append(plan.plan_time_s)
        arcs.append(len(plan.arcs))
        success.append(plan.success)
    obs, _ = ParkingEnv(scenes[0], planner.env_config).reset(options={"start": starts[0, 0]})
    calls = 2000
    t0 = time.perf_counter()
    for _ in range(calls):
        planner.actor(obs)
    actor_us = 1e6 * (time.perf_counter() - t0) / calls
    ms = 1e3 * np.asarray(times)
    return {"checkpoint": str(checkpoint), "samples": samples, "episodes": len(pairs),
            "success": float(np.mean(success)),
            "plan_time_median_ms": float(np.median(ms)), "plan_time_p90_ms": float(np.percentile(ms, 90)),
            "plan_time_mean_ms": float(ms.mean()), "arcs_median": float(np.median(arcs)),
            "arcs_mean": float(np.mean(arcs)), "actor_us_per_call": actor_us,
            "goal_median_ms": GOAL_MEDIAN_MS, "paper_cpp_ms": PAPER_CPP_MS}


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring); returns the figures of `measure`."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.bench_planner", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--checkpoint", type=Path, default=Path("checkpoints/factorial_np_seed0.pt"))
    parser.add_argument("--episodes", type=positive_int, help="seeded subset of the 1,080 frozen starts (default all)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="subset seed")
    parser.add_argument("--samples", type=non_negative_int, default=0, metavar="N",
                        help="time the best of the mean rollout and N sampled rollouts (default 0: the paper's "
                             "planner)")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    args = parser.parse_args(argv)
    result = measure(args.checkpoint, args.episodes, args.seed, args.samples)
    if args.json:
        print(json.dumps(result))
        return result
    best_of = f", best of mean + {args.samples} sampled rollouts" if args.samples else ""
    print(f"NeuralParker ({result['checkpoint']}{best_of}) on {result['episodes']} Factorial frozen test starts:")
    print(f"  plan time median {result['plan_time_median_ms']:.3f} ms (goal <= {GOAL_MEDIAN_MS}; paper C++ "
          f"{PAPER_CPP_MS}), p90 {result['plan_time_p90_ms']:.2f} ms, mean {result['plan_time_mean_ms']:.2f} ms")
    print(f"  success {result['success']:.3f}; arcs per query median {result['arcs_median']:.0f}, "
          f"mean {result['arcs_mean']:.1f}; compiled policy {result['actor_us_per_call']:.0f} µs per call")
    return result


if __name__ == "__main__":
    main()
