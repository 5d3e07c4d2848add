"""Planned-path validators (spec §8, paper Table VI) over the one plan validator, `np_sim.validate`.

* reference point: the paper's rule, the env's own check (30 reference points per arc, the 100 Hermite samples);
* footprint: the full vehicle rectangle at the same samples (the footprint convention as the env scores it);
* exact: the rectangle (or the reference point) swept continuously along every arc and the Hermite cubic, with no
  sampling: what a plan that never touches anything between samples passes.
"""

from __future__ import annotations

from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.validate import validate_plan as _validate
from np_sim.vehicle import VehicleSpec

VALIDATOR_NAMES = ("reference_point", "footprint", "exact_reference_point", "exact_footprint")
"""The keys of ``validate_plan``'s answer."""


def reference_point_valid(scene: Scene, plan: Plan) -> bool:
    """The paper's rule: every checked reference point strictly inside the boundary and outside every obstacle."""
    return _validate(scene, plan, "paper").valid


def footprint_valid(scene: Scene, plan: Plan, vehicle: VehicleSpec | None = None) -> bool:
    """The full vehicle rectangle at every checked pose inside the boundary and disjoint from every obstacle."""
    return _validate(scene, plan, "footprint_sampled", vehicle=vehicle).valid


def exact_valid(scene: Scene, plan: Plan, convention: str = "footprint", vehicle: VehicleSpec | None = None) -> bool:
    """The body of ``convention`` swept continuously along the plan never touches an obstacle or the boundary."""
    return _validate(scene, plan, "exact", convention=convention, vehicle=vehicle).valid


def validate_plan(scene: Scene, plan: Plan, vehicle: VehicleSpec | None = None) -> dict[str, bool]:
    """{name: valid} for every name of ``VALIDATOR_NAMES``; a failed plan is invalid under all of them."""
    if not plan.success:
        return dict.fromkeys(VALIDATOR_NAMES, False)
    return {"reference_point": reference_point_valid(scene, plan),
            "footprint": footprint_valid(scene, plan, vehicle),
            "exact_reference_point": exact_valid(scene, plan, "reference_point"),
            "exact_footprint": exact_valid(scene, plan, "footprint", vehicle)}
