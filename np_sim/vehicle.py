"""The vehicle: the single source of footprint and steering geometry for every module (spec §3)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from np_sim.errors import ConfigError


@dataclass(frozen=True)
class VehicleSpec:
    """Rectangular footprint adopted from HOPE, reference point at the rear-axle centre.

    Vehicle frame: x forward along the heading, y to the left, origin at the reference point.
    """

    wheelbase_m: float = 2.8
    """Distance between rear and front axle (m)."""
    front_overhang_m: float = 0.96
    """Front axle to front bumper (m)."""
    rear_overhang_m: float = 0.929
    """Rear axle to rear bumper (m)."""
    width_m: float = 1.942
    """Body width (m)."""
    kappa_max: float = 0.68
    """Largest path curvature the vehicle may drive (1/m); also the action bound |κ|."""

    def __post_init__(self) -> None:
        for name in ("wheelbase_m", "front_overhang_m", "rear_overhang_m", "width_m", "kappa_max"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"VehicleSpec.{name}: expected a finite positive number, got {value!r}")

    @property
    def length_m(self) -> float:
        """Bumper-to-bumper length (m)."""
        return self.rear_overhang_m + self.wheelbase_m + self.front_overhang_m

    @property
    def front_m(self) -> float:
        """Reference point to front bumper (m), the rectangle's +x extent."""
        return self.wheelbase_m + self.front_overhang_m

    @property
    def max_steer_rad(self) -> float:
        """Front-wheel steering angle needed for κ_max on the kinematic bicycle: atan(κ_max · wheelbase)."""
        return math.atan(self.kappa_max * self.wheelbase_m)

    def inflated(self, margin_m: float) -> "VehicleSpec":
        """The same vehicle with ``margin_m`` of clearance added on every side of the footprint (a planner's safety
        margin); kinematics (wheelbase, κ_max) unchanged."""
        if not (math.isfinite(margin_m) and margin_m >= 0):
            raise ConfigError(f"VehicleSpec.inflated: margin must be a finite number >= 0 m, got {margin_m!r}")
        return dataclasses.replace(self, front_overhang_m=self.front_overhang_m + margin_m,
                                   rear_overhang_m=self.rear_overhang_m + margin_m,
                                   width_m=self.width_m + 2.0 * margin_m)

    def footprint_local(self) -> np.ndarray:
        """(4, 2) rectangle corners in the vehicle frame, counter-clockwise from rear-right."""
        half_w = 0.5 * self.width_m
        return np.array(
            [
                [-self.rear_overhang_m, -half_w],
                [self.front_m, -half_w],
                [self.front_m, half_w],
                [-self.rear_overhang_m, half_w],
            ]
        )

    def footprint(self, pose) -> np.ndarray:
        """(4, 2) rectangle corners in the world frame for a reference-point pose (x, y, θ)."""
        from np_sim.frames import place

        return place(self.footprint_local(), np.asarray(pose, float)[:3])
