"""Projection of the vehicle onto a reference segment: nearest point, path-frame errors and reference values."""

from __future__ import annotations

import math
from dataclasses import dataclass

from tracking.kernels import nearest_piece
from tracking.reference import Segment


@dataclass(frozen=True)
class Projection:
    """The vehicle's nearest point on a segment and the path-frame errors there."""

    index: int
    """Sample index i of the nearest polyline piece [i, i+1]."""
    s: float
    """Distance along the segment of the nearest point (m)."""
    lateral_m: float
    """Signed lateral error e_y: the reference point's offset left of the reference heading (m)."""
    heading_rad: float
    """Heading error e_θ = θ − θ_ref, wrapped to (−π, π] (rad)."""
    theta_ref: float
    """Reference heading at the nearest point (rad)."""
    steer_curvature_ref: float
    """Steering feed-forward curvature at the nearest point (1/m; `Segment.steer_feedforward`)."""
    speed_ref: float
    """Profile speed magnitude at the nearest point (m/s)."""
    remaining_m: float
    """Path left to the segment end, negative once past the end along the final travel direction (m)."""


def project(segment: Segment, pose, hint: int, back: int = 20, ahead: int = 80) -> Projection:
    """Nearest point of the polyline pieces [hint − back, hint + ahead] of ``segment`` to the pose's position.

    Piece i from p_i to p_{i+1}: t = clip((p − p_i)·(p_{i+1} − p_i) / |p_{i+1} − p_i|², 0, 1); the nearest piece
    minimises |p − p_i − t (p_{i+1} − p_i)| (`tracking.kernels.nearest_piece`). The window keeps the match local
    where a path passes near itself.
    """
    xy = segment.xy
    n = len(xy)
    px, py = float(pose[0]), float(pose[1])
    i, tk = nearest_piece(xy, px, py, max(0, hint - back), min(n - 1, hint + ahead))
    s = segment.s[i] + tk * (segment.s[i + 1] - segment.s[i])
    th_ref = segment.theta[i] + tk * (segment.theta[i + 1] - segment.theta[i])
    c_ref = segment.steer_feedforward[i] + tk * (segment.steer_feedforward[i + 1] - segment.steer_feedforward[i])
    v_ref = segment.speed[i] + tk * (segment.speed[i + 1] - segment.speed[i])
    cx, cy = math.cos(th_ref), math.sin(th_ref)
    gx, gy = px - (xy[i, 0] + tk * (xy[i + 1, 0] - xy[i, 0])), py - (xy[i, 1] + tk * (xy[i + 1, 1] - xy[i, 1]))
    remaining = segment.length - s
    if i == n - 2 and tk >= 1.0:
        remaining -= segment.gear * (gx * cx + gy * cy)
    return Projection(index=i, s=s, lateral_m=cx * gy - cy * gx,
                      heading_rad=math.remainder(float(pose[2]) - th_ref, 2.0 * math.pi), theta_ref=th_ref,
                      steer_curvature_ref=float(c_ref), speed_ref=float(v_ref), remaining_m=remaining)
