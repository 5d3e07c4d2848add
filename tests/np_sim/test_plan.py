"""Plan: sampling with gear and physical steering curvature (spec §2), metrics (eq:metrics)."""

import math

import numpy as np
import pytest

from np_sim.hermite import connect
from np_sim.kinematics import arc_step
from np_sim.metrics import plan_metrics
from np_sim.plan import HermiteSegment, Plan
from np_sim.scene import Scene


def test_arc_samples_follow_eq_arc_with_gear_and_steering_sign():
    arcs = np.array([[0.5, 3.0], [0.5, -2.0], [0.0, 1.0]])
    plan = Plan(start=np.array([1.0, 2.0, 0.3]), arcs=arcs, success=True)
    rows = plan.sample(0.1)
    pose = plan.start
    for kappa, length in arcs:
        pose = arc_step(pose, kappa, length)
    np.testing.assert_allclose(rows[-1, :3], pose, atol=1e-12)
    # forward κ > 0 turns right (steer < 0); reverse κ > 0 is steer > 0 (c = −sgn(l)κ)
    gears = rows[1:, 4]
    steer = rows[1:, 3]
    assert set(np.unique(gears)) == {-1.0, 1.0}
    assert np.all(steer[(gears > 0) & (rows[1:, 5] <= 3.0)] == -0.5)
    assert np.all(steer[gears < 0] == 0.5)
    assert rows[-1, 5] == pytest.approx(6.0)
    assert np.all(np.diff(rows[:, 5]) <= 0.1 + 1e-12) and np.all(np.diff(rows[:, 5]) > 0)
    assert plan.metrics() == plan_metrics(arcs)


def test_hermite_samples_end_at_the_target_with_the_right_steering_sign():
    scene = Scene.from_dict({"boundary": [[-20, -25], [20, -25], [20, 25], [-20, 25]], "obstacles": [],
                             "target": [0.0, 0.0, math.pi / 2]})
    for start, forward in (([3.0, -8.0, math.pi / 2 + 0.2], True), ([3.0, 8.0, math.pi / 2 + 0.2], False)):
        c = connect(scene, start, 0.0)
        assert c.forward is forward
        seg = HermiteSegment(points=c.points, forward=c.forward, length=c.length, delta_kappa=c.delta_kappa)
        plan = Plan(start=np.array(start), hermite=seg, success=True)
        rows = plan.sample(0.05)
        np.testing.assert_allclose(rows[-1, :2], c.points[-1], atol=1e-9)
        assert abs(math.remainder(rows[-1, 2] - c.terminal_pose[2], 2 * math.pi)) < 0.05
        assert np.all(rows[1:, 4] == (1.0 if forward else -1.0))
        # the integral of steer_curvature over signed length equals the heading change (spec §2)
        signed = np.diff(rows[:, 5]) * rows[1:, 4]
        dtheta = np.sum(rows[1:, 3] * signed)
        assert dtheta == pytest.approx(math.remainder(rows[-1, 2] - rows[0, 2], 2 * math.pi), abs=0.05)
        assert plan.metrics()[0] == pytest.approx(c.length)


def test_bad_spacing_is_an_error():
    with pytest.raises(ValueError, match="ds must be > 0"):
        Plan(start=np.zeros(3)).sample(0.0)


def _dense_signed_curvature(g0, g1, d0, d1, n=200_001):
    """Independent oracle: eq:hermite sampled very densely, curvature from finite differences."""
    from np_sim.hermite import hermite_curve

    pts = hermite_curve(g0, g1, d0, d1, n)
    t = np.linspace(0.0, 1.0, n)
    dx, dy = np.gradient(pts[:, 0], t), np.gradient(pts[:, 1], t)
    ddx, ddy = np.gradient(dx, t), np.gradient(dy, t)
    return pts, (dx * ddy - dy * ddx) / np.hypot(dx, dy) ** 3


@pytest.mark.parametrize("forward", [True, False])
def test_long_hermite_samples_carry_the_curves_own_curvature(forward):
    # a 40 m connection: its 100 stored samples are 0.4 m apart, so interpolating between them linearly would
    # put each interval's turn into a spike at its vertices; the samples must follow the cubic itself
    from np_sim.hermite import hermite_curve

    g0, g1, d0, d1 = [2.0, -38.0], [0.0, 0.0], [-8.0, 45.0], [0.0, 40.0]
    seg = HermiteSegment(points=hermite_curve(g0, g1, d0, d1, 100), forward=forward, length=40.0, delta_kappa=0.0)
    rows = Plan(start=np.array([*g0, 0.0]), hermite=seg, success=True).sample(0.05)[1:]
    dense, kappa = _dense_signed_curvature(g0, g1, d0, d1)
    nearest = np.argmin(np.hypot(dense[None, :, 0] - rows[::20, None, 0], dense[None, :, 1] - rows[::20, None, 1]),
                        axis=1)
    gear = 1.0 if forward else -1.0
    np.testing.assert_allclose(rows[::20, 3], gear * kappa[nearest], atol=2e-4)
    np.testing.assert_allclose(rows[-1, :2], g1, atol=1e-9)
    assert np.max(np.abs(np.diff(rows[:, 3]))) < 1e-3  # smooth: no spikes at the stored samples
    assert np.all(np.diff(rows[:, 5]) <= 0.05 + 1e-9)


def test_hermite_points_that_are_not_one_cubic_are_an_error():
    pts = np.column_stack([np.linspace(0, 10, 20), np.abs(np.linspace(-5, 5, 20))])  # a V, not a cubic
    seg = HermiteSegment(points=pts, forward=True, length=14.0, delta_kappa=0.0)
    with pytest.raises(ValueError, match="not samples of one cubic"):
        Plan(start=np.array([0.0, 5.0, 0.0]), hermite=seg, success=True).sample(0.1)
