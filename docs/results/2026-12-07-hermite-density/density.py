"""How the number of samples on each Hermite candidate changes the connectors' successes under the paper's rule
and under the exact reference-point rule, on the validation starts of the Factorial training scenes.

The paper checks each Hermite candidate at its N = 100 stored samples (``ConnectorConfig.n_samples``); the exact
rule (`np_sim.validate`) tests the cubic itself. Here the same checkpoints plan the same starts with N = 100 and
N = 1,000 (the connector's selection and the paper's rule both read the N samples; nothing else changes), with
their own connector and with the other one swapped in at evaluation. Validation starts (`--split validation`: ten
seeded starts on each of the 81 training scenes), so nothing is read from the frozen test starts.

    python docs/results/2026-12-07-hermite-density/density.py [--limit N] \
        > docs/results/2026-12-07-hermite-density/density.txt
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from tqdm import tqdm

from experiments.evaluate import episode_row
from np_policy.config import PAPER
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.benchmarks.frozen import split_episodes
from np_sim.vehicle import VehicleSpec

RUNS = Path("checkpoints/runs")
CHECKPOINTS = {"fixed": ("factorial_np_fixed_seed0_lot", "factorial_np_fixed_seed1_lot"),
               "ensemble": ("factorial_np_seed0_lot", "factorial_np_seed1_lot", "factorial_np_seed2_lot")}
"""The finished runs of Table IV's fixed-connector rows and of its ensemble-trained row, by training connector."""
COLUMNS = ("success", "exact_ref_point", "exact_footprint", "L", "delta_kappa", "plan_time_ms")
SAMPLES = (100, 1000)


def planner_with_samples(run: str, connector: str, n_samples: int) -> NeuralParkerPlanner:
    """The run's ``best.pt`` planning as the paper's preset with ``connector``, its Hermite candidates checked at
    ``n_samples`` points each."""
    policy = Policy.load(RUNS / run / "best.pt", "factorial")
    env = policy.train.env
    env = dataclasses.replace(env, connector=dataclasses.replace(env.connector, n_samples=n_samples))
    policy = dataclasses.replace(policy, train=dataclasses.replace(policy.train, env=env))
    return NeuralParkerPlanner(policy, dataclasses.replace(PAPER, connector=connector))


def measure(planner: NeuralParkerPlanner, scenes, starts, episodes, vehicle, what: str) -> dict[str, float]:
    """Success under the paper's rule, successes that also pass the exact rules, L and Δκ over the successes, and
    the median plan time, over ``episodes``."""
    rows = [episode_row(planner, PAPER, scenes[k], starts[k, j], vehicle,
                        {"scene": scenes[k].name, "start_id": j, "checkpoint": what, "seed_index": 0})
            for k, j in tqdm(episodes, desc=what, leave=False)]
    ok = np.array([r["success"] for r in rows], bool)
    return {"success": ok.mean(),
            "exact_ref_point": (ok & np.array([r["exact_ref_point_valid"] for r in rows], bool)).mean(),
            "exact_footprint": (ok & np.array([r["exact_footprint_valid"] for r in rows], bool)).mean(),
            "L": np.mean([r["L"] for r in rows if r["success"]]),
            "delta_kappa": np.mean([r["delta_kappa"] for r in rows if r["success"]]),
            "plan_time_ms": np.median([r["plan_time_ms"] for r in rows])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--limit", type=int, default=None, help="only the first N validation starts")
    args = parser.parse_args()
    vehicle = VehicleSpec()
    scenes, starts = split_episodes("factorial", "validation", 10, vehicle, 0)
    episodes = [(k, j) for k in range(len(scenes)) for j in range(starts.shape[1])][:args.limit]
    print(f"{len(episodes)} validation starts on {len(scenes)} training scenes; success: paper's rule at N samples; "
          "exact: successes that also pass the exact rule; L, Δκ: over each row's successes\n")
    print("| trained with | run | evaluated with | N | " + " | ".join(COLUMNS) + " |")
    print("|---" * (4 + len(COLUMNS)) + "|")
    results = {}
    for trained, runs in CHECKPOINTS.items():
        for run in runs:
            for connector in ("fixed", "ensemble"):
                for n in SAMPLES:
                    m = measure(planner_with_samples(run, connector, n), scenes, starts, episodes, vehicle,
                                f"{run} {connector} N={n}")
                    results.setdefault((trained, connector, n), []).append(m)
                    print(f"| {trained} | {run} | {connector} | {n} | "
                          + " | ".join(f"{m[c]:.3f}" for c in COLUMNS) + " |", flush=True)
    print("\nMean ± sample SD over the runs:\n")
    print("| trained with | evaluated with | N | runs | " + " | ".join(COLUMNS) + " |")
    print("|---" * (4 + len(COLUMNS)) + "|")
    for (trained, connector, n), ms in results.items():
        cells = [f"{np.mean([m[c] for m in ms]):.3f} ± {np.std([m[c] for m in ms], ddof=1):.3f}" for c in COLUMNS]
        print(f"| {trained} | {connector} | {n} | {len(ms)} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
