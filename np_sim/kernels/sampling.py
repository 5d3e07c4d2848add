"""Compiled rejection step of the uniform start sampler."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import footprint_valid
from np_sim.kernels.geometry import INSIDE, point_in_polygon


@njit(cache=True, error_model="numpy")
def first_free_draw(geo, k: int, region: np.ndarray, lo: np.ndarray, hi: np.ndarray, u: np.ndarray,
                    local: np.ndarray) -> int:
    """Index of the first row of uniforms ``u`` (D, 3) whose pose — x, y = lo + u·(hi − lo), θ = −π + 2π u —
    lies strictly inside ``region`` with a footprint free in scene k; −1 when none does."""
    corners = np.empty((4, 2))
    for r in range(u.shape[0]):
        x = lo[0] + u[r, 0] * (hi[0] - lo[0])
        y = lo[1] + u[r, 1] * (hi[1] - lo[1])
        th = -math.pi + 2.0 * math.pi * u[r, 2]
        if point_in_polygon(x, y, region, region.shape[0]) != INSIDE:
            continue
        if footprint_valid(geo, k, x, y, th, local, corners):
            return r
    return -1
