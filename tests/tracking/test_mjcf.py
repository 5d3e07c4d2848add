"""tracking.mjcf: the vehicle MJCF comes from VehicleSpec; Ackermann geometry."""

import math

import mujoco
import numpy as np
import pytest

from np_sim.vehicle import VehicleSpec
from tracking.config import VehicleModelConfig
from tracking.errors import TrackingError
from tracking.mjcf import ackermann_angles, half_track_m, max_steer_rad, steer_joint_max_rad, vehicle_xml


def _model(spec=None, model=None):
    world = '<mujoco><include file="vehicle.xml"/></mujoco>'
    return mujoco.MjModel.from_xml_string(world, assets={"vehicle.xml": vehicle_xml(spec, model).encode()})


@pytest.mark.parametrize("spec", [VehicleSpec(), VehicleSpec(wheelbase_m=1.6, front_overhang_m=0.5,
                                                             rear_overhang_m=0.4, width_m=1.2, kappa_max=0.9)])
def test_chassis_box_is_the_footprint_and_steering_range_follows_the_spec(spec):
    m = _model(spec)
    g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "chassis")
    half_len, half_w, _ = m.geom_size[g]
    assert 2 * half_len == pytest.approx(spec.length_m)
    assert 2 * half_w == pytest.approx(spec.width_m)
    # box x-range in the vehicle frame = [−rear overhang, wheelbase + front overhang] (origin = rear-axle centre)
    assert m.geom_pos[g][0] - half_len == pytest.approx(-spec.rear_overhang_m)
    assert m.geom_pos[g][0] + half_len == pytest.approx(spec.front_m)
    j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "steer_fl")
    expected = steer_joint_max_rad(spec, VehicleModelConfig())
    np.testing.assert_allclose(m.jnt_range[j], [-expected, expected])
    # the inner wheel at κ_max needs more than the bicycle angle atan(κ_max·L)
    assert expected > spec.max_steer_rad
    front = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "steer_fl")
    assert m.body_pos[front][0] == pytest.approx(spec.wheelbase_m)


def test_ackermann_wheels_share_the_turn_centre_of_the_rear_axle():
    L, t = 2.8, 0.77
    for c in (-0.68, -0.2, 0.0, 0.3, 0.68):
        left, right = ackermann_angles(c, L, t)
        if c == 0:
            assert left == right == 0.0
            continue
        # a wheel at (L, y) with angle δ has its axle line through (0, 1/c) when tan δ = L / (1/c − y)
        assert math.tan(left) == pytest.approx(L / (1 / c - t))
        assert math.tan(right) == pytest.approx(L / (1 / c + t))
        lo, hi = sorted([left, right])
        assert lo <= math.atan(c * L) <= hi


def test_bad_model_parameters_are_named():
    with pytest.raises(TrackingError, match="wheel_inset_m"):
        half_track_m(VehicleSpec(), VehicleModelConfig(wheel_inset_m=1.0))
    with pytest.raises(TrackingError, match="ground_clearance_m"):
        vehicle_xml(model=VehicleModelConfig(ground_clearance_m=0.9))


def test_steering_margin_zero_is_exactly_the_spec_angle():
    spec = VehicleSpec()
    assert max_steer_rad(spec, VehicleModelConfig(steer_margin=0.0)) == pytest.approx(spec.max_steer_rad)
    assert max_steer_rad(spec, VehicleModelConfig()) > spec.max_steer_rad
    with pytest.raises(TrackingError, match="steer_margin"):
        max_steer_rad(spec, VehicleModelConfig(steer_margin=-0.1))
