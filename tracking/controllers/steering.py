"""Steering angle and rate limits on the bicycle steering angle δ = atan(c·L) (spec §2, §3)."""

from __future__ import annotations

import math


class SteeringLimiter:
    """δ_k = δ_{k−1} + clip(clip(atan(c·L), ±δ_max) − δ_{k−1}, ±rate·dt); returns c = tan(δ_k)/L.

    δ_max = `tracking.mjcf.max_steer_rad` (atan((1 + margin)·κ_max·L)); the rate bound is
    `VehicleModelConfig.steer_rate_max_rps`.
    """

    def __init__(self, wheelbase_m: float, max_steer_rad: float, rate_rps: float, dt_s: float):
        self.wheelbase_m, self.max_steer_rad, self.max_step = wheelbase_m, max_steer_rad, rate_rps * dt_s
        self.angle_rad = 0.0

    def reset(self, angle_rad: float) -> None:
        """Set the current steering angle (rad)."""
        self.angle_rad = angle_rad

    def target_angle(self, steer_curvature: float) -> float:
        """atan(c·L) clipped to ±δ_max (rad): where the limiter heads for the command c."""
        return max(-self.max_steer_rad, min(self.max_steer_rad, math.atan(steer_curvature * self.wheelbase_m)))

    def __call__(self, steer_curvature: float) -> float:
        """The limited steering curvature (1/m) for the commanded one."""
        target = self.target_angle(steer_curvature)
        self.angle_rad += max(-self.max_step, min(self.max_step, target - self.angle_rad))
        return math.tan(self.angle_rad) / self.wheelbase_m
