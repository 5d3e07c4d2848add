"""Closed-loop tracking of planned paths on the benchmark frozen starts (spec §8).

``python -m experiments.track --benchmark factorial --planner hybrid_astar [--convention footprint]
[--vehicle sedan|van|FILE] [--per-scene K] [--limit N] [--controller lqr|stanley|pure_pursuit|all]
[--rrd-episodes N] [--no-render] [--out DIR] [--scenes FILE... [--starts N] [--seed S]]``

Every frozen start of the benchmark's test scenes (1,080 Factorial, 720 Topology-Stress; ``--per-scene K`` keeps
the first K of the 40 starts of every scene, ``--limit`` then the first N episodes in scene order) is planned
once; the plan is checked by the validators (reference point and full footprint at the benchmark's samples, and
the exact swept footprint, `tracking.validators`) and executed on the MuJoCo vehicle by each controller
(`tracking.executor`). The table gives, per controller: planning success, planned-path validity under both
conventions and the exact swept footprint, executed
closed-loop success (no body contact, parked within 0.3 m / 10°) on all episodes and on the footprint-valid
plans, tracking errors (mean over executed runs of the per-run cross-track RMS and max; final pose error of the
executed successes) and the median real-time factor. ``--vehicle`` (`np_sim.vehicle`) is the vehicle planned
for, validated and driven: the planner's footprint and κ_max, the validators' footprint and the MuJoCo vehicle
built from it (`tracking.mjcf`); a start where its footprint is not free (the frozen starts were drawn for the
default car) is executed as 'start_in_collision'. Writes ``records.csv``/``records.json`` (one row per episode and
controller), ``table.md``, ``config.json`` and the first ``--rrd-episodes`` runs as ``.rrd`` files.

``--scenes FILE...`` tracks plans on your own scene files instead (`experiments.scene_files`): each file's explicit
starts, or ``--starts N`` drawn from its start region with ``--seed S`` and free under the planner's convention;
records add the file and the start pose, and config.json how many drawn starts were rejected in collision.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.common import first, run_folder, write_records
from experiments.registry import PlannerOptions, build_planners, check_names
from experiments.scene_files import (add_scene_arguments, describe, episode_scenes, load_scene_files, scene_columns,
                                     starts_summary)
from np_sim.cli import cli_boundary, existing_file, fresh_folder, non_negative_int, positive_int, vehicle_spec
from np_sim.errors import ConfigError
from np_sim.provenance import provenance
from np_sim.vehicle import VehicleSpec
from tracking.config import TrackerConfig
from tracking.controllers import CONTROLLERS
from tracking.executor import execute
from tracking.validators import validate_plan

PLANNERS = ("hybrid_astar", "np_guided_astar", "ompl_rrtstar", "neuralparker", "staged_astar_np")
"""Planners this experiment can run (`experiments.registry`); the learned ones need ``--checkpoint``."""


def track(benchmark: str = "factorial", planner: str = "hybrid_astar", controllers: tuple[str, ...] = ("lqr",),
          convention: str = "footprint", checkpoint: Path | None = None, limit: int | None = None,
          per_scene: int | None = None,
          out: Path | None = None, rrd_episodes: int = 0, render: bool = True,
          progress: bool = True, vehicle: VehicleSpec | None = None, scenes: list[Path] | None = None,
          n_starts: int | None = None, seed: int = 0) -> dict[str, Any]:
    """Plan, validate and execute the frozen starts for ``vehicle`` (default the sedan); returns the records, the
    table and the run folder. With ``scenes`` (files), their starts instead (`experiments.scene_files`: the files'
    own, or ``n_starts`` drawn with ``seed``)."""
    for c in controllers:
        if c not in CONTROLLERS:
            raise ConfigError(f"--controller: expected one of {sorted(CONTROLLERS)} or 'all', got {c!r}")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    tracker = dataclasses.replace(TrackerConfig(), vehicle=vehicle)
    options = PlannerOptions(checkpoint=checkpoint, convention=convention, benchmark=None if scenes else benchmark,
                             vehicle=vehicle)
    source = build_planners(check_names([planner], PLANNERS), options)[planner]
    files = load_scene_files(scenes, n_starts, seed, source.convention, vehicle) if scenes else None
    scenes, starts = episode_scenes(benchmark, files)
    episodes = first([(k, j) for k in range(len(scenes))
                      for j in first(range(len(starts[k])), per_scene, "--per-scene")], limit)
    folder = run_folder("track", out)
    records: list[dict[str, Any]] = []
    for n, (k, j) in enumerate(tqdm(episodes, desc=f"{planner} → MuJoCo", unit="ep", disable=not progress)):
        scene = scenes[k]
        plan = source.plan(scene, starts[k][j])
        valid = validate_plan(scene, plan, vehicle)
        L, rev, _ = plan.metrics() if plan.success else (math.nan, -1, math.nan)
        base = {"scene": scene.name, "start_id": j, **scene_columns(files, k, j), "planner": planner,
                "convention": convention,
                "plan_success": int(plan.success), "plan_reason": plan.reason, "plan_time_ms": 1e3 * plan.plan_time_s,
                "L": L, "plan_reversals": rev, "ref_point_valid": int(valid["reference_point"]),
                "footprint_valid": int(valid["footprint"]),
                "exact_ref_point_valid": int(valid["exact_reference_point"]),
                "exact_footprint_valid": int(valid["exact_footprint"])}
        for controller in controllers:
            rrd = folder / "rrd" / f"{scene.name}_{j:02d}_{controller}.rrd" if n < rrd_episodes else None
            record = execute(scene, plan, controller=controller, render=render and rrd is not None, rerun_path=rrd,
                             config=tracker)
            records.append({**base, **record.to_row()})
    table = format_table(records, controllers)
    write_records(folder, records)
    (folder / "table.md").write_text(table + "\n")
    (folder / "config.json").write_text(json.dumps(
        {"benchmark": None if files else benchmark, "scenes": describe(files), "starts_seed": seed,
         "planner": planner, "convention": convention, "vehicle": vehicle.to_dict(),
         "checkpoint": str(checkpoint),
         "controllers": list(controllers), "episodes": len(episodes), "per_scene": per_scene, "limit": limit,
         "rrd_episodes": rrd_episodes,
         "render": render, **provenance()}, indent=2))
    return {"records": records, "table": table, "folder": folder, "starts": starts_summary(files)}


def _mean(values) -> float:
    v = np.asarray(list(values), float)
    return float(np.nanmean(v)) if len(v) and not np.all(np.isnan(v)) else math.nan


def format_table(records: list[dict[str, Any]], controllers) -> str:
    """Markdown table, one row per controller (see the module docstring for the columns)."""
    header = ("| Controller | Plan succ. | Ref.-point valid | Footprint valid | Exact footprint valid | "
              "Executed succ. | Executed succ. (footprint-valid plans) | Cross-track RMS (m) | Cross-track max (m) | "
              "Final error (m / °) | Real-time factor |\n|---|---|---|---|---|---|---|---|---|---|---|")
    rows = [header]
    for c in controllers:
        rs = [r for r in records if r["controller"] == c]
        ran = [r for r in rs if r["plan_success"] and r["reason"] not in ("plan_failed", "empty_plan")]
        fv = [r for r in rs if r["footprint_valid"]]
        ok = [r for r in rs if r["success"]]
        rows.append(
            f"| {c} | {_mean(r['plan_success'] for r in rs):.3f} | {_mean(r['ref_point_valid'] for r in rs):.3f} | "
            f"{_mean(r['footprint_valid'] for r in rs):.3f} | {_mean(r['exact_footprint_valid'] for r in rs):.3f} | "
            f"{_mean(r['success'] for r in rs):.3f} | "
            f"{_mean(r['success'] for r in fv):.3f} ({len(fv)}) | "
            f"{_mean(r['cross_track_rms_m'] for r in ran):.3f} | {_mean(r['cross_track_max_m'] for r in ran):.3f} | "
            f"{_mean(r['final_position_error_m'] for r in ok):.3f} / "
            f"{_mean(r['final_heading_error_deg'] for r in ok):.1f} | "
            f"{np.nanmedian([r['realtime_factor'] for r in ran]) if ran else math.nan:.0f}× |")
    n = len({(r['scene'], r['start_id']) for r in records})
    return "\n".join(rows) + f"\n\n{n} episodes; errors over executed runs, final error over executed successes."


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options; a user's mistake
    exits 2 with one error line)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.track", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=["factorial", "topology"], default="factorial")
    parser.add_argument("--planner", choices=PLANNERS, default="hybrid_astar")
    parser.add_argument("--convention", choices=["reference_point", "footprint"], default="footprint",
                        help="collision convention the planner plans under (default: footprint)")
    parser.add_argument("--checkpoint", type=existing_file, default=None,
                        help="policy checkpoint of the learned planners (neuralparker, np_guided_astar, "
                             "staged_astar_np)")
    parser.add_argument("--vehicle", type=vehicle_spec, default=VehicleSpec(),
                        help="vehicle planned for and driven: a preset (sedan, the default; van) or a vehicle JSON "
                             "file (docs/vehicles.md)")
    parser.add_argument("--controller", choices=[*CONTROLLERS, "all"], default="lqr",
                        help="lqr, stanley, pure_pursuit or all")
    parser.add_argument("--per-scene", type=positive_int, default=None,
                        help="only the first K frozen starts of each scene")
    parser.add_argument("--limit", type=positive_int, default=None, help="only the first N episodes in scene order")
    parser.add_argument("--rrd-episodes", type=non_negative_int, default=2,
                        help="write .rrd files for the first N episodes")
    parser.add_argument("--no-render", action="store_true", help="no off-screen frames in the .rrd files")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/track/<timestamp>)")
    add_scene_arguments(parser)
    args = parser.parse_args(argv)
    controllers = tuple(CONTROLLERS) if args.controller == "all" else (args.controller,)
    result = track(args.benchmark, args.planner, controllers, args.convention, args.checkpoint, args.limit,
                   args.per_scene, args.out, args.rrd_episodes, not args.no_render, vehicle=args.vehicle,
                   scenes=args.scenes, n_starts=args.starts, seed=args.seed)
    if result["starts"]:
        print(result["starts"])
    print(result["table"])
    print(f"results in {result['folder']}")
    return result


if __name__ == "__main__":
    main()
