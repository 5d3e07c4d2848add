"""Moving objects: pose interpolation, mocap bodies following it, contacts named by the mover."""

import dataclasses
import math

import numpy as np
import pytest
from tracking_helpers import open_scene, plan_from_arcs

from tracking.config import ExecutorConfig, TrackerConfig, WorldConfig
from tracking.errors import TrackingError
from tracking.executor import execute
from tracking.movers import Mover, poses_at
from tracking.world import build_world

SQUARE = np.array([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]])


def crossing_mover(x: float = 8.0) -> Mover:
    """A 0.6 m box walking from (x, −5) to (x, 0) in 1 s (11 frames at 10 Hz), then standing on the path y = 0."""
    return Mover("mover_3", SQUARE, np.array([[x, -5.0 + 0.5 * i, 0.0] for i in range(11)]), 0.1)


def test_poses_are_linear_between_frames_and_held_outside():
    poses = np.array([[0.0, 0.0, 3.0], [1.0, 2.0, -3.0]])  # the heading turns 2π − 6 ≈ 0.283 rad the short way
    out = poses_at(poses, 0.1, np.array([-1.0, 0.0, 0.025, 0.05, 0.1, 5.0]))
    np.testing.assert_allclose(out[:, :2], [[0, 0], [0, 0], [0.25, 0.5], [0.5, 1.0], [1, 2], [1, 2]])
    assert out[3, 2] == pytest.approx(3.0 + 0.5 * (2 * math.pi - 6.0))
    assert Mover("mover_0", SQUARE, poses[:1], 0.1).pose_at(7.0) == pytest.approx([0.0, 0.0, 3.0])
    with pytest.raises(TrackingError, match="outline"):
        Mover("mover_0", SQUARE[:2], poses, 0.1)


def test_mocap_bodies_follow_the_mover_poses():
    mover = crossing_mover()
    world = build_world(open_scene((12.0, 0.0, 0.0)), (0.0, 0.0, 0.0), movers=(mover,))
    geom = world.model.geom("mover_3").id
    assert world.geom_names[geom] == "mover_3"
    world.move_objects(0.55)
    import mujoco

    mujoco.mj_forward(world.model, world.data)
    np.testing.assert_allclose(world.data.geom_xpos[geom, :2], [8.0, -2.25], atol=1e-9)


@pytest.mark.parametrize("solid", [True, False])
def test_a_mover_crossing_the_path_is_a_contact_with_its_name(solid):
    plan = plan_from_arcs([[0.0, 12.0]], start=(0.0, 0.0, 0.0))
    scene = open_scene((12.0, 0.0, 0.0))
    config = dataclasses.replace(TrackerConfig(), world=WorldConfig(solid_obstacles=solid),
                                 executor=ExecutorConfig(stop_on_contact=solid))
    record = execute(scene, plan, config=config, world=build_world(scene, plan.start, config, (crossing_mover(),)))
    assert record.reason == "contact" and record.contacts[0].geom == "mover_3"
    assert record.contacts[0].time_s > 1.0  # the box is on the path from t = 1 s; the bumper gets there later
    assert record.contacts[0].position[0] == pytest.approx(7.7, abs=0.15)  # its near face
    if not solid:  # detection only: the run goes on through the box and parks
        assert record.final_error[0] < 0.3
