"""Compiled 2-D geometry kernels: strict point-in-polygon, segment intersection, ray casting, footprint tests.

Each kernel is a short ``@njit(cache=True, error_model="numpy")`` function over arrays and scalars, tested against
shapely in ``tests/np_sim/kernels/test_geometry.py``. "Strict" means exact, zero tolerance (paper App. A, "strict,
zero-tolerance segment-bound tests"): a point on a polygon edge is neither inside nor outside (it is *on* the
polygon); a ray hits a segment when the segment parameter lies in [0, 1] exactly — no epsilon widens or shrinks
the bounds, so a beam through a polygon corner hits it — and the ray parameter is strictly positive (the ray's
own origin is not a hit). A ray parallel to a segment never hits it; a beam grazing an edge therefore stops at
the corner where the next edge begins.
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

    Solves o + t d = p0 + u (p1 - p0); a hit needs t > 0 and 0 <= u <= 1 (exact bounds), parallel rays never hit.
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
    if t > 0.0 and 0.0 <= u <= 1.0:
        return t
    return np.inf


ATAN_APPROX_MAX_ERR = 1e-4
"""Bound (rad) on the error of ``_atan2_approx``, with margin; it only chooses which beams to test exactly."""


@njit(cache=True, error_model="numpy")
def _atan2_approx(y: float, x: float) -> float:
    """atan2 to within 1e-5 rad (odd minimax polynomial on [0, 1] plus octant folding)."""
    ax = abs(x)
    ay = abs(y)
    if ax == 0.0 and ay == 0.0:
        return 0.0
    swap = ay > ax
    z = ax / ay if swap else ay / ax
    z2 = z * z
    a = z * (0.9998660 + z2 * (-0.3302995 + z2 * (0.1801410 + z2 * (-0.0851330 + z2 * 0.0208351))))
    if swap:
        a = 0.5 * math.pi - a
    if x < 0.0:
        a = math.pi - a
    return -a if y < 0.0 else a


@njit(cache=True, error_model="numpy")
def beam_offsets(n_beams: int):
    """(cos, sin) of the beam offsets 2πi/n, i = 0..n−1, relative to the heading."""
    c = np.empty(n_beams)
    s = np.empty(n_beams)
    for i in range(n_beams):
        c[i] = math.cos(2.0 * math.pi * i / n_beams)
        s[i] = math.sin(2.0 * math.pi * i / n_beams)
    return c, s


@njit(cache=True, error_model="numpy")
def cast_beams_offsets(
    ox: float,
    oy: float,
    heading: float,
    segs: np.ndarray,
    n_segs: int,
    off_c: np.ndarray,
    off_s: np.ndarray,
    max_range: float,
    out: np.ndarray,
) -> None:
    """First-hit distances of the beams with offset directions (off_c, off_s) (from ``beam_offsets``) into
    ``out``, capped at ``max_range``; beam i points along the heading rotated by its offset.

    ``segs[:n_segs]`` holds (x0, y0, x1, y1) rows. For speed each segment only tests the beams inside its angular
    span (from an approximate atan2, widened by one beam plus the approximation error each side); the hit test
    itself is the exact ``ray_segment_distance``, so the result equals testing every beam against every segment.
    """
    n_beams = out.shape[0]
    step = 2.0 * math.pi / n_beams
    margin = 1 + int(math.ceil(ATAN_APPROX_MAX_ERR / step))
    ch = math.cos(heading)
    sh = math.sin(heading)
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
        # endpoint angles relative to the heading, in the vehicle frame
        a0 = _atan2_approx(-sh * x0 + ch * y0, ch * x0 + sh * y0)
        a1 = _atan2_approx(-sh * x1 + ch * y1, ch * x1 + sh * y1)
        span = a1 - a0
        if span >= math.pi:
            span -= 2.0 * math.pi
        elif span < -math.pi:
            span += 2.0 * math.pi
        if abs(span) >= math.pi - 2.0 * ATAN_APPROX_MAX_ERR:
            lo_idx = 0
            hi_idx = n_beams - 1
        else:
            lo = a0 if span >= 0.0 else a0 + span
            f_lo = lo / step
            lo_idx = int(math.floor(f_lo)) - margin
            hi_idx = int(math.ceil(f_lo + abs(span) / step)) + margin
            if hi_idx - lo_idx >= n_beams:
                lo_idx = 0
                hi_idx = n_beams - 1
        for j in range(lo_idx, hi_idx + 1):
            b = j % n_beams
            dx = ch * off_c[b] - sh * off_s[b]
            dy = sh * off_c[b] + ch * off_s[b]
            t = ray_segment_distance(0.0, 0.0, dx, dy, x0, y0, x1, y1)
            if t < out[b]:
                out[b] = t


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

    Beam i points at ``heading + 2πi/n_beams`` (beam 0 along the heading, counter-clockwise), its direction
    computed as the heading's unit vector rotated by (cos 2πi/n, sin 2πi/n) (``beam_direction``).
    """
    off_c, off_s = beam_offsets(n_beams)
    cast_beams_offsets(ox, oy, heading, segs, n_segs, off_c, off_s, max_range, out[:n_beams])


@njit(cache=True, error_model="numpy")
def beam_direction(heading: float, i: int, n_beams: int):
    """Unit direction of beam i exactly as the casters compute it (heading vector rotated by 2πi/n)."""
    ch = math.cos(heading)
    sh = math.sin(heading)
    c = math.cos(2.0 * math.pi * i / n_beams)
    s = math.sin(2.0 * math.pi * i / n_beams)
    return ch * c - sh * s, sh * c + ch * s


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
