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
def arc_point(x: float, y: float, th: float, kappa: float, length: float):
    """Pose reached by the arc (κ, l) from (x, y, θ), paper eq:arc; κ = 0 is a straight segment of length l.

    With r = 1/|κ|, α = |lκ|, δ_l = sgn(l), δ_κ = sgn(κ):
    x' = x + δ_l [r(1 − cos α) δ_κ sin θ + r sin α cos θ],
    y' = y + δ_l [−r(1 − cos α) δ_κ cos θ + r sin α sin θ],
    θ' = θ − δ_κ α.
    """
    if kappa == 0.0:
        return x + length * math.cos(th), y + length * math.sin(th), wrap_angle(th)
    r = 1.0 / abs(kappa)
    alpha = abs(length * kappa)
    d_l = 1.0 if length > 0.0 else (-1.0 if length < 0.0 else 0.0)
    d_k = 1.0 if kappa > 0.0 else -1.0
    s = math.sin(th)
    c = math.cos(th)
    one_minus_cos = 1.0 - math.cos(alpha)
    sin_a = math.sin(alpha)
    nx = x + d_l * (r * one_minus_cos * d_k * s + r * sin_a * c)
    ny = y + d_l * (-r * one_minus_cos * d_k * c + r * sin_a * s)
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
