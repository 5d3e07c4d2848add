"""Classical, learned and hybrid planners on one benchmark's frozen test starts (paper §IV-B, §V-A Table
``tab:twostage``, §V-F).

``python -m experiments.planners --benchmark factorial|topology [--checkpoint PATH] [--methods ...]
[--convention reference_point|footprint] [--vehicle sedan|van|FILE] [--limit N] [--out DIR [--resume]]
[--scenes FILE... [--starts N] [--seed S] | --split validation|holdout [--starts-per-scene N]]``

Methods: Hybrid A*, NP-Guided A* (Hybrid A* guided by one NeuralParker rollout), the OMPL peer (RRT* in a
Reeds–Shepp space, same time budget as Hybrid A*), NeuralParker (the checkpoint's deterministic policy) and the
staged planner (region-goal Hybrid A* prefix to 10 m, then NeuralParker). Every frozen start (1,080 Factorial,
720 Topology-Stress) is planned by every method. The table gives success on the full set; L, reversals and Δκ
(eq:metrics; staged: without the hand-off curvature jump) as means over the common-success cohort of all methods
run; plan time median and 90th percentile; expanded nodes (search methods: lattice expansions; OMPL: tree
vertices) median; beside success, the exact validity of the planned paths (`np_sim.validate`: the footprint and
the reference point swept continuously; a failure counts as invalid) and, below the table, the successes that fail
the rule their method is scored by (the paper's samples, or the env's footprint samples; NeuralParker: its
checkpoint's convention) or do not end within the target's tolerances (`np_sim.validate.ends_at_target`, read from
the plan itself; every validity column requires it). ``--vehicle`` plans for another vehicle (`np_sim.vehicle`:
the searches' footprint and κ_max, the validators' footprint; a learned planner's checkpoint must have been trained
for it); the frozen starts were drawn for the default car, so each record says whether the vehicle's footprint
at its start is free (``start_footprint_free``) and the table counts those that are not. Writes ``records.csv``/
``records.json`` (one row per episode and method), ``table.md`` and ``config.json`` into the run folder. Each
finished episode is kept in the folder as the run goes (`experiments.progress`): after a kill, ``--resume`` with the
same arguments and ``--out`` plans only the episodes that were not finished, and the records equal an uninterrupted
run's.

``--scenes FILE...`` plans your own scene files instead (`experiments.scene_files`): each file's explicit starts,
or ``--starts N`` drawn from its start region with ``--seed S``; records add the file and the start pose, and
config.json how many drawn starts were rejected in collision.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.common import first
from experiments.progress import EpisodeProgress, check_out, progress_folder
from experiments.registry import PlannerOptions, build_planners, check_names, label
from experiments.scene_files import (add_scene_arguments, add_split_arguments, common_holdout, describe,
                                     episode_scenes, load_scene_files, scene_columns, starts_summary, strictest)
from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.config import HOPE_ACTIONS
from hope_policy.train import HopeTrainConfig
from np_policy.planner import Policy
from np_sim.benchmarks.frozen import VALIDATION_STARTS_PER_SCENE
from np_sim.cli import cli_boundary, non_negative_int, positive_int, vehicle_spec
from np_sim.collision import path_valid
from np_sim.planners import HybridAStar
from np_sim.validate import plan_valid, scoring_rule
from np_sim.vehicle import VehicleSpec

METHODS = ("hybrid_astar", "np_guided_astar", "ompl_rrtstar", "neuralparker", "staged_astar_np", "hope",
           "staged_astar_hope")
"""Planners of the table (`experiments.registry`), in its row order."""
DEFAULT_METHODS = tuple(m for m in METHODS if m not in ("hope", "staged_astar_hope"))
"""What runs without naming methods: all but the two that play the adapted HOPE, which need its checkpoint."""
DEFAULT_CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")


def run(benchmark: str, methods: list[str] | None = None, checkpoint: Path | None = DEFAULT_CHECKPOINT,
        convention: str = "reference_point", out: Path | None = None, limit: int | None = None, ompl_seed: int = 0,
        progress: bool = True, hope_checkpoint: Path | None = None, hope_action: str = "sampled", hope_seed: int = 0,
        vehicle: VehicleSpec | None = None, scenes: list[Path] | None = None, n_starts: int | None = None,
        seed: int = 0, resume: bool = False, split: str = "test",
        starts_per_scene: int = VALIDATION_STARTS_PER_SCENE) -> dict[str, Any]:
    """Plan every frozen start with every method for ``vehicle`` (default the sedan); returns the records, the
    table text and the run folder. With ``scenes`` (files), their starts instead (`experiments.scene_files`:
    the files' own, or ``n_starts`` drawn with ``seed``); with ``split`` 'validation', ``starts_per_scene`` seeded
    starts on each training scene (`np_sim.benchmarks.validation_starts`). Each finished episode is kept in the
    folder as it goes (`experiments.progress`); ``resume`` continues the interrupted run in ``out``."""
    methods = check_names(DEFAULT_METHODS if methods is None else methods, METHODS)
    vehicle = VehicleSpec() if vehicle is None else vehicle
    options = PlannerOptions(checkpoint=checkpoint, convention=convention, ompl_seed=ompl_seed,
                             benchmark=None if scenes else benchmark, hope_checkpoint=hope_checkpoint,
                             hope_action=hope_action, hope_seed=hope_seed, vehicle=vehicle)
    planners = build_planners(methods, options)
    files = (load_scene_files(scenes, n_starts, seed, strictest(p.convention for p in planners.values()), vehicle)
             if scenes else None)
    holdout_every = (learned_holdout(methods, checkpoint, hope_checkpoint, benchmark) if split == "holdout" else 0)
    scenes, starts = episode_scenes(benchmark, files, split, starts_per_scene, vehicle, holdout_every)
    episodes = first([(k, j) for k in range(len(scenes)) for j in range(len(starts[k]))], limit)
    settings = {"benchmark": None if files else benchmark, "scenes": describe(files), "starts_seed": seed,
                **({} if files or split == "test" else {"split": split, "starts_per_scene": starts_per_scene}),
                **({"holdout_every": holdout_every} if holdout_every else {}),
                "methods": methods, "checkpoint": None if checkpoint is None else str(checkpoint),
                "convention": convention, "vehicle": vehicle.to_dict(), "episodes": len(episodes),
                "ompl_seed": ompl_seed, "neuralparker": options.neuralparker.to_dict(),
                "hope": {"checkpoint": None if hope_checkpoint is None else str(hope_checkpoint),
                         "action": hope_action, "seed": hope_seed}}
    folder = progress_folder("planners", out, resume)
    kept = EpisodeProgress(folder, settings, resume)
    records: list[dict[str, Any]] = []
    for k, j in tqdm(episodes, desc=f"planners/{'scenes' if files else benchmark}", unit="ep", disable=not progress):
        records += kept.rows((k, j), lambda: episode_rows(
            planners, scenes[k], starts[k][j], vehicle, ompl_seed,
            {"scene": scenes[k].name, "start_id": j, **scene_columns(files, k, j)}))
    table = format_table(records, methods)
    kept.write_results(records, table, {
        **settings, "hybrid_astar": {k: v for k, v in vars(planners.get("hybrid_astar", HybridAStar()).config).items()
                                     if k != "vehicle"}})
    return {"records": records, "table": table, "folder": folder, "starts": starts_summary(files)}


NP_METHODS = ("np_guided_astar", "neuralparker", "staged_astar_np")
"""Methods that play the NeuralParker checkpoint (``--checkpoint``)."""
HOPE_METHODS = ("hope", "staged_astar_hope")
"""Methods that play the adapted-HOPE checkpoint (``--hope-checkpoint``)."""


def learned_holdout(methods: list[str], checkpoint: Path | None, hope_checkpoint: Path | None,
                    benchmark: str) -> int:
    """The ``holdout_every`` the learned methods' checkpoints were all trained with (``--split holdout``:
    `experiments.scene_files.common_holdout`); ConfigError when no learned method runs or they differ."""
    values = {}
    if checkpoint is not None and any(m in NP_METHODS for m in methods):
        values[str(checkpoint)] = Policy.load(checkpoint, benchmark).train.holdout_every
    if hope_checkpoint is not None and any(m in HOPE_METHODS for m in methods):
        payload = load_hope_checkpoint(hope_checkpoint)
        values[str(hope_checkpoint)] = HopeTrainConfig.from_dict(payload["config"]).holdout_every
    return common_holdout(values)


def episode_rows(planners: dict[str, Any], scene, start, vehicle: VehicleSpec, ompl_seed: int,
                 episode: dict[str, Any]) -> list[dict[str, Any]]:
    """One record row per method for the start ``start`` of ``scene`` (``episode``: the columns naming it)."""
    free = int(path_valid(scene, start[None], "footprint", vehicle))
    rows = []
    for method, planner in planners.items():
        plan = planner.plan(scene, start)
        L, rev, dk = plan.metrics() if plan.success else (float("nan"), -1, float("nan"))
        scored = planner.convention
        rows.append({**episode, "method": method, "seed": ompl_seed,
                     "convention": scored, "success": int(plan.success), "reason": plan.reason, "L": L,
                     "reversals": rev, "delta_kappa": dk, "plan_time_ms": 1e3 * plan.plan_time_s,
                     "expanded_nodes": plan.expanded_nodes,
                     "guide_time_ms": 1e3 * getattr(plan, "guide_time_s", float("nan")),
                     "start_footprint_free": free,
                     "scored_valid": int(plan_valid(scene, plan, scoring_rule(scored), vehicle=vehicle)),
                     "exact_footprint_valid": int(plan_valid(scene, plan, "exact", "footprint", vehicle)),
                     "exact_ref_point_valid": int(plan_valid(scene, plan, "exact", "reference_point", vehicle))})
    return rows


def format_table(records: list[dict[str, Any]], methods: list[str]) -> str:
    """Markdown table: per method success (full set), cohort L / Rev. / Δκ, plan time median / p90, nodes."""
    by_method = {m: [r for r in records if r["method"] == m] for m in methods}
    solved = [{(r["scene"], r["start_id"]) for r in rows if r["success"]} for rows in by_method.values()]
    cohort = set.intersection(*solved) if solved else set()
    lines = [f"Common-success cohort: {len(cohort)} episodes.", "",
             "| Method | Succ. | Exact-valid footprint (ref. point) | L (m) | Rev. | Δκ | "
             "plan time median / p90 (ms) | expanded nodes median |", "|---|---|---|---|---|---|---|---|"]
    for method, rows in by_method.items():
        in_cohort = [r for r in rows if (r["scene"], r["start_id"]) in cohort]
        metric = {key: np.mean([r[key] for r in in_cohort]) if in_cohort else float("nan")
                  for key in ("L", "reversals", "delta_kappa")}
        times = np.array([r["plan_time_ms"] for r in rows])
        nodes = np.median([r["expanded_nodes"] for r in rows])
        lines.append(f"| {label(method)} | {np.mean([r['success'] for r in rows]):.3f} | "
                     f"{np.mean([r['exact_footprint_valid'] for r in rows]):.3f} "
                     f"({np.mean([r['exact_ref_point_valid'] for r in rows]):.3f}) | {metric['L']:.2f} | "
                     f"{metric['reversals']:.2f} | {metric['delta_kappa']:.2f} | {np.median(times):.2f} / "
                     f"{np.percentile(times, 90):.2f} | {nodes:.0f} |")
    false_claims = {label(m): sum(r["success"] and not r["scored_valid"] for r in rows)
                    for m, rows in by_method.items()}
    lines += ["", "Successes failing the rule they are scored by: "
              + ", ".join(f"{label} {n}" for label, n in false_claims.items()) + "."]
    # records of runs before the column was recorded have no start_footprint_free: their starts count as free
    blocked = {(r["scene"], r["start_id"]) for r in records if not r.get("start_footprint_free", 1)}
    if blocked:
        lines += ["", f"Starts where the vehicle's footprint is not free (drawn for the default car): {len(blocked)} "
                      f"of {len({(r['scene'], r['start_id']) for r in records})} (records: start_footprint_free = 0)."]
    if {"hybrid_astar", "np_guided_astar"} <= set(methods):
        hybrid = np.median([r["plan_time_ms"] for r in by_method["hybrid_astar"]])
        guided = by_method["np_guided_astar"]
        total = np.median([r["plan_time_ms"] for r in guided])
        search = np.median([r["plan_time_ms"] - r["guide_time_ms"] for r in guided])
        lines += ["", f"NP-Guided A* / Hybrid A* median plan time: {total / hybrid:.2f} with the rollout, "
                      f"{search / hybrid:.2f} search only (rollout median "
                      f"{np.median([r['guide_time_ms'] for r in guided]):.2f} ms)."]
    return "\n".join(lines)


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options; a user's mistake
    exits 2 with one error line)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.planners", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=["factorial", "topology"], default="factorial")
    parser.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT,
                        help=f"NeuralParker checkpoint for the learned methods (default {DEFAULT_CHECKPOINT})")
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(DEFAULT_METHODS),
                        help="planners to run (default all but hope and staged_astar_hope: they need "
                             "--hope-checkpoint)")
    parser.add_argument("--hope-checkpoint", type=Path,
                        help="adapted-HOPE checkpoint of the hope and staged_astar_hope methods "
                             "(hope_policy.train's final.pt)")
    parser.add_argument("--hope-action", choices=HOPE_ACTIONS, default="sampled",
                        help="how the adapted HOPE picks its actions: sampled (HOPE's evaluation protocol: the "
                             "masked anchor draw, or the clipped Gaussian sample; the default) or mean (the mean "
                             "action / most probable anchor)")
    parser.add_argument("--hope-seed", type=non_negative_int, default=0,
                        help="seed of the adapted HOPE's sampled actions (default 0)")
    parser.add_argument("--convention", choices=["reference_point", "footprint"], default="reference_point")
    parser.add_argument("--vehicle", type=vehicle_spec, default=VehicleSpec(),
                        help="vehicle planned for: a preset (sedan, the default; van) or a vehicle JSON file "
                             "(docs/vehicles.md)")
    parser.add_argument("--ompl-seed", type=non_negative_int, default=0, help="OMPL's random seed")
    parser.add_argument("--out", type=Path,
                        help="new or empty run folder (default: a fresh results/planners/<timestamp>)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the interrupted run in --out where it stopped (the same other arguments; a "
                             "new or empty --out starts a fresh run)")
    parser.add_argument("--limit", type=positive_int, help="only the first N frozen episodes (smoke runs)")
    add_scene_arguments(parser)
    add_split_arguments(parser, ("test", "validation", "holdout"))
    args = parser.parse_args(argv)
    if args.scenes and args.split != "test":
        parser.error(f"--split {args.split} plans the benchmark's training scenes; it cannot go with --scenes")
    check_out(parser, args.out, args.resume)
    result = run(args.benchmark, args.methods, args.checkpoint, args.convention, args.out, args.limit, args.ompl_seed,
                 hope_checkpoint=args.hope_checkpoint, hope_action=args.hope_action, hope_seed=args.hope_seed,
                 vehicle=args.vehicle, scenes=args.scenes,
                 n_starts=args.starts, seed=args.seed, resume=args.resume, split=args.split,
                 starts_per_scene=args.starts_per_scene)
    if result["starts"]:
        print(result["starts"])
    print(result["table"])
    print(f"records: {result['folder'] / 'records.csv'}")
    return result


if __name__ == "__main__":
    main()
