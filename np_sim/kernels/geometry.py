"""Compiled 2-D geometry kernels: strict point-in-polygon, segment intersection, ray casting, footprint tests.

Each kernel is a short ``@njit(cache=True, error_model="numpy")`` function over arrays and scalars, tested against shapely in
``tests/np_sim/kernels/test_geometry.py``. "Strict" means zero tolerance: a point on a polygon edge is neither
inside nor outside (it is *on* the polygon), and a ray hits a segment only for segment parameter 0 < u < 1 and
ray parameter t > 0 (paper App. A, "strict, zero-tolerance segment-bound tests").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

INSIDE = 1
OUTSIDE = 0
ON_EDGE = -1


@njit(cache=True, error_model="numpy")
def point_in_polygon(px: float, py: float, verts: np.ndarray, n: int) -> int:
    """Classify a point against the simple polygon ``verts[:n]``: INSIDE (1), OUTSIDE (0) or ON_EDGE (-1).

    Crossing-number test; a point exactly on an edge (zero cross product, within the edge's bounds) is ON_EDGE.
    """
    inside = False
    j = n - 1
    for i in range(n):
        xi = verts[i, 0]
        yi = verts[i, 1]
        xj = verts[j, 0]
        yj = verts[j, 1]
        cross = (xj - xi) * (py - yi) - (yj - yi) * (px - xi)
        if cross == 0.0 and min(xi, xj) <= px <= max(xi, xj) and min(yi, yj) <= py <= max(yi, yj):
            return ON_EDGE
        if (yi > py) != (yj > py):
            x_cross = xi + (py - yi) * (xj - xi) / (yj - yi)
            if px < x_cross:
                inside = not inside
        j = i
    return INSIDE if inside else OUTSIDE


@njit(cache=True, error_model="numpy")
def _orient(ax: float, ay: float, bx: float, by: float, cx: float, cy: float) -> float:
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True, error_model="numpy")
def _on_segment(ax: float, ay: float, bx: float, by: float, cx: float, cy: float) -> bool:
    """c is collinear with a-b; is it within the segment's bounding box?"""
    return min(ax, bx) <= cx <= max(ax, bx) and min(ay, by) <= cy <= max(ay, by)


@njit(cache=True, error_model="numpy")
def segments_intersect(
    ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float, dy: float
) -> bool:
    """Closed segments a-b and c-d share at least one point (touching counts), by exact orientation tests."""
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, dx, dy)
    o3 = _orient(cx, cy, dx, dy, ax, ay)
    o4 = _orient(cx, cy, dx, dy, bx, by)
    if ((o1 > 0 and o2 < 0) or (o1 < 0 and o2 > 0)) and ((o3 > 0 and o4 < 0) or (o3 < 0 and o4 > 0)):
        return True
    if o1 == 0 and _on_segment(ax, ay, bx, by, cx, cy):
        return True
    if o2 == 0 and _on_segment(ax, ay, bx, by, dx, dy):
        return True
    if o3 == 0 and _on_segment(cx, cy, dx, dy, ax, ay):
        return True
    if o4 == 0 and _on_segment(cx, cy, dx, dy, bx, by):
        return True
    return False


@njit(cache=True, error_model="numpy")
def ray_segment_distance(
    ox: float, oy: float, dx: float, dy: float, x0: float, y0: float, x1: float, y1: float
) -> float:
    """Distance t > 0 along the unit ray o + t·d to segment (x0,y0)-(x1,y1), or +inf when it misses.

    Solves o + t d = p0 + u (p1 - p0); a hit needs t > 0 and 0 < u < 1 strictly, parallel rays never hit.
    """
    ex = x1 - x0
    ey = y1 - y0
    denom = dx * ey - dy * ex
    if denom == 0.0:
        return np.inf
    px = x0 - ox
    py = y0 - oy
    t = (px * ey - py * ex) / denom
    u = (px * dy - py * dx) / denom
    if t > 0.0 and 0.0 < u < 1.0:
        return t
    return np.inf


@njit(cache=True, error_model="numpy")
def cast_beams(
    ox: float,
    oy: float,
    heading: float,
    segs: np.ndarray,
    n_segs: int,
    n_beams: int,
    max_range: float,
    out: np.ndarray,
) -> None:
    """First-hit distances of ``n_beams`` rays over 360° into ``out`` (capped at ``max_range``).

    Beam i points at ``heading + 2πi/n_beams`` (beam 0 along the heading, counter-clockwise). ``segs[:n_segs]``
    holds (x0, y0, x1, y1) rows. For speed each segment only tests the beams inside its angular span (plus one
    beam of margin each side); the hit test itself is the exact ``ray_segment_distance``.
    """
    step = 2.0 * math.pi / n_beams
    for i in range(n_beams):
        out[i] = max_range
    for k in range(n_segs):
        x0 = segs[k, 0] - ox
        y0 = segs[k, 1] - oy
        x1 = segs[k, 2] - ox
        y1 = segs[k, 3] - oy
        # skip segments entirely beyond max_range (distance from the origin to the segment)
        ex = x1 - x0
        ey = y1 - y0
        ee = ex * ex + ey * ey
        u = 0.0
        if ee > 0.0:
            u = -(x0 * ex + y0 * ey) / ee
            u = min(1.0, max(0.0, u))
        cx = x0 + u * ex
        cy = y0 + u * ey
        if cx * cx + cy * cy > max_range * max_range:
            continue
        a0 = math.atan2(y0, x0) - heading
        a1 = math.atan2(y1, x1) - heading
        span = a1 - a0
        span = span - 2.0 * math.pi * math.floor((span + math.pi) / (2.0 * math.pi))  # wrap to [-π, π)
        if abs(span) >= math.pi - 1e-9:
            lo_idx = 0
            hi_idx = n_beams - 1
        else:
            lo = a0 if span >= 0.0 else a0 + span
            f_lo = lo / step
            lo_idx = int(math.floor(f_lo)) - 1
            hi_idx = int(math.ceil(f_lo + abs(span) / step)) + 1
            if hi_idx - lo_idx >= n_beams:
                lo_idx = 0
                hi_idx = n_beams - 1
        for j in range(lo_idx, hi_idx + 1):
            b = j % n_beams
            ang = heading + b * step
            t = ray_segment_distance(0.0, 0.0, math.cos(ang), math.sin(ang), x0, y0, x1, y1)
            if t < out[b]:
                out[b] = t


@njit(cache=True, error_model="numpy")
def footprint_corners(x: float, y: float, th: float, local: np.ndarray, out: np.ndarray) -> None:
    """World corners of the vehicle rectangle ``local`` (4, 2) at pose (x, y, θ) into ``out`` (4, 2)."""
    c = math.cos(th)
    s = math.sin(th)
    for i in range(4):
        out[i, 0] = x + c * local[i, 0] - s * local[i, 1]
        out[i, 1] = y + s * local[i, 0] + c * local[i, 1]


@njit(cache=True, error_model="numpy")
def polygon_edges_cross(a: np.ndarray, na: int, b: np.ndarray, nb: int) -> bool:
    """Some closed edge of polygon ``a[:na]`` touches or crosses some closed edge of ``b[:nb]``."""
    for i in range(na):
        i2 = (i + 1) % na
        for j in range(nb):
            j2 = (j + 1) % nb
            if segments_intersect(a[i, 0], a[i, 1], a[i2, 0], a[i2, 1], b[j, 0], b[j, 1], b[j2, 0], b[j2, 1]):
                return True
    return False


@njit(cache=True, error_model="numpy")
def polygons_overlap(a: np.ndarray, na: int, b: np.ndarray, nb: int) -> bool:
    """Closed simple polygons a and b share a point (touching counts): edges meet or one holds the other."""
    if polygon_edges_cross(a, na, b, nb):
        return True
    if point_in_polygon(a[0, 0], a[0, 1], b, nb) != OUTSIDE:
        return True
    if point_in_polygon(b[0, 0], b[0, 1], a, na) != OUTSIDE:
        return True
    return False


@njit(cache=True, error_model="numpy")
def rect_circle_overlap(x: float, y: float, th: float, local: np.ndarray, cx: float, cy: float, r: float) -> bool:
    """Closed vehicle rectangle at pose (x, y, θ) and closed disc (cx, cy, r) share a point.

    Exact: the circle centre in the vehicle frame is clamped to the rectangle; overlap iff that distance <= r.
    """
    c = math.cos(th)
    s = math.sin(th)
    dx = cx - x
    dy = cy - y
    lx = c * dx + s * dy
    ly = -s * dx + c * dy
    qx = min(max(lx, local[0, 0]), local[1, 0])
    qy = min(max(ly, local[0, 1]), local[2, 1])
    return (lx - qx) ** 2 + (ly - qy) ** 2 <= r * r
