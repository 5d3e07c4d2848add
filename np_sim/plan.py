"""The plan every planner returns (SPEC §7, §10): executed arcs, at most one terminal Hermite segment, timing.

A tracker consumes ``Plan.sample(ds)``: rows (x, y, θ, steer_curvature, gear, s) with the physical steering
curvature of SPEC §2 (positive = left; for an arc ``−sgn(l)·κ``), gear ±1 and the travelled distance s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from np_sim.kernels.kinematics import arc_point
from np_sim.metrics import plan_metrics


@dataclass(frozen=True, eq=False)
class HermiteSegment:
    """The terminal Hermite connection of a plan."""

    points: np.ndarray
    """(N, 2) world-frame samples from the connected pose to the terminal point."""
    forward: bool
    """Drive direction along the segment."""
    length: float
    """Sampled length L_H (m)."""
    delta_kappa: float
    """Δκ_H of eq:hermite-kappa (1/m)."""


@dataclass(frozen=True, eq=False)
class Plan:
    """A planner's answer from ``start``: success flag and reason, executed arcs, optional Hermite segment."""

    start: np.ndarray
    """[x, y, θ] the plan starts from."""
    arcs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    """(T, 2) executed (κ, l) arcs in order (Reeds–Shepp pieces expressed as arcs)."""
    hermite: HermiteSegment | None = None
    """Terminal Hermite segment, or None (direct terminal success or failure)."""
    success: bool = False
    """The plan reaches the target within tolerance."""
    reason: str = ""
    """Why it failed ('' on success): e.g. 'collision', 'timeout', 'no path'."""
    plan_time_s: float = 0.0
    """Wall time spent planning (s)."""
    expanded_nodes: int = 0
    """Search nodes expanded (searches only)."""

    def metrics(self) -> tuple[float, int, float]:
        """(L, reversals, Δκ) of paper eq:metrics."""
        h = self.hermite
        if h is None:
            return plan_metrics(self.arcs)
        return plan_metrics(self.arcs, h.length, h.delta_kappa, h.forward)

    def sample(self, ds: float = 0.1) -> np.ndarray:
        """(M, 6) rows x, y, θ, steer_curvature, gear, s at spacing ≤ ``ds`` (m) along the plan, start included."""
        if not ds > 0:
            raise ValueError(f"Plan.sample: ds must be > 0, got {ds}")
        rows = [[*np.asarray(self.start, float), 0.0, 0.0, 0.0]]
        x, y, th = (float(v) for v in self.start)
        s = 0.0
        for kappa, length in np.asarray(self.arcs, float).reshape(-1, 2):
            n = max(1, math.ceil(abs(length) / ds))
            gear = float(np.sign(length))
            steer = -gear * kappa
            if rows[-1][4] == 0.0:
                rows[-1][3:5] = [steer, gear]
            for j in range(1, n + 1):
                px, py, pth = arc_point(x, y, th, kappa, length * j / n)
                rows.append([px, py, pth, steer, gear, s + abs(length) * j / n])
            x, y, th = rows[-1][:3]
            s += abs(length)
        if self.hermite is not None:
            rows.extend(self._hermite_rows(ds, s, rows[-1]))
        return np.array(rows)

    def _hermite_rows(self, ds: float, s0: float, last: list[float]) -> list[list[float]]:
        pts = np.asarray(self.hermite.points, float)
        seg = np.hypot(*np.diff(pts, axis=0).T)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        n = max(1, math.ceil(cum[-1] / ds))
        u = np.linspace(0.0, cum[-1], n + 1)
        xs, ys = np.interp(u, cum, pts[:, 0]), np.interp(u, cum, pts[:, 1])
        gear = 1.0 if self.hermite.forward else -1.0
        travel = np.unwrap(np.arctan2(np.gradient(ys), np.gradient(xs)))
        heading = travel if gear > 0 else travel + math.pi
        # signed geometric curvature of the travelled curve (left positive) = dφ/ds; steering = gear × that
        curvature = np.gradient(travel, u, edge_order=1)
        steer = gear * curvature
        if last[4] == 0.0:
            last[3:5] = [steer[0], gear]
        return [[xs[i], ys[i], math.remainder(heading[i], 2 * math.pi), steer[i], gear, s0 + u[i]]
                for i in range(1, n + 1)]
