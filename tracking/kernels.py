"""Compiled kernels of the tracking loop (pure functions over arrays; tested against numpy versions)."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def nearest_piece(xy, px: float, py: float, i0: int, i1: int):
    """(i, t) of the polyline piece p_i → p_{i+1}, i ∈ [i0, i1), nearest to (px, py), and the piece parameter
    t = clip((p − p_i)·(p_{i+1} − p_i) / |p_{i+1} − p_i|², 0, 1) of the nearest point; the first piece wins ties."""
    best, best_i, best_t = 1e300, i0, 0.0
    for i in range(i0, i1):
        ax, ay = xy[i, 0], xy[i, 1]
        dx, dy = xy[i + 1, 0] - ax, xy[i + 1, 1] - ay
        rx, ry = px - ax, py - ay
        dd = dx * dx + dy * dy
        t = (rx * dx + ry * dy) / dd if dd > 1e-18 else 0.0
        t = min(1.0, max(0.0, t))
        gx, gy = rx - t * dx, ry - t * dy
        d2 = gx * gx + gy * gy
        if d2 < best:
            best, best_i, best_t = d2, i, t
    return best_i, best_t
