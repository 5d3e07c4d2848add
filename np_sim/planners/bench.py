"""Plan-time benchmark of the classical planners: ``python -m np_sim.planners.bench [--benchmark factorial]
[--convention reference_point|footprint] [--episodes N] [--ompl-episodes M] [--json]``.

* Hybrid A* on the frozen test starts (all of them, or a seeded subset of N): success, plan time median / p90 and
  expanded nodes median, every returned path re-checked with the rule it is scored by (``np_sim.validate``; the
  first query of a scene includes building its heuristic grid's free cells, and each query the grid distances it
  is the first to ask for; one warm-up query loads the compiled kernels first);
* the OMPL peer (RRT*, same time budget) and Hybrid A* on the same seeded subset of M starts: success and tree
  vertices.

Targets are printed beside the figures: Hybrid A* success ≥ 0.95 on the Factorial starts
(reference-point convention) and median plan time ≤ 20 ms (the paper's C++ reports 5.26 ms on its site clips).
NP-Guided A* needs the policy (torch), which ``np_sim`` never imports: its time ratio to Hybrid A* is printed by
``python -m experiments.planners``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.cli import cli_boundary, non_negative_int, positive_int
from np_sim.planners.hybrid_astar import HybridAStar
from np_sim.validate import plan_valid, scoring_rule


def _episodes(n_scenes: int, n_starts: int, count: int | None, rng: np.random.Generator) -> list[tuple[int, int]]:
    every = [(k, j) for k in range(n_scenes) for j in range(n_starts)]
    if count is None or count >= len(every):
        return every
    return [every[i] for i in sorted(rng.choice(len(every), count, replace=False))]


def _summary(plans, valid) -> dict:
    times = np.array([p.plan_time_s for p in plans]) * 1e3
    return {"episodes": len(plans), "success": float(np.mean([p.success for p in plans])),
            "valid_paths": float(np.mean(valid)), "plan_time_median_ms": float(np.median(times)),
            "plan_time_p90_ms": float(np.percentile(times, 90)),
            "expanded_nodes_median": float(np.median([p.expanded_nodes for p in plans]))}


def bench(benchmark: str = "factorial", convention: str = "reference_point", episodes: int | None = None,
          ompl_episodes: int = 27, seed: int = 0) -> dict:
    """Run the measurements; returns a dict of figures (``hybrid_astar`` and, when M > 0, ``ompl_subset``)."""
    scenes = load_benchmark(benchmark, "test")
    starts = frozen_starts(benchmark)
    rng = np.random.default_rng(seed)
    search = HybridAStar(convention=convention)
    HybridAStar(convention=convention).plan(scenes[0], starts[0, 0])  # load the compiled kernels
    chosen = _episodes(len(scenes), starts.shape[1], episodes, rng)
    plans = [search.plan(scenes[k], starts[k, j]) for k, j in chosen]
    valid = [plan_valid(scenes[k], p, scoring_rule(convention)) for p, (k, j) in zip(plans, chosen)]
    result = {"benchmark": benchmark, "convention": convention, "hybrid_astar": _summary(plans, valid),
              "time_budget_s": search.config.time_budget_s}
    if ompl_episodes > 0:
        from np_sim.planners.ompl_peer import OmplPeer, OmplPeerConfig

        peer = OmplPeer(OmplPeerConfig(time_budget_s=search.config.time_budget_s, seed=seed), convention)
        subset = _episodes(len(scenes), starts.shape[1], ompl_episodes, rng)
        o_plans = [peer.plan(scenes[k], starts[k, j]) for k, j in subset]
        o_valid = [plan_valid(scenes[k], p, scoring_rule(convention)) for p, (k, j) in zip(o_plans, subset)]
        h_plans = [search.plan(scenes[k], starts[k, j]) for k, j in subset]
        result["ompl_subset"] = {"ompl_rrtstar": _summary(o_plans, o_valid),
                                 "hybrid_astar": _summary(h_plans, [p.success for p in h_plans])}
    return result


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options)."""
    parser = argparse.ArgumentParser(prog="python -m np_sim.planners.bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=["factorial", "topology"], default="factorial")
    parser.add_argument("--convention", choices=["reference_point", "footprint"], default="reference_point")
    parser.add_argument("--episodes", type=positive_int,
                        help="seeded subset of the frozen starts for Hybrid A* (default all)")
    parser.add_argument("--ompl-episodes", type=non_negative_int, default=27,
                        help="seeded subset for the OMPL peer (0 = skip)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="subset and OMPL seed")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    result = bench(args.benchmark, args.convention, args.episodes, args.ompl_episodes, args.seed)
    result["wall_s"] = time.perf_counter() - t0
    if args.json:
        print(json.dumps(result))
        return result
    h = result["hybrid_astar"]
    print(f"Hybrid A* on {h['episodes']} {args.benchmark} frozen test starts ({args.convention}):")
    print(f"  success {h['success']:.4f} (target >= 0.95), valid paths {h['valid_paths']:.4f}")
    print(f"  plan time median {h['plan_time_median_ms']:.2f} ms (target <= 20; paper C++ 5.26), "
          f"p90 {h['plan_time_p90_ms']:.2f} ms; expanded nodes median {h['expanded_nodes_median']:.0f}")
    if "ompl_subset" in result:
        o, hs = result["ompl_subset"]["ompl_rrtstar"], result["ompl_subset"]["hybrid_astar"]
        print(f"Seeded subset of {o['episodes']} starts, budget {result['time_budget_s']:.2f} s each:")
        print(f"  OMPL RRT*: success {o['success']:.3f}, tree vertices median {o['expanded_nodes_median']:.0f}, "
              f"plan time median {o['plan_time_median_ms']:.0f} ms")
        print(f"  Hybrid A*: success {hs['success']:.3f}, expanded nodes median {hs['expanded_nodes_median']:.0f}, "
              f"plan time median {hs['plan_time_median_ms']:.2f} ms")
    return result


if __name__ == "__main__":
    main()
