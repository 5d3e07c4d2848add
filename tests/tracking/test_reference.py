"""tracking.reference: gear segments at cusps, speed profile bounds, steering feed-forward."""

import math

import numpy as np
import pytest

from tracking.config import SpeedProfileConfig
from tracking.reference import reference_segments, split_segments, window_average

from tracking_helpers import plan_from_arcs

CFG = SpeedProfileConfig()


def test_segments_split_at_cusps_with_the_physical_steering_sign(cusp_plan):
    segs = reference_segments(cusp_plan, 0.05, CFG, 0.5, 2.8)
    assert [s.gear for s in segs] == [1, -1]
    assert segs[0].length == pytest.approx(9.0) and segs[1].length == pytest.approx(7.0)
    np.testing.assert_allclose(segs[0].xy[-1], segs[1].xy[0])  # the cusp point ends one and starts the next
    # forward κ = 0.2 steers right (c = −0.2); reverse κ = −0.4 gives c = −sgn(l)·κ = −0.4
    assert segs[0].steer_curvature[1] == pytest.approx(-0.2)
    assert segs[1].steer_curvature[1] == pytest.approx(-0.4)


def test_zero_length_arcs_and_motionless_plans_give_no_segments():
    assert split_segments(plan_from_arcs([[0.3, 0.0]]).sample(0.1)) == []
    assert len(split_segments(plan_from_arcs([[0.3, 0.0], [0.0, 2.0]]).sample(0.1))) == 1


def test_speed_profile_rests_at_the_ends_and_respects_its_bounds():
    plan = plan_from_arcs([[0.0, 8.0], [0.68, 4.0], [-0.68, 4.0]])
    seg, = reference_segments(plan, 0.05, CFG, 0.5, 2.8)
    v, s = seg.speed, seg.s
    assert v[0] == 0.0 and v[-1] == 0.0
    assert np.all(v <= CFG.forward_speed_mps + 1e-12)
    assert np.all(v ** 2 * np.abs(seg.steer_curvature) <= CFG.lateral_accel_mps2 + 1e-9)
    assert np.all(np.abs(np.diff(v ** 2)) <= 2 * CFG.accel_mps2 * np.diff(s) + 1e-9)
    # the steering reversal at s = 12 (δ from +62° to −62°) is driven slowly enough for a 0.5 rad/s ramp over W
    at = np.argmin(np.abs(s - 12.0))
    assert v[at] <= 0.5 * CFG.steer_window_m / (2 * math.atan(0.68 * 2.8)) + 1e-9


def test_window_average_is_exact_for_piecewise_constant_values():
    s = np.linspace(0.0, 4.0, 81)
    values = np.where(s <= 2.0, 1.0, -1.0)  # value of the piece ending at each sample
    avg = window_average(s, values, 1.0)
    assert avg[0] == pytest.approx(1.0) and avg[-1] == pytest.approx(-1.0)
    assert avg[40] == pytest.approx(0.0)  # centred on the step
    assert avg[50] == pytest.approx(-1.0)  # half a window past it
