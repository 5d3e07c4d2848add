"""One scene of your own, every planner: plan, execute in MuJoCo, draw and record.

``python -m experiments.scene_run SCENE.json [--start X Y THETA] [--planners NAME...] [--checkpoint PATH]
[--footprint-checkpoint PATH] [--hope-checkpoint PATH] [--convention footprint|reference_point]
[--vehicle sedan|van|FILE] [--controller lqr|stanley|pure_pursuit] [--seed S] [--no-render] [--out DIR]``

The scene file is the project's JSON format (`np_sim.scene`, schema ``np_sim/data/scene.schema.json``). The start
is ``--start``, else the file's first explicit start, else one drawn from its start region and heading range with
``--seed`` (`np_sim.scene_starts`); it must be free under the strictest convention of the planners run. Every
planner of the registry (`experiments.registry`) plans from it, or those named by ``--planners``; without
``--planners`` a learned planner whose checkpoint is missing is skipped and listed as such. A scene with more
obstacles than a learned planner's slots is planned by the site's rule (`np_sim.nearest`). Each plan is checked by
the validators (`tracking.validators`) and driven on the MuJoCo vehicle (`tracking.executor.execute`). Writes, into
a fresh ``results/scene_run/<timestamp>/``: ``plans.png`` (the scene and every plan), ``records.csv``/``.json``
(one row per planner: plan, validity, executed outcome), ``table.md``, ``config.json`` and ``rrd/<planner>.rrd``
(a Rerun recording of each execution: scene, plan, driven trajectory, footprint, scalars and, unless
``--no-render``, off-screen frames).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from experiments.common import run_folder, write_records
from experiments.registry import REGISTRY, PlannerOptions, build_planners, check_names, label
from experiments.scene_files import scene_file, strictest
from np_sim.cli import cli_boundary, fresh_folder, non_negative_int, vehicle_spec
from np_sim.collision import path_valid
from np_sim.errors import CapacityError, ConfigError, SceneError, StartInCollisionError
from np_sim.plan import Plan
from np_sim.plotting import plot_scene, target_marker
from np_sim.provenance import provenance
from np_sim.scene import Scene
from np_sim.scene_starts import draw_starts
from np_sim.vehicle import VehicleSpec
from tracking.config import TrackerConfig
from tracking.controllers import CONTROLLERS
from tracking.executor import execute
from tracking.validators import validate_plan

DEFAULT_CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")
"""Policy of neuralparker, np_guided_astar and staged_astar_np."""
DEFAULT_FOOTPRINT_CHECKPOINT = Path("checkpoints/site_np_footprint.pt")
"""Policy of neuralparker_footprint (trained at the delivery site under the footprint convention)."""
PLAN_COLOURS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray",
                "gold", "navy")
"""Plan colours of ``plans.png``, none the start's green or the target's red."""


def _checked_start(start) -> np.ndarray:
    """``start`` as a (3,) pose; ConfigError unless it is three finite numbers."""
    pose = np.asarray(start, float)
    if pose.shape != (3,) or not np.all(np.isfinite(pose)):
        raise ConfigError(f"--start: expected three finite numbers X Y THETA, got {np.ravel(pose).tolist()}")
    return pose


def resolve_start(scene: Scene, start, seed: int, convention: str, vehicle: VehicleSpec,
                  source: str) -> tuple[np.ndarray, str]:
    """(start pose, where it came from): ``start`` when given, else the scene's first explicit start, else one
    drawn from its start region with ``seed``; SceneError when it is in collision under ``convention``."""
    if start is not None:
        pose, how = _checked_start(start), "--start"
    elif scene.starts is not None and len(scene.starts):
        pose, how = np.array(scene.starts[0]), "file"
    else:
        return draw_starts(scene, 1, seed, convention, vehicle, source=source).poses[0], "drawn"
    if not path_valid(scene, pose[None], convention, vehicle):
        where = "--start" if how == "--start" else "starts[0]"
        raise SceneError(f"{source}: {where}: the start ({', '.join(f'{v:g}' for v in pose)}) is in collision "
                         f"under the {convention} convention")
    return pose, how


def available_planners(names: list[str] | None, options: PlannerOptions) -> tuple[dict, dict[str, str]]:
    """(planners by name, skipped name -> why): ``names`` are all built (a missing checkpoint is an error);
    without names every registry planner, a learned one whose checkpoint is missing skipped with the reason."""
    if names is not None:
        return build_planners(check_names(names), options), {}
    planners, skipped = {}, {}
    for name in REGISTRY:
        try:
            planners.update(build_planners([name], options))
        except FileNotFoundError as error:
            skipped[name] = str(error)
    return planners, skipped


def _plan_row(scene: Scene, name: str, planner, start: np.ndarray,
              vehicle: VehicleSpec) -> tuple[Plan, dict[str, Any]]:
    """The plan of planner ``name`` and its record columns (a scene beyond the planner's limits is a refused
    plan)."""
    try:
        plan = planner.plan(scene, start)
    except (CapacityError, StartInCollisionError) as error:
        plan = Plan(start=np.asarray(start, float), reason=f"refused: {error}")
    valid = validate_plan(scene, plan, vehicle)
    L, rev, dk = plan.metrics() if plan.success else (math.nan, -1, math.nan)
    return plan, {"planner": name, "convention": planner.convention, "plan_success": int(plan.success),
                  "plan_reason": plan.reason, "plan_time_ms": 1e3 * plan.plan_time_s, "L": L, "plan_reversals": rev,
                  "delta_kappa": dk, **{f"{k}_valid": int(v) for k, v in valid.items()}}


def draw_plans(scene: Scene, start: np.ndarray, plans: dict[str, Plan], png: Path, vehicle: VehicleSpec) -> None:
    """``png``: the scene (`np_sim.plotting.plot_scene`), the start and every successful plan's path."""
    lo, hi = scene.boundary.min(axis=0), scene.boundary.max(axis=0)
    width = 10.0
    figure = Figure(figsize=(width + 3.0, max(4.0, width * (hi[1] - lo[1]) / (hi[0] - lo[0]))), layout="constrained")
    ax = figure.subplots()
    plot_scene(ax, scene, vehicle=vehicle)
    for n, (name, plan) in enumerate(plans.items()):
        colour = PLAN_COLOURS[n % len(PLAN_COLOURS)]
        if plan.success:
            rows = plan.sample(0.05)
            ax.plot(rows[:, 0], rows[:, 1], color=colour, linewidth=1.5, label=label(name))
        else:
            ax.plot([], [], color=colour, linestyle=":", label=f"{label(name)}: {plan.reason[:40]}")
    bar, stem = target_marker(start, vehicle)
    ax.plot(bar[:, 0], bar[:, 1], color="tab:green", linewidth=2.0, label="start")
    ax.plot(stem[:, 0], stem[:, 1], color="tab:green", linewidth=2.0)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
    figure.savefig(png, dpi=110)


def format_table(records: list[dict[str, Any]], skipped: dict[str, str]) -> str:
    """Markdown: one row per planner (plan, exact footprint validity, executed outcome), then the skipped ones."""
    lines = ["| Planner | Plan | L (m) | Rev. | Plan time (ms) | Exact footprint valid | Executed | Final error "
             "(m / °) |", "|---|---|---|---|---|---|---|---|"]
    for r in records:
        plan = "ok" if r["plan_success"] else r["plan_reason"][:60]
        executed = "parked" if r["success"] else r["reason"]
        lines.append(f"| {label(r['planner'])} | {plan} | {r['L']:.2f} | {r['plan_reversals']} | "
                     f"{r['plan_time_ms']:.1f} | {r['exact_footprint_valid']} | {executed} | "
                     f"{r['final_position_error_m']:.3f} / {r['final_heading_error_deg']:.1f} |")
    if skipped:
        lines += ["", *(f"Not run: {label(name)} ({why})." for name, why in skipped.items())]
    return "\n".join(lines)


def run_scene(path: Path, start=None, planners: list[str] | None = None,
              checkpoint: Path | None = DEFAULT_CHECKPOINT,
              footprint_checkpoint: Path | None = DEFAULT_FOOTPRINT_CHECKPOINT, hope_checkpoint: Path | None = None,
              convention: str = "footprint", vehicle: VehicleSpec | None = None, controller: str = "lqr",
              seed: int = 0, render: bool = True, out: Path | None = None) -> dict[str, Any]:
    """Plan ``path``'s scene from one start with every planner, execute each plan, write the run folder (module
    docstring); returns the records, the table, the start and the folder."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    start = None if start is None else _checked_start(start)
    scene = Scene.load(path, vehicle=vehicle)
    options = PlannerOptions(checkpoint=checkpoint, footprint_checkpoint=footprint_checkpoint,
                             hope_checkpoint=hope_checkpoint, convention=convention, vehicle=vehicle)
    built, skipped = available_planners(planners, options)
    pose, how = resolve_start(scene, start, seed, strictest(p.convention for p in built.values()), vehicle, str(path))
    folder = run_folder("scene_run", out)
    tracker = dataclasses.replace(TrackerConfig(), vehicle=vehicle)
    base = {"scene": scene.name, "scene_file": str(path), "start_source": how, "start_x": float(pose[0]),
            "start_y": float(pose[1]), "start_theta": float(pose[2])}
    records, plans = [], {}
    for name, planner in built.items():
        plans[name], row = _plan_row(scene, name, planner, pose, vehicle)
        record = execute(scene, plans[name], controller=controller, render=render,
                         rerun_path=folder / "rrd" / f"{name}.rrd", config=tracker)
        records.append({**base, **row, **record.to_row()})
    draw_plans(scene, pose, plans, folder / "plans.png", vehicle)
    table = format_table(records, skipped)
    write_records(folder, records)
    (folder / "table.md").write_text(table + "\n")
    (folder / "config.json").write_text(json.dumps(
        {"scene_file": str(path), "start": pose.tolist(), "start_source": how, "seed": seed,
         "planners": list(built), "skipped": skipped, "checkpoint": str(checkpoint),
         "footprint_checkpoint": str(footprint_checkpoint), "hope_checkpoint": str(hope_checkpoint),
         "convention": convention, "vehicle": vehicle.to_dict(), "controller": controller, "render": render,
         **provenance()}, indent=2))
    return {"records": records, "table": table, "start": pose, "folder": folder}


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; a user's mistake exits 2 with one error line)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.scene_run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", type=scene_file,
                        help="scene JSON file, or the name of a shipped example scene (own_lot, reverse_bay, ...)")
    parser.add_argument("--start", type=float, nargs=3, metavar=("X", "Y", "THETA"),
                        help="start pose: reference point (m) and heading (rad)")
    parser.add_argument("--planners", nargs="+", choices=list(REGISTRY),
                        help="planners to run (default every registry planner whose checkpoint exists)")
    parser.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT,
                        help=f"policy of neuralparker, np_guided_astar, staged_astar_np (default {DEFAULT_CHECKPOINT})")
    parser.add_argument("--footprint-checkpoint", type=Path, default=DEFAULT_FOOTPRINT_CHECKPOINT,
                        help=f"policy of neuralparker_footprint (default {DEFAULT_FOOTPRINT_CHECKPOINT})")
    parser.add_argument("--hope-checkpoint", type=Path, help="adapted-HOPE checkpoint (hope_policy.train's final.pt)")
    parser.add_argument("--convention", choices=["reference_point", "footprint"], default="footprint",
                        help="collision convention of the searches (default footprint)")
    parser.add_argument("--vehicle", type=vehicle_spec, default=VehicleSpec(),
                        help="vehicle planned for and driven: a preset (sedan, the default; van) or a vehicle JSON "
                             "file")
    parser.add_argument("--controller", choices=list(CONTROLLERS), default="lqr")
    parser.add_argument("--seed", type=non_negative_int, default=0,
                        help="seed of the start drawn from the start region (no --start, no starts in the file)")
    parser.add_argument("--no-render", action="store_true", help="no off-screen frames in the .rrd files")
    parser.add_argument("--out", type=fresh_folder, help="new or empty run folder (default: results/scene_run/<time>)")
    args = parser.parse_args(argv)
    result = run_scene(args.scene, args.start, args.planners, args.checkpoint, args.footprint_checkpoint,
                       args.hope_checkpoint, args.convention, args.vehicle, args.controller, args.seed,
                       not args.no_render, args.out)
    print(f"start ({', '.join(f'{v:.3f}' for v in result['start'])})")
    print(result["table"])
    print(f"results in {result['folder']}")
    return result


if __name__ == "__main__":
    main()
