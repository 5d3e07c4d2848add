"""LQR lateral control on the kinematic path-error model, gains from python-control scheduled on speed and gear."""

from __future__ import annotations

import control
import numpy as np

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


class LQRController(LateralController):
    """c = c_ref − K(v, gear)·(e_y, e_θ, c_now − c_ref): LQR feedback plus curvature feed-forward (SPEC §8).

    Gains are computed once per gear on the speed grid of `LQRConfig` and interpolated linearly in |v|
    (clamped to the grid), with the gear's sign: the schedule is on the commanded gear, so it stays defined at
    standstill.
    """

    name = "lqr"

    def __init__(self, config):
        cfg = config.lqr
        grid = np.asarray(cfg.speed_grid_mps, dtype=float)
        if len(grid) < 1 or np.any(grid <= 0) or np.any(np.diff(grid) <= 0):
            raise ValueError(f"LQRConfig.speed_grid_mps: expected increasing positive speeds, got {cfg.speed_grid_mps}")
        self.grid = grid
        self.gains = {g: np.array([lqr_gain(g * v, cfg.q_lateral, cfg.q_heading, cfg.r_curvature,
                                             cfg.steer_time_constant_s) for v in grid]) for g in (1, -1)}

    def gain(self, speed_mps: float, gear: int) -> np.ndarray:
        """The scheduled gain K at |v| for the gear (+1 / −1)."""
        table = self.gains[gear]
        v = abs(speed_mps)
        return np.array([np.interp(v, self.grid, table[:, j]) for j in range(table.shape[1])])

    def steer_curvature(self, state: TrackingState) -> float:
        p = state.projection
        k = self.gain(state.speed_mps, state.segment.gear)
        c_ref = p.steer_curvature_ref
        return c_ref - (k[0] * p.lateral_m + k[1] * p.heading_rad + k[2] * (state.steer_curvature - c_ref))
