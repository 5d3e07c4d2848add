"""tracking.validators: reference-point and footprint validity of planned paths (same geometry as path_valid)."""

import numpy as np
from tracking_helpers import open_scene, plan_from_arcs

from np_sim.plan import Plan
from tracking.validators import footprint_valid, reference_point_valid, validate_plan


def test_a_path_grazing_an_obstacle_passes_the_reference_point_check_only():
    # the obstacle is 0.6 m beside the reference-point path: the point clears it, the 0.971 m half-width body not
    scene = open_scene((10.0, 0.0, 0.0), obstacles=[{"polygon": [[4, 0.6], [6, 0.6], [6, 2], [4, 2]]}])
    plan = plan_from_arcs([[0.0, 10.0]], start=(0.0, 0.0, 0.0))
    assert reference_point_valid(scene, plan)
    assert not footprint_valid(scene, plan)
    assert validate_plan(scene, plan) == {"reference_point": True, "footprint": False}


def test_a_clear_path_passes_both_and_a_failed_plan_neither():
    scene = open_scene((10.0, 0.0, 0.0), obstacles=[{"polygon": [[4, 3], [6, 3], [6, 5], [4, 5]]}])
    assert validate_plan(scene, plan_from_arcs([[0.0, 10.0]], start=(0.0, 0.0, 0.0))) == {
        "reference_point": True, "footprint": True}
    assert validate_plan(scene, Plan(start=np.zeros(3))) == {"reference_point": False, "footprint": False}
