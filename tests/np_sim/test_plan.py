"""Plan: sampling with gear and physical steering curvature (spec §2), metrics (eq:metrics)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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


CURVATURES = st.floats(-0.68, 0.68).filter(lambda k: k == 0 or abs(k) > 1e-3)
ARC_LENGTHS = st.tuples(st.floats(0.01, 8.0), st.sampled_from([-1.0, 1.0])).map(lambda lg: lg[0] * lg[1])


@settings(max_examples=200, deadline=None)
@given(start=st.tuples(*[st.floats(-50, 50)] * 2, st.floats(-math.pi, math.pi)),
       arcs=st.lists(st.tuples(CURVATURES, ARC_LENGTHS), min_size=1, max_size=5),
       ds=st.sampled_from([0.05, 0.1, 0.3]))
def test_sampled_rows_lie_on_their_arcs_circles_at_the_spacing_asked(start, arcs, ds):
    """Every row of an arc is on that arc's circle of radius 1/|κ| about the centre eq:arc turns around (a line for
    κ = 0), steps are ≤ ds and the arc's ⌈|l|/ds⌉ of them, gear sgn(l), steer −sgn(l)κ (spec §2)."""
    rows = Plan(start=np.array(start), arcs=np.array(arcs), success=True).sample(ds)
    k, (x, y, th) = 0, start
    for kappa, length in arcs:
        n = max(1, math.ceil(abs(length) / ds))
        part = rows[k + 1:k + n + 1]
        gear = np.sign(length)
        if kappa != 0.0:  # eq:arc turns about the point 1/κ right of the heading driving forward, left in reverse
            cx, cy = x + gear * math.sin(th) / kappa, y - gear * math.cos(th) / kappa
            np.testing.assert_allclose(np.hypot(part[:, 0] - cx, part[:, 1] - cy), 1 / abs(kappa),
                                       rtol=1e-9, atol=1e-9)
        else:
            np.testing.assert_allclose((part[:, 0] - x) * math.sin(th) - (part[:, 1] - y) * math.cos(th), 0.0,
                                       atol=1e-9)
        assert np.all(part[:, 4] == gear) and np.all(part[:, 3] == -gear * kappa)
        assert np.all(np.diff(rows[k:k + n + 1, 5]) <= ds + 1e-12)
        k += n
        x, y, th = rows[k, :3]
    assert len(rows) == k + 1 and rows[-1, 5] == pytest.approx(sum(abs(length) for _, length in arcs))
