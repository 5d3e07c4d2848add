"""The MJCF vehicle built from the van preset has the van's dimensions (compiled by MuJoCo, numbers of van.json)."""

import mujoco
import numpy as np
import pytest

from np_sim.vehicle import load_vehicle
from tracking.config import VehicleModelConfig
from tracking.mjcf import main as mjcf_main


def _compiled(path):
    return mujoco.MjModel.from_xml_path(str(path))


def test_the_van_mjcf_has_the_vans_body_wheelbase_and_track(tmp_path):
    out = mjcf_main(["--vehicle", "van", "-o", str(tmp_path / "van.xml")])
    m = _compiled(out)
    chassis = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "chassis")
    half_length, half_width, _ = m.geom_size[chassis]
    # van.json: 4.75 m long (0.875 m behind the rear axle, 2.975 + 0.9 m ahead of it), 1.85 m wide
    assert (2 * half_length, 2 * half_width) == pytest.approx((4.75, 1.85))
    assert m.geom_pos[chassis][0] == pytest.approx((3.875 - 0.875) / 2)
    # wheels: rear on the reference point's axle, front 2.975 m ahead, each side width / 2 − inset from the axis
    half_track = 1.85 / 2 - VehicleModelConfig().wheel_inset_m
    body = {name: m.body_pos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)][:2]
            for name in ("steer_fl", "steer_fr", "wheel_rl", "wheel_rr")}
    np.testing.assert_allclose(body["steer_fl"], [2.975, half_track])
    np.testing.assert_allclose(body["steer_fr"], [2.975, -half_track])
    np.testing.assert_allclose(body["wheel_rl"], [0.0, half_track])
    np.testing.assert_allclose(body["wheel_rr"], [0.0, -half_track])
    # the steering reaches (1 + margin)·κ_max = 1.1 · 0.24 1/m on the inner wheel: atan2(L·c, 1 − c·half_track)
    c = 1.1 * 0.24
    steer = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "steer_fl")
    assert m.jnt_range[steer][1] == pytest.approx(np.arctan2(2.975 * c, 1 - c * half_track))
    assert load_vehicle("van").wheelbase_m == 2.975


def test_the_default_mjcf_is_still_the_sedan(tmp_path):
    m = _compiled(mjcf_main(["-o", str(tmp_path / "car.xml")]))
    chassis = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "chassis")
    assert 2 * m.geom_size[chassis][:2] == pytest.approx([4.689, 1.942])
