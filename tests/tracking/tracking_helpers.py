"""Helpers of the tracking tests: hand-built plans and open scenes around them."""

import numpy as np

from np_sim.kinematics import arc_step
from np_sim.plan import Plan
from np_sim.scene import Scene


def plan_from_arcs(arcs, start=(0.0, 0.0, 0.3)) -> Plan:
    """A successful plan of the arcs (κ, l) from ``start``."""
    return Plan(start=np.array(start, float), arcs=np.array(arcs, float).reshape(-1, 2), success=True)


def plan_end(plan: Plan) -> np.ndarray:
    """The pose eq:arc reaches at the end of the plan's arcs."""
    pose = np.asarray(plan.start, float)
    for kappa, length in plan.arcs:
        pose = arc_step(pose, kappa, length)
    return pose


def open_scene(target, obstacles=(), half=25.0) -> Scene:
    """A square lot of side 2·half around the origin with the target pose and obstacles."""
    return Scene.from_dict({"boundary": [[-half, -half], [half, -half], [half, half], [-half, half]],
                            "obstacles": list(obstacles), "target": list(map(float, target))})
