"""Compiled rejection step of the uniform start sampler."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import footprint_valid
from np_sim.kernels.geometry import INSIDE, point_in_polygon


@njit(cache=True, error_model="numpy")
def first_free_draws(geo, scene_idx: np.ndarray, regions: np.ndarray, n_region: np.ndarray, u: np.ndarray,
                     local: np.ndarray, out: np.ndarray) -> np.ndarray:
    """For each request r (scene ``scene_idx[r]``), the first row of uniforms ``u[r]`` (D, 3) whose pose —
    x, y = lo + u·(hi − lo) over the region's bounding box, θ = −π + 2π u — lies strictly inside the start region
    ``regions[k, :n_region[k]]`` with a footprint free in scene k. Writes accepted poses to ``out[r]`` and returns
    a mask of the requests that found one."""
    found = np.zeros(u.shape[0], np.bool_)
    corners = np.empty((4, 2))
    for r in range(u.shape[0]):
        k = scene_idx[r]
        region = regions[k, : n_region[k]]
        lox = region[:, 0].min()
        hix = region[:, 0].max()
        loy = region[:, 1].min()
        hiy = region[:, 1].max()
        for d in range(u.shape[1]):
            x = lox + u[r, d, 0] * (hix - lox)
            y = loy + u[r, d, 1] * (hiy - loy)
            th = -math.pi + 2.0 * math.pi * u[r, d, 2]
            if point_in_polygon(x, y, region, region.shape[0]) != INSIDE:
                continue
            if footprint_valid(geo, k, x, y, th, local, corners):
                out[r, 0] = x
                out[r, 1] = y
                out[r, 2] = th
                found[r] = True
                break
    return found
