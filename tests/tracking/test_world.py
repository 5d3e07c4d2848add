"""tracking.world: the scene world and the vehicle's stability at rest and at 3 m/s in both gears."""

import dataclasses
import math

import mujoco
import numpy as np
import pytest
from tracking_helpers import open_scene, plan_end, plan_from_arcs

from np_sim.benchmarks import load_benchmark
from tracking.config import SpeedProfileConfig, TrackerConfig
from tracking.executor import execute
from tracking.observer import RunObserver
from tracking.world import build_world


def test_scene_geoms_are_named_by_obstacle_and_boundary_edge():
    scene = load_benchmark("factorial", "test")[0]
    world = build_world(scene, scene.target)
    names = set(world.geom_names.values())
    for i in range(len(scene.obstacles)):
        assert f"obstacle_{i}" in names or any(n.startswith(f"obstacle_{i}_") for n in names)
    for e in range(len(scene.boundary)):
        assert any(n.startswith(f"wall_{e}_") for n in names)
    np.testing.assert_allclose(world.pose(), scene.target, atol=1e-9)


def test_vehicle_rests_where_it_is_placed():
    world = build_world(open_scene((0, 0, 0)), (2.0, 3.0, 1.0))
    z0 = world.data.qpos[2]
    mujoco.mj_step(world.model, world.data, nstep=500)  # 2 s, no torque, straight wheels
    np.testing.assert_allclose(world.pose(), [2.0, 3.0, 1.0], atol=2e-3)
    assert abs(world.data.qpos[2] - z0) < 2e-3
    assert world.body_contacts() == []


class _Attitude(RunObserver):
    """Largest speed and roll/pitch tilt seen during a run."""

    def __init__(self):
        self.speed, self.tilt = 0.0, 0.0

    def on_step(self, t, world, state, command, target_speed):
        w, x, y, z = world.data.qpos[3:7]
        up_z = 1.0 - 2.0 * (x * x + y * y)  # z-component of the body's up axis
        self.tilt = max(self.tilt, math.acos(min(1.0, up_z)))
        self.speed = max(self.speed, abs(state.speed_mps))


@pytest.mark.parametrize("length", [25.0, -25.0])
def test_vehicle_is_stable_at_3_mps_forward_and_reverse(length):
    config = dataclasses.replace(TrackerConfig(), profile=SpeedProfileConfig(forward_speed_mps=3.0,
                                                                             reverse_speed_mps=3.0))
    plan = plan_from_arcs([[0.0, length], [0.05, math.copysign(8.0, length)]], start=(-12.0 * np.sign(length), -8, 0))
    att = _Attitude()
    record = execute(open_scene(plan_end(plan), half=40.0), plan, config=config, observer=att)
    assert record.success, record.detail
    assert att.speed == pytest.approx(3.0, abs=0.15)
    assert att.tilt < math.radians(2.0)
