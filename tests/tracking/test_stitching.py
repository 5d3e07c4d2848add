"""tracking.stitching: replans of a moving vehicle start where it can still stop, and the followed plan is driven
up to there."""

import math

import numpy as np
import pytest

from np_sim.kinematics import arc_step
from np_sim.plan import Plan
from tracking.stitching import StitchedPlan, stitch_distance


def test_stitch_distance_is_braking_distance_plus_one_period_plus_margin():
    # 1.5 m/s at 1 m/s²: 1.125 m to stop, 0.15 m in one 0.1 s period, 0.2 m margin
    assert stitch_distance(1.5, 1.0, 0.1, 0.2) == pytest.approx(1.475)
    assert stitch_distance(-2.0, 0.5, 0.1, 0.0) == pytest.approx(4.0 + 0.2)
    assert stitch_distance(0.0, 1.0, 0.1, 0.3) == pytest.approx(0.3)


def _prefix() -> Plan:
    return Plan(start=np.array([1.0, 2.0, 0.3]), arcs=np.array([[0.2, 4.0], [-0.1, 3.0]]), success=True)


def test_stitched_samples_drive_the_prefix_stretch_then_the_suffix():
    prefix = _prefix()
    s_from, s_to = 1.0, 5.5
    at_from = arc_step(prefix.start, 0.2, 1.0)
    at_to = arc_step(arc_step(prefix.start, 0.2, 4.0), -0.1, 1.5)
    suffix = Plan(start=at_to, arcs=np.array([[0.15, -2.5], [0.0, 1.0]]), success=True, plan_time_s=0.01)
    plan = StitchedPlan.join(prefix, s_from, s_to, suffix)
    rows = plan.sample(0.05)
    np.testing.assert_allclose(plan.start, at_from, atol=1e-3)
    np.testing.assert_allclose(rows[0, :3], at_from, atol=1e-3)
    stitch = np.flatnonzero(np.isclose(rows[:, 5], s_to - s_from))
    assert len(stitch) == 1
    np.testing.assert_allclose(rows[stitch[0], :3], at_to, atol=1e-3)
    end = arc_step(arc_step(at_to, 0.15, -2.5), 0.0, 1.0)
    np.testing.assert_allclose(rows[-1, :3], end, atol=1e-9)
    assert rows[-1, 5] == pytest.approx(4.5 + 3.5)
    assert np.all(np.diff(rows[:, 5]) > 0) and np.all(np.diff(rows[:, 5]) <= 0.05 + 1e-9)
    assert np.all(np.hypot(*np.diff(rows[:, :2], axis=0).T) <= 0.05 + 1e-6)  # no jump at the stitch
    gears = rows[1:, 4]
    assert np.all(gears[: stitch[0]] == 1.0) and gears[stitch[0]] == -1.0  # a cusp at the stitch
    assert plan.success and plan.plan_time_s == 0.01
    L, reversals, dk = plan.metrics()
    assert L == pytest.approx(8.0) and reversals == 2 and math.isnan(dk)


def test_restitching_past_the_first_stitch_unwraps_instead_of_nesting():
    prefix = _prefix()
    at_to = arc_step(prefix.start, 0.2, 3.0)
    first = StitchedPlan.join(prefix, 0.5, 3.0, Plan(start=at_to, arcs=np.array([[0.1, 6.0]]), success=True))
    at_second = arc_step(at_to, 0.1, 4.0)
    suffix = Plan(start=at_second, arcs=np.array([[0.0, 2.0]]), success=True)
    second = StitchedPlan.join(first, 3.5, 6.5, suffix)  # 3.5 m along `first` is 1 m into its suffix
    assert not isinstance(second.prefix, StitchedPlan) and second.prefix_s == pytest.approx((1.0, 4.0))
    rows = second.sample(0.05)
    np.testing.assert_allclose(rows[0, :3], arc_step(at_to, 0.1, 1.0), atol=1e-3)
    np.testing.assert_allclose(rows[-1, :3], arc_step(at_second, 0.0, 2.0), atol=1e-9)
    inside = StitchedPlan.join(first, 1.0, 2.0, suffix)  # still inside the first prefix: kept as it is
    assert inside.prefix is first


def test_a_stretch_running_backwards_is_an_error():
    with pytest.raises(ValueError, match="s_from <= s_to"):
        StitchedPlan.join(_prefix(), 3.0, 2.0, Plan(start=np.zeros(3), success=True))
