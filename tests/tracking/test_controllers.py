"""tracking.controllers: LQR gains from python-control, limits, the controller registry."""

import math

import numpy as np
import pytest

from np_sim.errors import ConfigError
from tracking.config import LQRConfig, TrackerConfig
from tracking.controllers import SteeringLimiter, make_lateral
from tracking.controllers.lqr import gain_table, lqr_gain
from tracking.errors import TrackingError


@pytest.mark.parametrize("v", [-2.0, -0.3, 0.3, 2.0])
def test_lqr_closed_loop_is_stable_in_both_gears(v):
    tau = 0.3
    K = lqr_gain(v, 4.0, 1.0, 1.0, tau)
    A = np.array([[0, v, 0], [0, 0, v], [0, 0, -1 / tau]])
    B = np.array([[0], [0], [1 / tau]])
    assert np.all(np.linalg.eigvals(A - B @ K[None]).real < 0)


def test_gains_are_scheduled_on_speed_and_gear():
    table = gain_table(LQRConfig())
    assert not np.allclose(table[1][0], table[1][-1])  # speed changes the gains
    np.testing.assert_allclose(table[-1][:, 1], -table[1][:, 1])  # reverse flips the heading gain
    np.testing.assert_allclose(table[-1][:, [0, 2]], table[1][:, [0, 2]])
    with pytest.raises(ConfigError, match="speed_grid_mps"):
        gain_table(LQRConfig(speed_grid_mps=(1.0,)))


def test_steering_limiter_bounds_angle_and_rate():
    lim = SteeringLimiter(2.8, math.atan(0.68 * 2.8), 0.8, 0.02)
    c = lim(10.0)
    assert math.atan(c * 2.8) == pytest.approx(0.8 * 0.02)
    for _ in range(500):
        c = lim(10.0)
    assert c == pytest.approx(0.68)


def test_unknown_controller_is_an_error_naming_the_choices():
    with pytest.raises(TrackingError, match="lqr"):
        make_lateral("mpc", TrackerConfig())
