"""Detection-only obstacles (`WorldConfig.solid_obstacles=False`): contacts are recorded, the vehicle is not pushed."""

import dataclasses

import pytest
from tracking_helpers import open_scene, plan_from_arcs

from tracking.config import ExecutorConfig, TrackerConfig, WorldConfig
from tracking.executor import execute
from tracking.world import build_world

WALL = {"polygon": [[8.0, -3.0], [9.0, -3.0], [9.0, 3.0], [8.0, 3.0]]}
DETECT = dataclasses.replace(TrackerConfig(), world=WorldConfig(solid_obstacles=False),
                             executor=ExecutorConfig(stop_on_contact=False))


def test_the_vehicle_drives_through_a_detection_only_obstacle_and_the_contact_is_recorded():
    plan = plan_from_arcs([[0.0, 12.0]], start=(0.0, 0.0, 0.0))
    record = execute(open_scene((12.0, 0.0, 0.0), obstacles=[WALL]), plan, config=DETECT)
    assert record.reason == "contact" and [c.geom for c in record.contacts] == ["obstacle_0"]
    assert record.contacts[0].position[0] == pytest.approx(8.0, abs=0.1)  # the bumper meets the near face
    assert record.final_error[0] < 0.3 and record.final_pose[0] == pytest.approx(12.0, abs=0.3)
    solid = execute(open_scene((12.0, 0.0, 0.0), obstacles=[WALL]), plan,
                    config=dataclasses.replace(TrackerConfig(), executor=ExecutorConfig(stop_on_contact=False)))
    assert solid.final_pose[0] < 8.0 - 3.5  # the solid wall stops the bumper at x = 8


def test_detection_only_walls_report_the_boundary_edge_and_nothing_collides_with_them():
    plan = plan_from_arcs([[0.0, -30.0]], start=(0.0, 0.0, 1.5707963267948966))  # reverse towards y = −25
    record = execute(open_scene((10.0, 0.0, 0.0)), plan, config=DETECT)
    assert record.contacts and record.contacts[0].geom.startswith("wall_0_")
    world = build_world(open_scene((0.0, 0.0, 0.0), obstacles=[WALL]), (0.0, 0.0, 0.0), DETECT)
    assert all(world.model.geom_contype[g] == 0 and world.model.geom_conaffinity[g] == 0 for g in world.geom_names)
    assert world.body_contacts() == []
