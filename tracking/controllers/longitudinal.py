"""Longitudinal speed control: PI on the speed error with acceleration feed-forward."""

from __future__ import annotations

from tracking.config import LongitudinalConfig


class SpeedController:
    """Drive force F = m_eff·(a_ff + k_p·(v* − v) + k_i·∫(v* − v) dt) along the heading, split over the two rear
    wheels as torque F·r/2 each (signed: positive drives forward, negative reverses or brakes). m_eff is the
    inertia the rear-axle speed feels at the current steering (`tracking.world.World.effective_mass`).

    The integral is clamped to ±``integral_limit_mps2`` (anti-windup)."""

    def __init__(self, config: LongitudinalConfig, wheel_radius_m: float, dt_s: float):
        self.config, self.wheel_radius_m, self.dt_s = config, wheel_radius_m, dt_s
        self.integral = 0.0

    def wheel_torque(self, target_mps: float, accel_ff_mps2: float, speed_mps: float, mass_kg: float) -> float:
        """Torque per rear wheel (N·m) for the signed target speed, feed-forward acceleration, signed speed and
        effective mass."""
        cfg = self.config
        error = target_mps - speed_mps
        limit = cfg.integral_limit_mps2
        self.integral = min(limit, max(-limit, self.integral + cfg.ki_per_s2 * error * self.dt_s))
        accel = accel_ff_mps2 + cfg.kp_per_s * error + self.integral
        return 0.5 * mass_kg * accel * self.wheel_radius_m
