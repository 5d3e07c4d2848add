"""Compiled exact (continuous) collision tests of a body swept along an arc or a Hermite cubic (``np_sim.validate``).

An arc (κ, l) of paper eq:arc moves the vehicle rigidly: with κ ≠ 0 it rotates about the fixed centre
C = (x, y) + sgn(l)/κ · (sin θ, −cos θ) by ω = −κ|l| (heading θ(u) = θ − κ|l|u, u ∈ [0, 1]); with κ = 0 it
translates by d = l (cos θ, sin θ). For a rigid motion of polygons, contact begins when a vertex of one crosses an
edge of the other, so a body that is clear at u = 0 stays clear on [0, 1] unless

* a vehicle corner's trajectory (an arc about C, or a segment) meets an obstacle or boundary edge, or
* an obstacle or boundary vertex's trajectory relative to the body (an arc about C swept by −ω, or the segment
  V − u·d, written in the start pose's world coordinates) meets a vehicle edge (at u = 0);

a disc of radius r: a corner trajectory meets the disc, or the disc centre's relative trajectory meets a vehicle
edge shifted outward by r. The reference point is a body without edges: only its own trajectory counts.

"Meets" is distance ≤ ``eps`` (``EXACT_TOLERANCE_M``): every contact and every near miss closer than eps is a
violation, so the rule errs only on the strict side. The distance between an arc (or segment) and a segment is
zero or at most eps exactly when a crossing point lies on both, an endpoint of one lies within eps of the other, or
the foot of the perpendicular from C onto the segment's line lies on the segment within eps of the circle inside the
arc's angular range; each test below checks exactly these cases and returns the first contact parameter u.

An arc turning by less than ``STRAIGHT_TURN_RAD`` is tested as a straight segment with eps widened by what the
turn can move a body point (its sagitta plus ρ·|κl|), which keeps C from lying metres away in rounding noise.

The Hermite cubic is not a rigid circular motion. It is certified piecewise: over t ∈ [t0, t1] with midpoint tm,
Δt = t1 − t0, M2 = max(|r''(t0)|, |r''(t1)|) (r'' is linear, so its norm peaks at an end), every body point stays
within m = D + ρ·Δψ of where it is at t0, with D = Δt (|r'(tm)| + M2 Δt/2) the largest displacement of the
reference point and Δψ = Δt M2 / (|r'(tm)| − M2 Δt/2) a bound on the turn of the heading (the tangent direction)
and ρ the largest distance of a body point from the reference point. A piece is clear when the body at t0,
inflated by m, is more than eps from every obstacle and the boundary; otherwise it is bisected (in order of t, so
the first violation is found first). A piece whose body at t0 itself touches is a violation, and so is one
whose m has fallen to eps without being cleared (the body then comes within 2·eps: on the Hermite segment the
rule counts contacts within 2·eps, which bounds the bisection depth); a piece still undecided after
``HERMITE_MAX_DEPTH`` bisections or a piece budget is reported as a violation (never as clear).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import pose_valid
from np_sim.kernels.geometry import INSIDE, OUTSIDE, footprint_corners, point_in_polygon, segments_intersect

EXACT_TOLERANCE_M = 1e-9
"""Distance (m) at or below which the exact rule counts a contact: touching is a violation, and so is a near miss
closer than this (floating point cannot tell them apart)."""
STRAIGHT_TURN_RAD = 1e-7
"""Arcs turning by less than this (rad) are tested as straight segments with a widened tolerance."""
HERMITE_MAX_DEPTH = 40
"""Bisections of the Hermite parameter before an undecided piece is reported as a violation."""

KIND_NONE, KIND_BOUNDARY, KIND_POLYGON, KIND_CIRCLE, KIND_UNDECIDED = -1, 0, 1, 2, 3
"""What a violation touched (written to ``hit[0]``; ``hit[1]`` is the packed polygon or circle index)."""


@njit(cache=True, error_model="numpy")
def _seg_point_dist(ax, ay, bx, by, px, py):
    """(distance, parameter t ∈ [0, 1]) from point p to the closed segment a-b."""
    ex = bx - ax
    ey = by - ay
    ee = ex * ex + ey * ey
    t = 0.0
    if ee > 0.0:
        t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / ee))
    return math.hypot(ax + t * ex - px, ay + t * ey - py), t


@njit(cache=True, error_model="numpy")
def _angle_u(px, py, cx, cy, phi0, sweep, tol_rad):
    """Parameter u ∈ [0, 1] at which the arc from angle φ0 swept by ``sweep`` first reaches the angle of p about
    c (within ``tol_rad``), or −1 when it never does."""
    a = abs(sweep)
    if a == 0.0:
        return -1.0
    d = (math.atan2(py - cy, px - cx) - phi0) * (1.0 if sweep > 0.0 else -1.0)
    d = d - 2.0 * math.pi * math.floor(d / (2.0 * math.pi))
    if d <= a + tol_rad:
        return min(d / a, 1.0)
    if d >= 2.0 * math.pi - tol_rad:
        return 0.0
    return -1.0


@njit(cache=True, error_model="numpy")
def _arc_point(cx, cy, radius, phi0, sweep, u):
    a = phi0 + sweep * u
    return cx + radius * math.cos(a), cy + radius * math.sin(a)


@njit(cache=True, error_model="numpy")
def _first(best, u):
    """Smaller of two contact parameters where −1 means none."""
    if u < 0.0:
        return best
    if best < 0.0 or u < best:
        return u
    return best


@njit(cache=True, error_model="numpy")
def arc_segment_contact(cx, cy, radius, phi0, sweep, ax, ay, bx, by, eps):
    """First u ∈ [0, 1] at which the arc (centre c, radius, start angle φ0, sweep) comes within ``eps`` of the
    closed segment a-b, or −1 (module docstring: crossings, endpoint distances, the tangent foot point)."""
    tol = eps / max(radius, 1e-300)
    best = -1.0
    for u in (0.0, 1.0):
        px, py = _arc_point(cx, cy, radius, phi0, sweep, u)
        if _seg_point_dist(ax, ay, bx, by, px, py)[0] <= eps:
            best = _first(best, u)
    for px, py in ((ax, ay), (bx, by)):
        if abs(math.hypot(px - cx, py - cy) - radius) <= eps:
            best = _first(best, _angle_u(px, py, cx, cy, phi0, sweep, tol))
    ex = bx - ax
    ey = by - ay
    ee = ex * ex + ey * ey
    if ee == 0.0:
        return best
    t_foot = ((cx - ax) * ex + (cy - ay) * ey) / ee
    h = abs((cx - ax) * ey - (cy - ay) * ex) / math.sqrt(ee)  # distance from c to the segment's line
    if h > radius + eps:
        return best
    half = math.sqrt(max(radius * radius - h * h, 0.0) / ee)
    for t in (t_foot - half, t_foot + half):
        if 0.0 <= t <= 1.0:
            best = _first(best, _angle_u(ax + t * ex, ay + t * ey, cx, cy, phi0, sweep, tol))
    return best


@njit(cache=True, error_model="numpy")
def moving_segment_contact(px, py, dx, dy, ax, ay, bx, by, eps):
    """First u ∈ [0, 1] at which the point p + u·d comes within ``eps`` of the closed segment a-b, or −1: its
    endpoints near a-b, a or b near its path, or a crossing."""
    best = -1.0
    for u in (0.0, 1.0):
        if _seg_point_dist(ax, ay, bx, by, px + u * dx, py + u * dy)[0] <= eps:
            best = _first(best, u)
    for qx, qy in ((ax, ay), (bx, by)):
        dist, u = _seg_point_dist(px, py, px + dx, py + dy, qx, qy)
        if dist <= eps:
            best = _first(best, u)
    ex = bx - ax
    ey = by - ay
    den = dx * ey - dy * ex
    if den != 0.0:
        wx = ax - px
        wy = ay - py
        u = (wx * ey - wy * ex) / den
        t = (wx * dy - wy * dx) / den
        if 0.0 <= u <= 1.0 and 0.0 <= t <= 1.0:
            best = _first(best, u)
    return best


@njit(cache=True, error_model="numpy")
def arc_disc_contact(cx, cy, radius, phi0, sweep, ox, oy, r, eps):
    """First u ∈ [0, 1] at which the arc comes within ``eps`` of the closed disc (o, r), or −1."""
    rr = r + eps
    best = -1.0
    for u in (0.0, 1.0):
        px, py = _arc_point(cx, cy, radius, phi0, sweep, u)
        if math.hypot(px - ox, py - oy) <= rr:
            best = _first(best, u)
    dist = math.hypot(ox - cx, oy - cy)
    if dist == 0.0 or dist > radius + rr or dist < radius - rr:
        return best
    cos_half = (radius * radius + dist * dist - rr * rr) / (2.0 * radius * dist)
    half = math.acos(min(1.0, max(-1.0, cos_half)))
    base = math.atan2(oy - cy, ox - cx)
    tol = eps / max(radius, 1e-300)
    for a in (base - half, base + half):
        best = _first(best, _angle_u(cx + math.cos(a), cy + math.sin(a), cx, cy, phi0, sweep, tol))
    return best


@njit(cache=True, error_model="numpy")
def moving_disc_contact(px, py, dx, dy, ox, oy, r, eps):
    """First u ∈ [0, 1] at which the point p + u·d comes within ``eps`` of the closed disc (o, r), or −1."""
    rr = r + eps
    fx = px - ox
    fy = py - oy
    c = fx * fx + fy * fy - rr * rr
    if c <= 0.0:
        return 0.0
    a = dx * dx + dy * dy
    b = 2.0 * (fx * dx + fy * dy)
    disc = b * b - 4.0 * a * c
    if a == 0.0 or disc < 0.0:
        return -1.0
    u = (-b - math.sqrt(disc)) / (2.0 * a)
    return u if 0.0 <= u <= 1.0 else -1.0


@njit(cache=True, error_model="numpy")
def arc_motion(x, y, th, kappa, length, rho, out):
    """The rigid motion of the arc (κ, l) from (x, y, θ) into ``out`` (6,): straight flag, C (or d) x, y, ω, the
    widening of eps for a nearly straight arc, and the arc's turn |κl| (``rho``: largest body-point distance)."""
    turn = abs(kappa * length)
    if turn < STRAIGHT_TURN_RAD:
        out[0] = 1.0
        out[1] = length * math.cos(th)
        out[2] = length * math.sin(th)
        out[3] = 0.0
        out[4] = abs(length) * turn / 8.0 + rho * turn  # sagitta + rotation of the farthest body point
    else:
        sgn = 1.0 if length > 0.0 else -1.0
        out[0] = 0.0
        out[1] = x + sgn * math.sin(th) / kappa
        out[2] = y - sgn * math.cos(th) / kappa
        out[3] = -kappa * abs(length)
        out[4] = 0.0
    out[5] = turn


@njit(cache=True, error_model="numpy")
def _path_segment_contact(motion, px, py, sign, ax, ay, bx, by, eps):
    """First contact of the point p moved by the motion (sign +1: a body point; −1: an obstacle point relative to
    the body) with the segment a-b, or −1."""
    if motion[0] > 0.0:
        return moving_segment_contact(px, py, sign * motion[1], sign * motion[2], ax, ay, bx, by, eps)
    cx = motion[1]
    cy = motion[2]
    return arc_segment_contact(cx, cy, math.hypot(px - cx, py - cy), math.atan2(py - cy, px - cx), sign * motion[3],
                               ax, ay, bx, by, eps)


@njit(cache=True, error_model="numpy")
def _path_disc_contact(motion, px, py, ox, oy, r, eps):
    """First contact of the body point p moved by the motion with the disc (o, r), or −1."""
    if motion[0] > 0.0:
        return moving_disc_contact(px, py, motion[1], motion[2], ox, oy, r, eps)
    cx = motion[1]
    cy = motion[2]
    return arc_disc_contact(cx, cy, math.hypot(px - cx, py - cy), math.atan2(py - cy, px - cx), motion[3], ox, oy,
                            r, eps)


@njit(cache=True, error_model="numpy")
def _moved(motion, px, py, u):
    """Where the body point p is at parameter u."""
    if motion[0] > 0.0:
        return px + u * motion[1], py + u * motion[2]
    c = math.cos(motion[3] * u)
    s = math.sin(motion[3] * u)
    dx = px - motion[1]
    dy = py - motion[2]
    return motion[1] + c * dx - s * dy, motion[2] + s * dx + c * dy


@njit(cache=True, error_model="numpy")
def _record(best, u, kind, index, px, py, hit):
    """Keep the earlier of the current best contact and (u, kind, index, position); returns the new best u."""
    if u < 0.0 or (best >= 0.0 and u >= best):
        return best
    hit[0] = kind
    hit[1] = index
    hit[2] = px
    hit[3] = py
    return u


@njit(cache=True, error_model="numpy")
def _ring_contact(motion, body, n_body, ring, n_ring, kind, index, eps, box, earliest, best, hit):
    """Contacts of the body (points ``body[:n_body]``, edges when n_body > 1) with the closed ring's edges and
    vertices (each edge or vertex outside the culling ``box`` skipped); returns the earliest u so far (without
    ``earliest``, the first contact found)."""
    for j in range(n_ring):
        ax = ring[j, 0]
        ay = ring[j, 1]
        bx = ring[(j + 1) % n_ring, 0]
        by = ring[(j + 1) % n_ring, 1]
        if max(ax, bx) < box[0] or min(ax, bx) > box[2] or max(ay, by) < box[1] or min(ay, by) > box[3]:
            continue
        for i in range(n_body):
            u = _path_segment_contact(motion, body[i, 0], body[i, 1], 1.0, ax, ay, bx, by, eps)
            if u >= 0.0:
                qx, qy = _moved(motion, body[i, 0], body[i, 1], u)
                best = _record(best, u, kind, index, qx, qy, hit)
                if best >= 0.0 and not earliest:
                    return best
    if n_body < 2:
        return best
    for j in range(n_ring):
        vx = ring[j, 0]
        vy = ring[j, 1]
        if vx < box[0] or vx > box[2] or vy < box[1] or vy > box[3]:
            continue
        for i in range(n_body):
            i2 = (i + 1) % n_body
            u = _path_segment_contact(motion, vx, vy, -1.0, body[i, 0], body[i, 1], body[i2, 0], body[i2, 1], eps)
            best = _record(best, u, kind, index, vx, vy, hit)
            if best >= 0.0 and not earliest:
                return best
    return best


@njit(cache=True, error_model="numpy")
def _disc_contact(motion, body, n_body, ox, oy, r, index, eps, best, hit):
    """Contacts of the body with the disc (o, r): body points against the disc, and (rectangle) the disc centre's
    relative path against each edge shifted outward by r (the body is counter-clockwise)."""
    for i in range(n_body):
        u = _path_disc_contact(motion, body[i, 0], body[i, 1], ox, oy, r, eps)
        if u >= 0.0:
            qx, qy = _moved(motion, body[i, 0], body[i, 1], u)
            best = _record(best, u, KIND_CIRCLE, index, qx, qy, hit)
    if n_body < 2:
        return best
    for i in range(n_body):
        i2 = (i + 1) % n_body
        ex = body[i2, 0] - body[i, 0]
        ey = body[i2, 1] - body[i, 1]
        norm = math.hypot(ex, ey)
        nx = r * ey / norm
        ny = -r * ex / norm
        u = _path_segment_contact(motion, ox, oy, -1.0, body[i, 0] + nx, body[i, 1] + ny, body[i2, 0] + nx,
                                  body[i2, 1] + ny, eps)
        best = _record(best, u, KIND_CIRCLE, index, ox, oy, hit)
    return best


@njit(cache=True, error_model="numpy")
def swept_arc_contact(geo, k, x, y, th, kappa, length, footprint, local, eps, earliest, hit):
    """First parameter u ∈ [0, 1] at which the body (the rectangle ``local`` when ``footprint``, else the reference
    point) moved along the arc (κ, l) from (x, y, θ) comes within ``eps`` of an obstacle or the boundary of scene
    k, or −1 when it never does (the pose at u = 0 is assumed clear; see ``body_clear``). Without ``earliest`` the
    first contact found is returned (a search needs only the verdict). ``hit`` (4,) receives the contact's kind
    (KIND_*), packed index and world position. Obstacles and edges outside the swept body's bounding box (its
    corners' paths, ``_swept_box``) are skipped."""
    boundary, n_boundary, poly, poly_nv, n_poly, aabb, circle, n_circle = (geo[0], geo[1], geo[2], geo[3], geo[4],
                                                                           geo[5], geo[6], geo[7])
    if length == 0.0:
        return -1.0
    n_body = 4 if footprint else 1
    body = np.zeros((4, 2))
    rho = 0.0
    if footprint:
        footprint_corners(x, y, th, local, body)
        for i in range(4):
            rho = max(rho, math.hypot(local[i, 0], local[i, 1]))
    else:
        body[0, 0] = x
        body[0, 1] = y
    motion = np.empty(6)
    arc_motion(x, y, th, kappa, length, rho, motion)
    eps = eps + motion[4]
    box = np.empty(4)
    _swept_box(motion, body, n_body, eps, box)
    best = _ring_contact(motion, body, n_body, boundary[k], n_boundary[k], KIND_BOUNDARY, 0, eps, box, earliest,
                         -1.0, hit)
    for j in range(n_poly[k]):
        if best >= 0.0 and not earliest:
            return best
        if aabb[k, j, 2] < box[0] or aabb[k, j, 0] > box[2] or aabb[k, j, 3] < box[1] or aabb[k, j, 1] > box[3]:
            continue
        best = _ring_contact(motion, body, n_body, poly[k, j], poly_nv[k, j], KIND_POLYGON, j, eps, box, earliest,
                             best, hit)
    for j in range(n_circle[k]):
        if best >= 0.0 and not earliest:
            return best
        ox = circle[k, j, 0]
        oy = circle[k, j, 1]
        r = circle[k, j, 2]
        if ox + r < box[0] or ox - r > box[2] or oy + r < box[1] or oy - r > box[3]:
            continue
        best = _disc_contact(motion, body, n_body, ox, oy, r, j, eps, best, hit)
    return best


@njit(cache=True, error_model="numpy")
def _swept_box(motion, body, n_body, margin, box):
    """Bounding box (x0, y0, x1, y1) of the body swept by the motion, grown by ``margin``: the extremes of a convex
    body along an axis are at its corners, and a corner's path is a segment (its ends) or an arc (its ends and the
    axis-extreme points of its circle inside the swept angle)."""
    box[0] = math.inf
    box[1] = math.inf
    box[2] = -math.inf
    box[3] = -math.inf
    for i in range(n_body):
        px = body[i, 0]
        py = body[i, 1]
        for u in (0.0, 1.0):
            qx, qy = _moved(motion, px, py, u)
            _grow(box, qx, qy)
        if motion[0] > 0.0:
            continue
        cx = motion[1]
        cy = motion[2]
        r = math.hypot(px - cx, py - cy)
        phi0 = math.atan2(py - cy, px - cx)
        for ax, ay in ((cx + r, cy), (cx, cy + r), (cx - r, cy), (cx, cy - r)):
            if _angle_u(ax, ay, cx, cy, phi0, motion[3], 0.0) >= 0.0:
                _grow(box, ax, ay)
    box[0] -= margin
    box[1] -= margin
    box[2] += margin
    box[3] += margin


@njit(cache=True, error_model="numpy")
def _grow(box, x, y):
    """Extend the box (x0, y0, x1, y1) to hold (x, y)."""
    box[0] = min(box[0], x)
    box[1] = min(box[1], y)
    box[2] = max(box[2], x)
    box[3] = max(box[3], y)


@njit(cache=True, error_model="numpy")
def _seg_seg_dist(ax, ay, bx, by, cx, cy, dx, dy):
    """Distance between the closed segments a-b and c-d (0 when they meet)."""
    if segments_intersect(ax, ay, bx, by, cx, cy, dx, dy):
        return 0.0
    return min(min(_seg_point_dist(ax, ay, bx, by, cx, cy)[0], _seg_point_dist(ax, ay, bx, by, dx, dy)[0]),
               min(_seg_point_dist(cx, cy, dx, dy, ax, ay)[0], _seg_point_dist(cx, cy, dx, dy, bx, by)[0]))


@njit(cache=True, error_model="numpy")
def _ring_within(body, n_body, ring, n_ring, reach, lo_x, hi_x, lo_y, hi_y):
    """Some edge of the closed ring lies within ``reach`` of the body's edges (its point when n_body = 1). An edge
    whose bounding box misses the body's box grown by ``reach`` ([lo_x, hi_x] × [lo_y, hi_y]) is farther than
    ``reach`` along one axis and is skipped."""
    for j in range(n_ring):
        ax = ring[j, 0]
        ay = ring[j, 1]
        bx = ring[(j + 1) % n_ring, 0]
        by = ring[(j + 1) % n_ring, 1]
        if max(ax, bx) < lo_x or min(ax, bx) > hi_x or max(ay, by) < lo_y or min(ay, by) > hi_y:
            continue
        if n_body == 1:
            if _seg_point_dist(ax, ay, bx, by, body[0, 0], body[0, 1])[0] <= reach:
                return True
            continue
        for i in range(n_body):
            i2 = (i + 1) % n_body
            if _seg_seg_dist(ax, ay, bx, by, body[i, 0], body[i, 1], body[i2, 0], body[i2, 1]) <= reach:
                return True
    return False


@njit(cache=True, error_model="numpy")
def body_clear(geo, k, body, n_body, margin, hit):
    """The body (rectangle corners ``body[:4]`` counter-clockwise, or the point ``body[0]``) inflated by ``margin``
    stays strictly inside scene k's boundary and off every obstacle (distance > margin + eps); else False with the
    first offender in ``hit``."""
    boundary, n_boundary, poly, poly_nv, n_poly, aabb, circle, n_circle = (geo[0], geo[1], geo[2], geo[3], geo[4],
                                                                           geo[5], geo[6], geo[7])
    reach = margin + EXACT_TOLERANCE_M
    for i in range(n_body):
        if point_in_polygon(body[i, 0], body[i, 1], boundary[k], n_boundary[k]) != INSIDE:
            return _flag(hit, KIND_BOUNDARY, 0, body[i, 0], body[i, 1])
    lo_x = body[:n_body, 0].min() - reach
    hi_x = body[:n_body, 0].max() + reach
    lo_y = body[:n_body, 1].min() - reach
    hi_y = body[:n_body, 1].max() + reach
    if _ring_within(body, n_body, boundary[k], n_boundary[k], reach, lo_x, hi_x, lo_y, hi_y):
        return _flag(hit, KIND_BOUNDARY, 0, body[0, 0], body[0, 1])
    for j in range(n_poly[k]):
        if aabb[k, j, 2] < lo_x or aabb[k, j, 0] > hi_x or aabb[k, j, 3] < lo_y or aabb[k, j, 1] > hi_y:
            continue
        ring = poly[k, j]
        nv = poly_nv[k, j]
        inside = point_in_polygon(body[0, 0], body[0, 1], ring, nv) != OUTSIDE
        if n_body > 1 and point_in_polygon(ring[0, 0], ring[0, 1], body, n_body) != OUTSIDE:
            inside = True
        if inside or _ring_within(body, n_body, ring, nv, reach, lo_x, hi_x, lo_y, hi_y):
            return _flag(hit, KIND_POLYGON, j, body[0, 0], body[0, 1])
    for j in range(n_circle[k]):
        ox = circle[k, j, 0]
        oy = circle[k, j, 1]
        if n_body == 1:
            dist = math.hypot(body[0, 0] - ox, body[0, 1] - oy)
        else:
            dist = _point_body_dist(ox, oy, body, n_body)
        if dist <= circle[k, j, 2] + reach:
            return _flag(hit, KIND_CIRCLE, j, ox, oy)
    return True


@njit(cache=True, error_model="numpy")
def _point_body_dist(px, py, body, n_body):
    """Distance from a point to the closed convex body (0 inside)."""
    if point_in_polygon(px, py, body, n_body) != OUTSIDE:
        return 0.0
    best = math.inf
    for i in range(n_body):
        i2 = (i + 1) % n_body
        best = min(best, _seg_point_dist(body[i, 0], body[i, 1], body[i2, 0], body[i2, 1], px, py)[0])
    return best


@njit(cache=True, error_model="numpy")
def _flag(hit, kind, index, px, py):
    """Write a violation into ``hit`` and return False (not clear)."""
    hit[0] = kind
    hit[1] = index
    hit[2] = px
    hit[3] = py
    return False


@njit(cache=True, error_model="numpy")
def _cubic_pose(c, t, reverse, footprint, local, body):
    """Place the body at parameter t of the cubic with monomial coefficients ``c`` (4, 2); returns |r'(t)|."""
    x = c[0, 0] + t * (c[1, 0] + t * (c[2, 0] + t * c[3, 0]))
    y = c[0, 1] + t * (c[1, 1] + t * (c[2, 1] + t * c[3, 1]))
    dx = c[1, 0] + t * (2.0 * c[2, 0] + 3.0 * t * c[3, 0])
    dy = c[1, 1] + t * (2.0 * c[2, 1] + 3.0 * t * c[3, 1])
    if footprint:
        th = math.atan2(dy, dx) + (math.pi if reverse else 0.0)
        footprint_corners(x, y, th, local, body)
    else:
        body[0, 0] = x
        body[0, 1] = y
    return math.hypot(dx, dy)


@njit(cache=True, error_model="numpy")
def hermite_contact(geo, k, c, reverse, footprint, local, max_pieces, hit):
    """First parameter t ∈ [0, 1] of a certified violation of the body moved along the cubic with monomial
    coefficients ``c`` (4, 2) (heading = tangent direction, + π when ``reverse``), or −1 when every piece is
    certified clear (module docstring). An undecided piece (``HERMITE_MAX_DEPTH`` bisections, or ``max_pieces``
    pieces in all) is a violation of kind KIND_UNDECIDED."""
    n_body = 4 if footprint else 1
    rho = 0.0
    if footprint:
        for i in range(4):
            rho = max(rho, math.hypot(local[i, 0], local[i, 1]))
    body = np.zeros((4, 2))
    stack = np.empty((HERMITE_MAX_DEPTH + 2, 3))
    stack[0, 0] = 0.0
    stack[0, 1] = 1.0
    stack[0, 2] = 0.0
    top = 1
    pieces = 0
    while top > 0:
        top -= 1
        t0 = stack[top, 0]
        t1 = stack[top, 1]
        depth = stack[top, 2]
        pieces += 1
        dt = t1 - t0
        tm = 0.5 * (t0 + t1)
        speed = _cubic_pose(c, tm, reverse, footprint, local, body)
        m2 = max(math.hypot(2.0 * c[2, 0] + 6.0 * t0 * c[3, 0], 2.0 * c[2, 1] + 6.0 * t0 * c[3, 1]),
                 math.hypot(2.0 * c[2, 0] + 6.0 * t1 * c[3, 0], 2.0 * c[2, 1] + 6.0 * t1 * c[3, 1]))
        low = speed - 0.5 * m2 * dt
        turn = 2.0 * rho if low <= 0.0 else min(rho * dt * m2 / low, 2.0 * rho)
        margin = dt * (speed + 0.5 * m2 * dt) + turn
        _cubic_pose(c, t0, reverse, footprint, local, body)
        if body_clear(geo, k, body, n_body, margin, hit):
            continue
        if margin <= EXACT_TOLERANCE_M or not body_clear(geo, k, body, n_body, 0.0, hit):
            return t0
        if depth >= HERMITE_MAX_DEPTH or pieces >= max_pieces:
            return _flag_t(hit, t0, body)
        stack[top, 0] = tm
        stack[top, 1] = t1
        stack[top, 2] = depth + 1.0
        stack[top + 1, 0] = t0
        stack[top + 1, 1] = tm
        stack[top + 1, 2] = depth + 1.0
        top += 2
    return -1.0


@njit(cache=True, error_model="numpy")
def _flag_t(hit, t, body):
    """Mark an undecided Hermite piece starting at t; returns t."""
    _flag(hit, KIND_UNDECIDED, -1, body[0, 0], body[0, 1])
    return t


@njit(cache=True, error_model="numpy")
def first_invalid_pose(geo, k, poses, footprint, local):
    """Index of the first pose row (x, y, θ) that the env's sampled check (``pose_valid``) rejects, or −1."""
    corners = np.empty((4, 2))
    for i in range(poses.shape[0]):
        if not pose_valid(geo, k, poses[i, 0], poses[i, 1], poses[i, 2], footprint, local, corners):
            return i
    return -1
