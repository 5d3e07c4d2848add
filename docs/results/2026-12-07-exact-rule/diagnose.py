"""Where and how deep the successes that fail the exact reference-point rule cross an obstacle.

For each run folder's frozen-start evaluation (``eval_factorial`` with the checkpoint's own connector,
``eval_factorial_ensemble`` with the ensemble swapped in), every success whose record says
``exact_ref_point_valid = 0`` is planned again, the exact validator (`np_sim.validate.validate_plan`) names the
segment and obstacle of its first violation, and shapely measures the deepest point of the reference point's
path inside that obstacle, sampled every 0.5 mm (`Plan.sample`). Prints one summary line per evaluation.

    python docs/results/2026-12-07-exact-rule/diagnose.py > docs/results/2026-12-07-exact-rule/diagnose.txt
"""
import collections
import csv
import dataclasses
from pathlib import Path

import numpy as np
from shapely.geometry import Point, Polygon

from np_policy.config import PAPER
from np_policy.planner import NeuralParkerPlanner
from np_sim.benchmarks.frozen import split_episodes
from np_sim.scene import PolygonObstacle
from np_sim.validate import validate_plan
from np_sim.vehicle import VehicleSpec

RUNS = Path("checkpoints/runs")
EVALUATIONS = (("factorial_np_fixed_seed0_lot", "eval_factorial", None),
               ("factorial_np_fixed_seed0_lot", "eval_factorial_ensemble", "ensemble"),
               ("factorial_np_seed0_lot", "eval_factorial", None))


def depth_inside(scene, plan, obstacle: int) -> float:
    """Deepest point (m) of the plan's reference-point path inside ``scene.obstacles[obstacle]``."""
    ob = scene.obstacles[obstacle]
    shape = Polygon(ob.vertices) if isinstance(ob, PolygonObstacle) else Point(ob.center).buffer(ob.radius, 256)
    points = [Point(p) for p in plan.sample(0.0005)[:, :2]]
    return max((shape.exterior.distance(p) for p in points if shape.contains(p)), default=0.0)


def diagnose(run: str, evaluation: str, connector: str | None, scenes, starts) -> str:
    """One summary line for the exact-invalid successes of one evaluation."""
    records = list(csv.DictReader(open(RUNS / run / evaluation / "records.csv")))
    successes = [r for r in records if r["success"] == "1"]
    failing = [r for r in successes if r["exact_ref_point_valid"] == "0"]
    config = PAPER if connector is None else dataclasses.replace(PAPER, connector=connector)
    planner = NeuralParkerPlanner.from_checkpoint(RUNS / run / "best.pt", config, benchmark="factorial")
    index = {s.name: k for k, s in enumerate(scenes)}
    where, depths = collections.Counter(), []
    for r in failing:
        k = index[r["scene"]]
        plan = planner.plan(scenes[k], starts[k, int(r["start_id"])])
        violation = validate_plan(scenes[k], plan, "exact", convention="reference_point").violation
        if violation is None:
            where["valid when planned again"] += 1
            continue
        segment = "Hermite" if violation.segment == len(plan.arcs) else "arc"
        where[f"{segment}, {violation.what}"] += 1
        if violation.obstacle is not None:
            depths.append(depth_inside(scenes[k], plan, violation.obstacle))
    d = np.array(depths) * 1000.0
    depth = (f"depth inside the obstacle median {np.median(d):.1f} mm, 90th percentile {np.percentile(d, 90):.1f} mm, "
             f"max {d.max():.1f} mm" if len(d) else "no obstacle depths")
    return (f"{run}/{evaluation}: {len(failing)} of {len(successes)} successes fail the exact rule; first violation: "
            f"{dict(where)}; {depth}")


def main() -> None:
    scenes, starts = split_episodes("factorial", "test", 0, VehicleSpec(), 0)
    for run, evaluation, connector in EVALUATIONS:
        print(diagnose(run, evaluation, connector, scenes, starts), flush=True)


if __name__ == "__main__":
    main()
