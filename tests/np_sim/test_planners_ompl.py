"""The OMPL peer (RRT* in a Reeds–Shepp space with our validity checker) returns plans under our validity contract."""

from __future__ import annotations

import math

import numpy as np
import pytest

from np_sim.errors import ConfigError
from np_sim.examples import example_path
from np_sim.kinematics import arc_step, wrap_angle
from np_sim.scene import Scene
from np_sim.validate import scoring_rule, validate_plan

pytest.importorskip("ompl")

from np_sim.planners.ompl_peer import OmplPeer, OmplPeerConfig  # noqa: E402


@pytest.mark.parametrize("convention", ["reference_point", "footprint"])
def test_rrtstar_plan_is_valid_and_reaches_the_target(convention):
    scene = Scene.load(example_path("reverse_bay"))
    peer = OmplPeer(OmplPeerConfig(time_budget_s=0.5, seed=1), convention)
    plan = peer.plan(scene, [10.0, 10.0, 0.0])
    assert plan.success, plan.reason
    assert validate_plan(scene, plan, scoring_rule(convention)).valid
    assert convention == "reference_point" or validate_plan(scene, plan, "exact", convention="footprint").valid
    end = np.asarray(plan.start, float)
    for kappa, length in plan.arcs:
        end = arc_step(end, kappa, length)
    assert math.hypot(*(end[:2] - scene.target[:2])) <= 0.1
    assert abs(wrap_angle(end[2] - scene.target[2])) <= math.radians(10)
    assert plan.expanded_nodes > 1 and plan.plan_time_s >= 0.5


def test_unreachable_target_and_bad_input():
    scene = Scene.load(example_path("enclosed_target"))
    peer = OmplPeer(OmplPeerConfig(time_budget_s=0.2))
    plan = peer.plan(scene, [5.0, 12.0, 0.0])
    assert not plan.success and plan.reason == "budget"
    assert peer.plan(scene, [-5.0, -5.0, 0.0]).reason == "start in collision"
    with pytest.raises(ValueError, match="start must be a finite"):
        peer.plan(scene, [1.0, 2.0])
    with pytest.raises(ConfigError, match="time_budget_s: expected a finite positive"):
        OmplPeerConfig(time_budget_s=0.0)
    with pytest.raises(ConfigError, match="convention must be"):
        OmplPeer(convention="wheels")
