"""Planned-path validators (SPEC §8, paper Table VI): reference-point and full-rectangle footprint validity of a
plan, on the same geometry as `np_sim.collision.path_valid`."""

from __future__ import annotations

from np_sim.collision import path_valid
from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec

DEFAULT_DS_M = 0.1
"""Validation sample spacing (m): at most 0.1 m, at least as dense as the paper's 30 samples per arc for arcs
of 3 m and more, and never coarser than the benchmark convention's 0.1 m spacing."""


def plan_poses(plan: Plan, ds_m: float = DEFAULT_DS_M):
    """(M, 3) poses of ``plan`` (start included) at spacing ≤ ``ds_m`` along it (`Plan.sample`)."""
    return plan.sample(ds_m)[:, :3]


def reference_point_valid(scene: Scene, plan: Plan, ds_m: float = DEFAULT_DS_M) -> bool:
    """Every sampled reference point strictly inside the boundary and outside every obstacle (paper convention)."""
    return path_valid(scene, plan_poses(plan, ds_m), "reference_point")


def footprint_valid(scene: Scene, plan: Plan, ds_m: float = DEFAULT_DS_M, vehicle: VehicleSpec | None = None) -> bool:
    """The full vehicle rectangle at every sample inside the boundary and disjoint from every obstacle."""
    return path_valid(scene, plan_poses(plan, ds_m), "footprint", vehicle)


def validate_plan(scene: Scene, plan: Plan, ds_m: float = DEFAULT_DS_M,
                  vehicle: VehicleSpec | None = None) -> dict[str, bool]:
    """{'reference_point': …, 'footprint': …}: both validators; a failed plan is invalid under both."""
    if not plan.success:
        return {"reference_point": False, "footprint": False}
    return {"reference_point": reference_point_valid(scene, plan, ds_m),
            "footprint": footprint_valid(scene, plan, ds_m, vehicle)}
