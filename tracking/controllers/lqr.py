"""LQR lateral control on the kinematic path-error model, gains from python-control scheduled on speed and gear."""

from __future__ import annotations

from functools import lru_cache

import control
import numpy as np

from np_sim.errors import ConfigError
from tracking.config import LQRConfig
from tracking.controllers.base import LateralController, TrackingState


def lqr_gain(speed_mps: float, q_lateral: float, q_heading: float, r_curvature: float,
             steer_time_constant_s: float) -> np.ndarray:
    """K (1 × 3) minimising ∫ (xᵀQx + R u²) dt for the kinematic path-error model of the rear-axle point.

    State x = (e_y, e_θ, c̃): lateral error, heading error and steering-curvature deviation c̃ = c − c_ref;
    input u = commanded curvature deviation. Linearised about the reference with signed speed v:
    ė_y = v·e_θ, ė_θ = v·c̃, dc̃/dt = (u − c̃)/τ (first-order steering lag), i.e.
    A = [[0, v, 0], [0, 0, v], [0, 0, −1/τ]], B = [0, 0, 1/τ]ᵀ, Q = diag(q_y, q_θ, 0), R = r (``control.lqr``).
    The law is u = −K x. Reverse gear is the same model with v < 0.
    """
    tau = steer_time_constant_s
    A = np.array([[0.0, speed_mps, 0.0], [0.0, 0.0, speed_mps], [0.0, 0.0, -1.0 / tau]])
    B = np.array([[0.0], [0.0], [1.0 / tau]])
    K, _, _ = control.lqr(A, B, np.diag([q_lateral, q_heading, 0.0]), np.array([[r_curvature]]))
    return np.asarray(K, dtype=float).reshape(3)


@lru_cache(maxsize=16)
def gain_table(config: LQRConfig) -> dict[int, np.ndarray]:
    """{gear: (len(grid), 3) gains} on the speed grid of ``config`` (computed once per config)."""
    grid = np.asarray(config.speed_grid_mps, dtype=float)
    if len(grid) < 2 or np.any(grid <= 0) or np.any(np.diff(grid) <= 0):
        raise ConfigError(f"LQRConfig.speed_grid_mps: expected at least two increasing positive speeds, got "
                          f"{config.speed_grid_mps}")
    return {g: np.array([lqr_gain(g * v, config.q_lateral, config.q_heading, config.r_curvature,
                                  config.steer_time_constant_s) for v in grid]) for g in (1, -1)}


class LQRController(LateralController):
    """c = c_ref − K(v, gear)·(e_y, e_θ, c_now − c_ref): LQR feedback plus curvature feed-forward (spec §8).

    Gains are computed once per gear on the speed grid of `LQRConfig` and interpolated linearly in |v|
    (clamped to the grid), with the gear's sign: the schedule is on the commanded gear, so it stays defined at
    standstill.
    """

    name = "lqr"

    def __init__(self, config):
        self.grid = np.asarray(config.lqr.speed_grid_mps, dtype=float)
        self.gains = gain_table(config.lqr)

    def gain(self, speed_mps: float, gear: int) -> tuple[float, float, float]:
        """The scheduled gain K at |v| for the gear (+1 / −1), linear in |v| between grid speeds."""
        table, grid = self.gains[gear], self.grid
        v = min(max(abs(speed_mps), grid[0]), grid[-1])
        j = min(int(np.searchsorted(grid, v, side="right")) - 1, len(grid) - 2)
        w = (v - grid[j]) / (grid[j + 1] - grid[j])
        k = table[j] + w * (table[j + 1] - table[j])
        return float(k[0]), float(k[1]), float(k[2])

    def steer_curvature(self, state: TrackingState) -> float:
        """c_ref − K (e_y, e_θ, c − c_ref): the LQR law of ``lqr_gain`` with the gain scheduled on speed and
        gear."""
        p = state.projection
        k = self.gain(state.speed_mps, state.segment.gear)
        c_ref = p.steer_curvature_ref
        return c_ref - (k[0] * p.lateral_m + k[1] * p.heading_rad + k[2] * (state.steer_curvature - c_ref))
