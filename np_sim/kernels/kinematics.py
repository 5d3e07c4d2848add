"""Compiled arc kinematics (paper eq:arc) and angle wrapping."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def wrap_angle(a: float) -> float:
    """Wrap an angle to (-π, π]."""
    return a - 2.0 * math.pi * math.ceil((a - math.pi) / (2.0 * math.pi))


@njit(cache=True, error_model="numpy")
def _sinc(x: float) -> float:
    """sin(x)/x, with its Taylor series near 0 (exact to double precision for |x| < 1e-4)."""
    if abs(x) < 1e-4:
        x2 = x * x
        return 1.0 - x2 / 6.0 + x2 * x2 / 120.0
    return math.sin(x) / x


@njit(cache=True, error_model="numpy")
def arc_point(x: float, y: float, th: float, kappa: float, length: float):
    """Pose reached by the arc (κ, l) from (x, y, θ), paper eq:arc; κ = 0 is a straight segment of length l.

    With r = 1/|κ|, α = |lκ|, δ_l = sgn(l), δ_κ = sgn(κ):
    x' = x + δ_l [r(1 − cos α) δ_κ sin θ + r sin α cos θ],
    y' = y + δ_l [−r(1 − cos α) δ_κ cos θ + r sin α sin θ],
    θ' = θ − δ_κ α.
    Evaluated without cancellation or overflow as r sin α = |l|·sinc(α) and
    r(1 − cos α) = 2 sin²(α/2)/|κ| = |l|·(α/2)·sinc²(α/2), which also gives the straight segment at κ = 0.
    """
    abs_l = abs(length)
    alpha = abs(length * kappa)
    d_l = 1.0 if length > 0.0 else (-1.0 if length < 0.0 else 0.0)
    d_k = 1.0 if kappa > 0.0 else (-1.0 if kappa < 0.0 else 0.0)
    along = abs_l * _sinc(alpha)  # r sin α
    half_sinc = _sinc(0.5 * alpha)
    across = abs_l * 0.5 * alpha * half_sinc * half_sinc  # r (1 − cos α)
    s = math.sin(th)
    c = math.cos(th)
    nx = x + d_l * (across * d_k * s + along * c)
    ny = y + d_l * (-across * d_k * c + along * s)
    return nx, ny, wrap_angle(th - d_k * alpha)


@njit(cache=True, error_model="numpy")
def sample_arc_into(x: float, y: float, th: float, kappa: float, length: float, out: np.ndarray) -> None:
    """Fill ``out`` (n, 3) with the poses at arc lengths l·(j+1)/n, j = 0..n−1 (last row = arc end)."""
    n = out.shape[0]
    for j in range(n):
        px, py, pth = arc_point(x, y, th, kappa, length * (j + 1) / n)
        out[j, 0] = px
        out[j, 1] = py
        out[j, 2] = pth


@njit(cache=True, error_model="numpy")
def sample_arcs(x: float, y: float, th: float, arcs: np.ndarray, ds: float):
    """(rows, length): (M, 6) rows x, y, θ, steer curvature, gear, s along the arcs (K, 2) of (κ, l) from (x, y, θ)
    (paper eq:arc) — the start, then each arc at ⌈|l|/ds⌉ (at least one) equal steps, its end included; a row's
    steer curvature is −gear·κ of the arc it ends (the start row takes the first arc's), gear = sgn(l) (0 for a
    zero-length arc), s the distance travelled — and the total length Σ|l| summed in arc order. The arcs part of
    `np_sim.plan.Plan.sample`, without a Python call per row."""
    counts = np.empty(arcs.shape[0], np.int64)
    for i in range(arcs.shape[0]):
        counts[i] = max(1, math.ceil(abs(arcs[i, 1]) / ds))
    rows = np.zeros((1 + counts.sum(), 6))
    rows[0, 0], rows[0, 1], rows[0, 2] = x, y, th
    k, s = 0, 0.0
    for i in range(arcs.shape[0]):
        kappa, length, n = arcs[i, 0], arcs[i, 1], counts[i]
        gear = 1.0 if length > 0.0 else (-1.0 if length < 0.0 else 0.0)
        steer = -gear * kappa
        if rows[k, 4] == 0.0:
            rows[k, 3], rows[k, 4] = steer, gear
        sample_arc_into(x, y, th, kappa, length, rows[k + 1:k + n + 1, :3])
        for j in range(1, n + 1):
            rows[k + j, 3], rows[k + j, 4], rows[k + j, 5] = steer, gear, s + abs(length) * j / n
        k += n
        x, y, th = rows[k, 0], rows[k, 1], rows[k, 2]
        s += abs(length)
    return rows, s
