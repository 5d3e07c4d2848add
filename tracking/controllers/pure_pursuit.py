"""Pure pursuit on the rear axle (Coulter 1992, "Implementation of the pure pursuit path tracking algorithm")."""

from __future__ import annotations

import math

import numpy as np

from tracking.controllers.base import LateralController, TrackingState
from tracking.reference import Segment


def lookahead_point(segment: Segment, s: float) -> tuple[float, float]:
    """The segment's point at distance ``s``; beyond the end, the end extended along the travel direction."""
    if s <= segment.length:
        return float(np.interp(s, segment.s, segment.xy[:, 0])), float(np.interp(s, segment.s, segment.xy[:, 1]))
    extra = (s - segment.length) * segment.gear
    th = segment.theta[-1]
    return float(segment.xy[-1, 0] + extra * math.cos(th)), float(segment.xy[-1, 1] + extra * math.sin(th))


class PurePursuitController(LateralController):
    """c = 2·y_b / d²: the circle through the rear axle, tangent to the heading, through the look-ahead point at
    body-frame lateral offset y_b and distance d (the same in both gears); look-ahead
    L_d = L_min + k·|v| along the path from the nearest point."""

    name = "pure_pursuit"

    def __init__(self, config):
        self.l_min, self.k = config.pure_pursuit.lookahead_min_m, config.pure_pursuit.lookahead_gain_s

    def steer_curvature(self, state: TrackingState) -> float:
        """Pure pursuit's curvature 2·y / d² to the lookahead point (y its lateral offset in the body frame, d its
        distance), the lookahead growing with speed."""
        pose = state.pose
        gx, gy = lookahead_point(state.segment, state.projection.s + self.l_min + self.k * abs(state.speed_mps))
        dx, dy = gx - pose[0], gy - pose[1]
        th = float(pose[2])
        y_body = -math.sin(th) * dx + math.cos(th) * dy
        return 2.0 * y_body / max(dx * dx + dy * dy, 1e-9)
