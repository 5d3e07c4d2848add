"""Stanley steering (Hoffmann et al. 2007, "Autonomous automobile trajectory tracking for off-road driving")."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from tracking.controllers.base import LateralController, TrackingState
from tracking.projection import project
from tracking.reference import Segment


class StanleyController(LateralController):
    """Stanley's law on the leading axle, with curvature feed-forward.

    Forward (the steered front axle leads): δ = atan(L·c_ref) − e_θ − atan(k·e_f / (k_s + |v|)), where e_f is the
    front-axle centre's lateral offset from the front-axle path p + L(cos θ, sin θ) and e_θ = θ − θ_ref.
    Reverse (the rear axle leads): the same law for a virtual vehicle driving forward along the travel direction
    θ + π, whose leading point is the rear axle, lateral error −e_y and curvature −c; the physical command is the
    negated virtual curvature.
    """

    name = "stanley"

    def __init__(self, config):
        self.k, self.k_soft = config.stanley.gain, config.stanley.softening_mps
        self.wheelbase_m = config.vehicle.wheelbase_m
        self._segment: Segment | None = None
        self._front: Segment | None = None
        self._hint = 0

    def _front_path(self, segment: Segment) -> Segment:
        """The path of the front-axle centre along ``segment`` (kept while the same segment is tracked)."""
        if segment is not self._segment:
            L = self.wheelbase_m
            xy = segment.xy + L * np.column_stack([np.cos(segment.theta), np.sin(segment.theta)])
            self._segment, self._front, self._hint = segment, replace(segment, xy=xy), 0
        return self._front

    def steer_curvature(self, state: TrackingState) -> float:
        """Commanded steering curvature tan(δ)/L of Stanley's law (class docstring) on the leading axle."""
        L, pose, segment, projection = self.wheelbase_m, state.pose, state.segment, state.projection
        soft = self.k_soft + abs(state.speed_mps)
        if segment.gear > 0:
            th = float(pose[2])
            front = (pose[0] + L * math.cos(th), pose[1] + L * math.sin(th), th)
            fp = project(self._front_path(segment), front, self._hint)
            self._hint = fp.index
            delta = math.atan(L * fp.steer_curvature_ref) - fp.heading_rad - math.atan(self.k * fp.lateral_m / soft)
            return math.tan(delta) / L
        delta_virtual = (math.atan(-L * projection.steer_curvature_ref) - projection.heading_rad
                         - math.atan(-self.k * projection.lateral_m / soft))
        return -math.tan(delta_virtual) / L
