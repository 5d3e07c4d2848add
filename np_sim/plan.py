"""The plan every planner returns (spec §7, §10): executed arcs, at most one terminal Hermite segment, timing.

A tracker consumes ``Plan.sample(ds)``: rows (x, y, θ, steer_curvature, gear, s) with the physical steering
curvature of spec §2 (positive = left; for an arc ``−sgn(l)·κ``), gear ±1 and the travelled distance s.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from np_sim.kernels.kinematics import sample_arcs
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


PLAN_STAGES = ("mean", "guarded", "search", "sampled", "rescue")
"""Stages of a staged-effort planner, cheapest first (``Plan.stage``; `np_policy.planner`): the mean rollout
accepted, the guarded mean rollout accepted (`np_policy.guarded`), the grown-body Hybrid A* plan accepted
(``NeuralParkerConfig.search_margin_m``), the best of the sampled round, the best after the rescue rounds."""


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
    stage: str = ""
    """Which stage of a staged-effort planner gave the plan (one of ``PLAN_STAGES``); '' for planners of one
    stage."""

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
        x, y, th = (float(v) for v in self.start)
        arcs = np.ascontiguousarray(np.asarray(self.arcs, float).reshape(-1, 2))
        out, length = sample_arcs(x, y, th, arcs, float(ds))
        if self.hermite is not None:
            hermite = self._hermite_rows(ds, length, out[-1, :3])
            if out[-1, 4] == 0.0:
                out[-1, 3:5] = hermite[0, 3:5]
            out = np.vstack([out, hermite[1:]])
        return out

    def _hermite_rows(self, ds: float, s0: float, last: np.ndarray) -> np.ndarray:
        """Rows of the Hermite segment from its start (row 0) at spacing ≤ ``ds``, s from ``s0``."""
        # The stored points are the connector's samples of one cubic (eq:hermite, uniform t); linear interpolation
        # between them would put the whole turn of each sample interval into a curvature spike at its vertices
        # (on a 40 m segment 0.4 m apart: 5x the true curvature), so the curve is rebuilt and differentiated.
        c = hermite_coefficients(self.hermite.points)
        gear = 1.0 if self.hermite.forward else -1.0
        t_fine = np.linspace(0.0, 1.0, 4 * max(len(self.hermite.points) - 1, 1) + 1)
        speed = np.hypot(*_cubic_derivatives(c, t_fine)[1].T)  # |dr/dt|
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t_fine))])
        if not cum[-1] > 0:
            return np.array([[*last, 0.0, gear, s0]] * 2)
        n = max(1, math.ceil(cum[-1] / ds))
        u = np.linspace(0.0, cum[-1], n + 1)
        xy, d1, d2 = _cubic_derivatives(c, np.interp(u, cum, t_fine))
        travel = np.arctan2(d1[:, 1], d1[:, 0])
        heading = np.remainder(travel + (0.0 if gear > 0 else math.pi) + math.pi, 2 * math.pi) - math.pi
        # signed geometric curvature of the travelled curve (left positive); steering = gear × that (spec §2)
        curvature = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(np.hypot(*d1.T), 1e-12) ** 3
        return np.column_stack([xy, heading, gear * curvature, np.full(n + 1, gear), s0 + u])


HERMITE_FIT_TOLERANCE_M = 1e-6
"""Largest distance (m, relative to the segment's extent when that exceeds 1 m) of a Hermite segment's stored
points from the cubic fitted through them; more means they are not samples of eq:hermite."""


def hermite_coefficients(points) -> np.ndarray:
    """(4, 2) monomial coefficients c_k (r(t) = Σ c_k t^k) of the cubic of paper eq:hermite through ``points``
    (N, 2) sampled at t_j = j/(N−1) (degree N−1 when N < 4); ValueError when the points are not such samples."""
    pts = np.asarray(points, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or not np.all(np.isfinite(pts)):
        raise ValueError(f"HermiteSegment.points: expected finite (N >= 2, 2) samples, got shape {pts.shape}")
    basis, pseudo_inverse = _monomial_fit(len(pts))
    fit = pseudo_inverse @ pts
    residual = float(np.max(np.abs(basis @ fit - pts)))
    extent = float(np.max(np.ptp(pts, axis=0)))
    if residual > HERMITE_FIT_TOLERANCE_M * max(1.0, extent):
        raise ValueError(f"HermiteSegment.points: not samples of one cubic at uniform parameter (eq:hermite): "
                         f"the fitted cubic misses them by {residual:.3g} m")
    coeffs = np.zeros((4, 2))
    coeffs[:len(fit)] = fit
    return coeffs


@functools.lru_cache(maxsize=8)
def _monomial_fit(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Monomial basis (n, d+1) at t_j = j/(n−1), d = min(3, n−1), and its least-squares pseudo-inverse."""
    basis = np.linspace(0.0, 1.0, n)[:, None] ** np.arange(min(3, n - 1) + 1)
    return basis, np.linalg.pinv(basis)


@njit(cache=True, error_model="numpy")
def _cubic_derivatives(c: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(len(t), 2) values, first and second t-derivatives of the cubic with monomial coefficients ``c`` (4, 2) (paper
    eq:hermite), compiled: each element is the same sequence of products and sums as the array expressions
    c0 + t(c1 + t(c2 + t c3)), c1 + t(2 c2 + 3t c3) and 2 c2 + 6t c3, so the values are theirs bit for bit, without
    a temporary array per operation."""
    value = np.empty((t.shape[0], 2))
    first = np.empty((t.shape[0], 2))
    second = np.empty((t.shape[0], 2))
    for i in range(t.shape[0]):
        ti = t[i]
        for j in range(2):
            value[i, j] = c[0, j] + ti * (c[1, j] + ti * (c[2, j] + ti * c[3, j]))
            first[i, j] = c[1, j] + ti * (2.0 * c[2, j] + 3.0 * ti * c[3, j])
            second[i, j] = 2.0 * c[2, j] + 6.0 * ti * c[3, j]
    return value, first, second
