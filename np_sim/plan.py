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
    """(N, 2) world-frame samples of the cubic of eq:hermite at t_j = j/(N−1), from the connected pose to the
    terminal point (the connector's own samples; ``Plan.sample`` rebuilds the cubic from them)."""
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
        # The stored points are the connector's samples of one cubic (eq:hermite, uniform t); linear interpolation
        # between them would put the whole turn of each sample interval into a curvature spike at its vertices
        # (on a 40 m segment 0.4 m apart: 5x the true curvature), so the curve is rebuilt and differentiated.
        coeffs = hermite_coefficients(self.hermite.points)
        t_fine = np.linspace(0.0, 1.0, 16 * max(len(self.hermite.points) - 1, 1) + 1)
        speed = np.hypot(*_cubic(coeffs, t_fine, 1).T)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t_fine))])
        gear = 1.0 if self.hermite.forward else -1.0
        if not cum[-1] > 0:
            return [[*last[:2], last[2], 0.0, gear, s0]]
        n = max(1, math.ceil(cum[-1] / ds))
        u = np.linspace(0.0, cum[-1], n + 1)
        t = np.interp(u, cum, t_fine)
        xy, d1, d2 = (_cubic(coeffs, t, k) for k in range(3))
        travel = np.arctan2(d1[:, 1], d1[:, 0])
        heading = travel if gear > 0 else travel + math.pi
        # signed geometric curvature of the travelled curve (left positive); steering = gear × that (SPEC §2)
        curvature = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(np.hypot(*d1.T), 1e-12) ** 3
        steer = gear * curvature
        if last[4] == 0.0:
            last[3:5] = [steer[0], gear]
        return [[xy[i, 0], xy[i, 1], math.remainder(heading[i], 2 * math.pi), steer[i], gear, s0 + u[i]]
                for i in range(1, n + 1)]


HERMITE_FIT_TOLERANCE_M = 1e-6
"""Largest distance (m, relative to the segment's extent when that exceeds 1 m) of a Hermite segment's stored
points from the cubic fitted through them; more means they are not samples of eq:hermite."""


def hermite_coefficients(points) -> np.ndarray:
    """(4, 2) monomial coefficients c_k (r(t) = Σ c_k t^k) of the cubic of paper eq:hermite through ``points``
    (N, 2) sampled at t_j = j/(N−1) (degree N−1 when N < 4); ValueError when the points are not such samples."""
    pts = np.asarray(points, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or not np.all(np.isfinite(pts)):
        raise ValueError(f"HermiteSegment.points: expected finite (N >= 2, 2) samples, got shape {pts.shape}")
    t = np.linspace(0.0, 1.0, len(pts))
    degree = min(3, len(pts) - 1)
    basis = t[:, None] ** np.arange(degree + 1)
    fit = np.linalg.lstsq(basis, pts, rcond=None)[0]
    residual = float(np.max(np.abs(basis @ fit - pts)))
    extent = float(np.max(np.ptp(pts, axis=0)))
    if residual > HERMITE_FIT_TOLERANCE_M * max(1.0, extent):
        raise ValueError(f"HermiteSegment.points: not samples of one cubic at uniform parameter (eq:hermite): "
                         f"the fitted cubic misses them by {residual:.3g} m")
    coeffs = np.zeros((4, 2))
    coeffs[:degree + 1] = fit
    return coeffs


def _cubic(coeffs: np.ndarray, t: np.ndarray, derivative: int) -> np.ndarray:
    """(len(t), 2) values of the cubic with monomial ``coeffs`` (or its first/second t-derivative)."""
    powers = np.arange(4)
    factor = np.ones(4)
    for j in range(derivative):
        factor = factor * np.maximum(powers - j, 0)
    exponent = np.maximum(powers - derivative, 0)
    return (t[:, None] ** exponent * factor) @ coeffs
