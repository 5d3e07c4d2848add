"""Compiled point-to-polygon distances for the site's rule (`np_sim.nearest`): which obstacles are nearest."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.geometry import OUTSIDE, point_in_polygon


@njit(cache=True, error_model="numpy")
def point_polygon_distances(points: np.ndarray, verts: np.ndarray, counts: np.ndarray, out: np.ndarray) -> None:
    """``out[i, j]`` = Euclidean distance from ``points[i]`` (x, y) to the simple polygon ``verts[j, :counts[j]]``:
    0 inside or on an edge (crossing-number test), else the least distance to its edges."""
    for i in range(points.shape[0]):
        px = points[i, 0]
        py = points[i, 1]
        for j in range(verts.shape[0]):
            n = counts[j]
            if point_in_polygon(px, py, verts[j], n) != OUTSIDE:
                out[i, j] = 0.0
                continue
            best = math.inf
            for k in range(n):
                ax, ay = verts[j, k, 0], verts[j, k, 1]
                ex, ey = verts[j, (k + 1) % n, 0] - ax, verts[j, (k + 1) % n, 1] - ay
                ee = ex * ex + ey * ey
                t = 0.0 if ee == 0.0 else min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / ee))
                best = min(best, math.hypot(ax + t * ex - px, ay + t * ey - py))
            out[i, j] = best
