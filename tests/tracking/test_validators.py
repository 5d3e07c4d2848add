"""tracking.validators: reference-point, footprint and exact validity of planned paths (`np_sim.validate`)."""

import numpy as np
from tracking_helpers import open_scene, plan_from_arcs

from np_sim.plan import Plan
from tracking.validators import exact_valid, footprint_valid, reference_point_valid, validate_plan

ALL_VALID = {"reference_point": True, "footprint": True, "exact_reference_point": True, "exact_footprint": True}


def test_a_path_grazing_an_obstacle_passes_the_reference_point_check_only():
    # the obstacle is 0.6 m beside the reference-point path: the point clears it, the 0.971 m half-width body not
    scene = open_scene((10.0, 0.0, 0.0), obstacles=[{"polygon": [[4, 0.6], [6, 0.6], [6, 2], [4, 2]]}])
    plan = plan_from_arcs([[0.0, 10.0]], start=(0.0, 0.0, 0.0))
    assert reference_point_valid(scene, plan)
    assert not footprint_valid(scene, plan)
    assert validate_plan(scene, plan) == {**ALL_VALID, "footprint": False, "exact_footprint": False}


def test_a_clear_path_passes_both_and_a_failed_plan_neither():
    scene = open_scene((10.0, 0.0, 0.0), obstacles=[{"polygon": [[4, 3], [6, 3], [6, 5], [4, 5]]}])
    assert validate_plan(scene, plan_from_arcs([[0.0, 10.0]], start=(0.0, 0.0, 0.0))) == ALL_VALID
    assert validate_plan(scene, Plan(start=np.zeros(3))) == dict.fromkeys(ALL_VALID, False)


def test_a_corner_clipped_between_samples_fails_only_the_exact_footprint():
    # along the arc (κ 0.5, l 3 m) the front-left corner sweeps 1 mm into a thin triangle's apex between the 11th
    # and 12th of its 30 samples (apex placed 1 mm inside the circle that corner traces about (0, −2))
    scene = open_scene((20.0, 20.0, 0.0), obstacles=[{"polygon": [[4.7417, -1.3138], [5.7286, -1.1508],
                                                                  [5.7343, -1.1904]]}])
    plan = plan_from_arcs([[0.5, 3.0]], start=(0.0, 0.0, 0.0))
    assert footprint_valid(scene, plan) and not exact_valid(scene, plan)
    assert validate_plan(scene, plan) == {**ALL_VALID, "exact_footprint": False}
