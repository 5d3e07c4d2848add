"""Compiled geometry kernels (np_sim.kernels.geometry) against shapely and against slow exact loops.

Most property tests draw coordinates on a dyadic grid (multiples of 2^-20, |v| <= 10; on-edge test points on the
2^-22 grid). On that grid every orientation/cross product the kernels form is computed *exactly* in float64
(differences need <= 27 bits, products <= 52, their difference <= 53), and the crossing-number abscissa is off by
less than 2^-48 while a point off an edge sits at least 2^-47 from it. So the kernels' zero-tolerance answers have
no rounding excuse there: they must agree with shapely's robust predicates *exactly*, touching and collinear cases
included. Generic (unsnapped) floats are covered separately, away from measure-zero ties.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, MultiLineString, Point, Polygon

from np_sim.kernels.geometry import (
    INSIDE,
    ON_EDGE,
    OUTSIDE,
    beam_direction,
    cast_beams,
    footprint_corners,
    point_in_polygon,
    polygons_overlap,
    ray_segment_distance,
    rect_circle_overlap,
    segments_intersect,
)
from np_sim.vehicle import VehicleSpec

PROPS = settings(
    max_examples=300,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow],
)
FEW = settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow],
)

GRIDS = [1.0, 0.25, 2.0**-10, 2.0**-20]  # all coarser than or equal to 2^-20: exact arithmetic (module docstring)


# ---------------------------------------------------------------------------------------------- strategies


def _grid_coord(g: float, lo: float = -8.0, hi: float = 8.0):
    return st.integers(int(math.ceil(lo / g)), int(math.floor(hi / g))).map(lambda i: i * g)


@st.composite
def grid_points(draw, g: float | None = None, lo: float = -8.0, hi: float = 8.0):
    g = draw(st.sampled_from(GRIDS)) if g is None else g
    return draw(_grid_coord(g, lo, hi)), draw(_grid_coord(g, lo, hi))


@st.composite
def grid_polygons(draw, convex: bool | None = None):
    """A simple polygon (3-8 vertices) with grid coordinates: star-shaped (random points sorted by angle around
    their mean) or convex (hull of random points). Returns (verts (n, 2) float array, shapely Polygon)."""
    g = draw(st.sampled_from(GRIDS))
    convex = draw(st.booleans()) if convex is None else convex
    n = draw(st.integers(3, 8 if not convex else 12))
    cx, cy = draw(st.floats(-3, 3)), draw(st.floats(-3, 3))
    scale = draw(st.floats(0.5, 4.5))
    raw = draw(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=n, max_size=n))
    pts = np.round((np.array([cx, cy]) + scale * np.array(raw)) / g) * g
    pts = np.clip(pts, -8.0, 8.0)
    if convex:
        hull = shapely.MultiPoint(pts).convex_hull
        assume(isinstance(hull, Polygon) and hull.area > 0)
        verts = np.array(hull.exterior.coords[:-1])
    else:
        mean = pts.mean(axis=0)
        order = np.argsort(np.arctan2(pts[:, 1] - mean[1], pts[:, 0] - mean[0]), kind="stable")
        verts = pts[order]
    assume(len(verts) >= 3 and len({tuple(v) for v in verts}) == len(verts))
    if draw(st.booleans()):
        verts = verts[::-1].copy()  # either orientation
    poly = Polygon(verts)
    assume(poly.is_valid and poly.area > 0)
    return np.ascontiguousarray(verts, dtype=float), poly


def star_polygon(rng: np.random.Generator, center, r_lo: float, r_hi: float, n: int) -> np.ndarray:
    """Star-shaped polygon: n sorted random angles (one per sector, jittered) and random radii; generic floats."""
    ang = 2.0 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n + rng.uniform(0, 2 * np.pi)
    rad = rng.uniform(r_lo, r_hi, n)
    return np.stack([center[0] + rad * np.cos(ang), center[1] + rad * np.sin(ang)], axis=1)


def classify_shapely(poly: Polygon, x: float, y: float) -> int:
    p = Point(x, y)
    if poly.contains(p):
        return INSIDE
    if not poly.intersects(p):
        return OUTSIDE
    return ON_EDGE


# ---------------------------------------------------------------------------------------------- point_in_polygon


@PROPS
@given(grid_polygons(), st.lists(grid_points(), min_size=1, max_size=20))
def test_point_in_polygon_matches_shapely_on_grid(polygon, points):
    verts, poly = polygon
    for x, y in points:
        got = point_in_polygon(x, y, verts, len(verts))
        assert got == classify_shapely(poly, x, y), (verts.tolist(), (x, y), got)


@PROPS
@given(grid_polygons(), st.data())
def test_point_in_polygon_on_edge_points_are_on_edge(polygon, data):
    """Vertices and the 1/4, 1/2, 3/4 points of every edge (exact on the 2^-22 grid) are ON_EDGE, as shapely says."""
    verts, poly = polygon
    n = len(verts)
    for i in range(n):
        a, b = verts[i], verts[(i + 1) % n]
        for j in range(4):
            q = a + (b - a) * (j / 4.0)
            assert poly.touches(Point(q)), (verts.tolist(), q)  # the point really is on the boundary
            assert point_in_polygon(q[0], q[1], verts, n) == ON_EDGE, (verts.tolist(), q.tolist())
    # points on the horizontal/vertical lines through vertices (the crossing-number's degenerate rows)
    k = data.draw(st.integers(0, n - 1))
    off = data.draw(st.floats(-9, 9).map(lambda v: round(v * 4) / 4))
    for x, y in ((verts[k, 0] + off, verts[k, 1]), (verts[k, 0], verts[k, 1] + off)):
        assert point_in_polygon(x, y, verts, n) == classify_shapely(poly, x, y), (verts.tolist(), (x, y))


def test_point_in_polygon_generic_floats_seeded():
    """Unsnapped star-shaped and convex polygons, 20 000 random points: classification equals shapely's; every
    vertex (and the midpoint of every axis-aligned edge) is ON_EDGE."""
    rng = np.random.default_rng(1234)
    for trial in range(100):
        n = int(rng.integers(3, 9))
        verts = star_polygon(rng, rng.uniform(-5, 5, 2), 0.3, 4.0, n)
        if trial % 2:
            verts = np.array(shapely.MultiPoint(verts).convex_hull.exterior.coords[:-1])
        if trial % 5 == 0:  # an axis-aligned rectangle with float corners
            x0, y0 = rng.uniform(-5, 5, 2)
            w, h = rng.uniform(0.1, 4, 2)
            verts = np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])
        poly = Polygon(verts)
        assert poly.is_valid
        n = len(verts)
        lo, hi = verts.min(axis=0) - 1.0, verts.max(axis=0) + 1.0
        pts = rng.uniform(lo, hi, (200, 2))
        got = np.array([point_in_polygon(x, y, verts, n) for x, y in pts])
        inside = shapely.contains_xy(poly, pts[:, 0], pts[:, 1])
        touching = shapely.intersects_xy(poly, pts[:, 0], pts[:, 1])
        want = np.where(inside, INSIDE, np.where(touching, ON_EDGE, OUTSIDE))
        np.testing.assert_array_equal(got, want)
        for i in range(n):
            a, b = verts[i], verts[(i + 1) % n]
            assert point_in_polygon(a[0], a[1], verts, n) == ON_EDGE
            if a[0] == b[0] or a[1] == b[1]:
                m = (a + b) / 2
                assert poly.touches(Point(m))
                assert point_in_polygon(m[0], m[1], verts, n) == ON_EDGE


def test_point_in_polygon_hand_cases():
    sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    assert point_in_polygon(1.0, 1.0, sq, 4) == INSIDE
    assert point_in_polygon(3.0, 1.0, sq, 4) == OUTSIDE
    assert point_in_polygon(-1.0, 0.0, sq, 4) == OUTSIDE  # on the bottom edge's line, left of it
    assert point_in_polygon(1.0, 0.0, sq, 4) == ON_EDGE
    assert point_in_polygon(2.0, 2.0, sq, 4) == ON_EDGE
    # padded vertex array: only verts[:n] count
    padded = np.vstack([sq, np.full((3, 2), 99.0)])
    assert point_in_polygon(1.0, 1.0, padded, 4) == INSIDE


# ---------------------------------------------------------------------------------------------- segments_intersect


def _seg_kernel(a, b, c, d) -> bool:
    return bool(segments_intersect(a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]))


def _seg_shapely(a, b, c, d) -> bool:
    return LineString([a, b]).intersects(LineString([c, d]))


@PROPS
@given(st.sampled_from(GRIDS).flatmap(lambda g: st.tuples(*[grid_points(g)] * 4)))
def test_segments_intersect_matches_shapely_on_grid(pts):
    a, b, c, d = (np.array(p) for p in pts)
    assume(not np.array_equal(a, b) and not np.array_equal(c, d))
    want = _seg_shapely(a, b, c, d)
    for args in ((a, b, c, d), (b, a, c, d), (c, d, a, b), (d, c, b, a)):  # symmetric in both senses
        assert _seg_kernel(*args) == want, (a.tolist(), b.tolist(), c.tolist(), d.tolist())


@PROPS
@given(grid_points(2.0**-20, -4, 4), grid_points(2.0**-20, -4, 4), st.integers(0, 4), grid_points(2.0**-20, -4, 4))
def test_segments_intersect_touching_point_on_segment(a, b, j, d):
    """c is exactly a, b, or the 1/4, 1/2, 3/4 point of a-b: the segments touch."""
    a, b, d = np.array(a), np.array(b), np.array(d)
    assume(not np.array_equal(a, b))
    c = a + (b - a) * (j / 4.0)
    assume(not np.array_equal(c, d))
    assert _seg_shapely(a, b, c, d)
    assert _seg_kernel(a, b, c, d) and _seg_kernel(c, d, a, b) and _seg_kernel(d, c, b, a)


@PROPS
@given(
    st.sampled_from(GRIDS[1:]).flatmap(lambda g: st.tuples(grid_points(g, -4, 4), grid_points(g, -4, 4))),
    st.integers(-8, 12),
    st.integers(-8, 12),
)
def test_segments_intersect_collinear_built_exactly(ab, s, t):
    """c, d = a + (b − a)·s/4, t/4: collinear overlap, containment, end-to-end touch (s or t in {0, 4}) or gap."""
    a, b = (np.array(p) for p in ab)
    assume(not np.array_equal(a, b) and s != t)
    c = a + (b - a) * (s / 4.0)
    d = a + (b - a) * (t / 4.0)
    overlap = max(min(s, t), 0) <= min(max(s, t), 4)
    assert _seg_shapely(a, b, c, d) == overlap
    assert _seg_kernel(a, b, c, d) == overlap and _seg_kernel(d, c, b, a) == overlap


def test_segments_intersect_hand_cases():
    assert _seg_kernel((0, 0), (2, 2), (0, 2), (2, 0))  # X crossing
    assert _seg_kernel((0, 0), (2, 0), (2, 0), (3, 5))  # shared endpoint
    assert _seg_kernel((0, 0), (2, 0), (1, 0), (1, 5))  # T junction
    assert not _seg_kernel((0, 0), (2, 0), (1, 1e-300), (1, 5))  # tiny gap is still a gap
    assert _seg_kernel((0, 0), (4, 0), (1, 0), (2, 0))  # collinear contained
    assert not _seg_kernel((0, 0), (1, 0), (2, 0), (3, 0))  # collinear gap
    assert not _seg_kernel((0, 0), (1, 1), (0, 1), (1, 2))  # parallel


# ---------------------------------------------------------------------------------------------- ray_segment_distance


def _exact_ray(o, dvec, p0, p1):
    """Exact rational (t, u, denom) of o + t·d = p0 + u·(p1 − p0) for the float inputs."""
    ox, oy, dx, dy = map(Fraction, (*o, *dvec))
    x0, y0, x1, y1 = map(Fraction, (*p0, *p1))
    ex, ey = x1 - x0, y1 - y0
    den = dx * ey - dy * ex
    if den == 0:
        return None, None, den
    px, py = x0 - ox, y0 - oy
    return (px * ey - py * ex) / den, (px * dy - py * dx) / den, den


coord = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


@PROPS
@given(st.tuples(coord, coord), st.floats(-math.pi, math.pi), st.tuples(coord, coord), st.tuples(coord, coord))
def test_ray_segment_distance_matches_shapely(o, ang, p0, p1):
    d = (math.cos(ang), math.sin(ang))
    t_ex, u_ex, den = _exact_ray(o, d, p0, p1)
    seg_len = math.dist(p0, p1)
    assume(seg_len > 1e-6)
    # stay away from measure-zero ties (ray through an endpoint, origin on the segment, grazing/parallel rays),
    # where the kernel and shapely legitimately differ by rounding
    assume(den is not None and abs(float(den)) > 1e-6 * seg_len)
    assume(abs(float(u_ex)) > 1e-9 and abs(float(u_ex) - 1) > 1e-9 and abs(float(t_ex)) > 1e-9)
    got = ray_segment_distance(o[0], o[1], d[0], d[1], p0[0], p0[1], p1[0], p1[1])
    far = (o[0] + 1e3 * d[0], o[1] + 1e3 * d[1])
    inter = LineString([o, far]).intersection(LineString([p0, p1]))
    if inter.is_empty:
        assert got == math.inf
        assert not (t_ex > 0 and 0 <= u_ex <= 1)
    else:
        want = Point(o).distance(inter)
        assert got == pytest.approx(want, rel=1e-9, abs=1e-12)
        assert got == pytest.approx(float(t_ex), rel=1e-12, abs=1e-15)


def test_ray_segment_distance_exact_bound_conventions():
    inf = math.inf
    assert ray_segment_distance(0, 0, 1, 0, 3, -1, 3, 1) == 3.0
    assert ray_segment_distance(0, 0, 1, 0, 3, 1, 3, -1) == 3.0  # either segment direction
    assert ray_segment_distance(0, 0, -1, 0, 3, -1, 3, 1) == inf  # behind the origin
    assert ray_segment_distance(0, 0, 1, 0, 3, 0, 3, 1) == 3.0  # through an endpoint (u = 0): exact bounds hit
    assert ray_segment_distance(0, 0, 1, 0, 3, -1, 3, 0) == 3.0  # through an endpoint (u = 1): exact bounds hit
    assert ray_segment_distance(0, 0, 1, 0, 0, -1, 0, 1) == inf  # origin on the segment (t = 0): strict miss
    assert ray_segment_distance(0, 0, 1, 0, 1, 0, 5, 0) == inf  # collinear: parallel rays never hit
    assert ray_segment_distance(0, 0, 1, 0, 1, 1, 5, 1) == inf  # parallel
    assert ray_segment_distance(1, 1, 0, 1, 0, 3, 2, 5) == 3.0  # x = 1 meets y = x + 3 at y = 4


# ---------------------------------------------------------------------------------------------- cast_beams


def brute_force_beams(ox, oy, heading, segs, n_beams, max_range):
    """Every beam against every segment with ray_segment_distance, no angular binning.

    Uses the same float inputs the kernel forms (segment endpoints shifted by the origin, beam direction as
    ``beam_direction`` rounds it: within 1e-15 of angle heading + 2πi/n, checked here), so the arrays must be
    bit-identical to cast_beams'."""
    step = 2.0 * math.pi / n_beams
    out = np.full(n_beams, max_range)
    for i in range(n_beams):
        dx, dy = beam_direction(heading, i, n_beams)
        ang = heading + i * step
        assert abs(dx - math.cos(ang)) <= 1e-14 and abs(dy - math.sin(ang)) <= 1e-14
        for k in range(len(segs)):
            x0, y0, x1, y1 = segs[k, 0] - ox, segs[k, 1] - oy, segs[k, 2] - ox, segs[k, 3] - oy
            t = ray_segment_distance(0.0, 0.0, dx, dy, x0, y0, x1, y1)
            if t < out[i]:
                out[i] = t
    return out


def shapely_beams(ox, oy, heading, segs, n_beams, max_range):
    """Nearest intersection of each ray LineString (length max_range) with the union of the segments."""
    lines = MultiLineString([[(s[0], s[1]), (s[2], s[3])] for s in segs])
    step = 2.0 * math.pi / n_beams
    origin = Point(ox, oy)
    out = np.full(n_beams, max_range)
    for i in range(n_beams):
        ang = heading + i * step
        ray = LineString([(ox, oy), (ox + max_range * math.cos(ang), oy + max_range * math.sin(ang))])
        inter = ray.intersection(lines)
        if not inter.is_empty:
            out[i] = origin.distance(inter)
    return out


def _run_cast(ox, oy, heading, segs, n_beams, max_range):
    out = np.full(n_beams, -1.0)
    padded = np.vstack([segs, np.full((2, 4), 1e6)])  # padding rows beyond n_segs must be ignored
    cast_beams(ox, oy, heading, padded, len(segs), n_beams, max_range, out)
    return out


def random_scene_segments(rng: np.random.Generator) -> np.ndarray:
    """Polygon rings, 16-gon rings and loose segments around the origin, some straddling the 10 m range."""
    rows = []
    for _ in range(int(rng.integers(1, 5))):
        v = star_polygon(rng, rng.uniform(-12, 12, 2), 0.3, 3.0, int(rng.integers(3, 9)))
        rows.append(np.concatenate([v, np.roll(v, -1, axis=0)], axis=1))
    for _ in range(int(rng.integers(0, 3))):
        c, r = rng.uniform(-10, 10, 2), rng.uniform(0.3, 2.0)
        a = 2 * np.pi * np.arange(16) / 16
        v = np.stack([c[0] + r * np.cos(a), c[1] + r * np.sin(a)], axis=1)
        rows.append(np.concatenate([v, np.roll(v, -1, axis=0)], axis=1))
    rows.append(rng.uniform(-14, 14, (int(rng.integers(1, 8)), 4)))
    # a segment straddling max_range and a boundary-like big ring
    a = rng.uniform(0, 2 * np.pi)
    rows.append(np.array([[8 * math.cos(a), 8 * math.sin(a), 12 * math.cos(a + 0.3), 12 * math.sin(a + 0.3)]]))
    b = star_polygon(rng, (0.0, 0.0), 9.0, 16.0, int(rng.integers(4, 11)))
    rows.append(np.concatenate([b, np.roll(b, -1, axis=0)], axis=1))
    return np.ascontiguousarray(np.concatenate(rows, axis=0))


def special_segments(heading: float, rng: np.random.Generator) -> np.ndarray:
    """Segments relative to the pose (origin at 0, 0): crossing the beam-0 direction, crossing the ±π direction
    (the atan2 wrap behind), wholly behind, spanning almost 180°, and long ones wrapping most of the circle."""
    c, s = math.cos(heading), math.sin(heading)

    def world(lx, ly):
        return c * lx - s * ly, s * lx + c * ly

    rows = []
    for lx0, ly0, lx1, ly1 in [
        (4.0, -1.5, 4.3, 1.7),  # straddles beam 0
        (-5.0, 1.0, -5.5, -1.2),  # straddles the backward direction (atan2 jumps at ±π)
        (-3.0, -0.2, -2.0, -4.0),  # behind and to the right
        (0.5, -0.01, -0.5, -0.012),  # just below the origin: subtends nearly 180°
        (6.0, 2.0, 6.0, 2.0 + rng.uniform(0.1, 3)),
        (-9.0, 9.5, 9.0, 9.5),  # long segment across the left
    ]:
        rows.append((*world(lx0, ly0), *world(lx1, ly1)))
    return np.array(rows)


@pytest.mark.parametrize("seed", range(12))
def test_cast_beams_equals_brute_force_and_shapely(seed):
    rng = np.random.default_rng(seed)
    segs = random_scene_segments(rng)
    for q in range(6):
        if q < 3:
            ox, oy = rng.uniform(-6, 6, 2)
        else:  # very near a segment: its point at parameter u, pushed off the line by 1e-9 .. 1e-4 m
            k = int(rng.integers(len(segs)))
            x0, y0, x1, y1 = segs[k]
            u = rng.uniform(0.05, 0.95)
            nx, ny = -(y1 - y0), x1 - x0
            eps = 10.0 ** rng.uniform(-9, -4) * rng.choice([-1.0, 1.0]) / math.hypot(nx, ny)
            ox, oy = x0 + u * (x1 - x0) + eps * nx, y0 + u * (y1 - y0) + eps * ny
        heading = float(rng.uniform(-3 * math.pi, 3 * math.pi)) if q % 2 else float(rng.uniform(-math.pi, math.pi))
        local = special_segments(heading, rng) + np.array([ox, oy, ox, oy])
        all_segs = np.ascontiguousarray(np.vstack([segs, local]))
        for n_beams, max_range in ((120, 10.0), (37, 15.0)):
            got = _run_cast(ox, oy, heading, all_segs, n_beams, max_range)
            ref = brute_force_beams(ox, oy, heading, all_segs, n_beams, max_range)
            np.testing.assert_array_equal(got, ref, err_msg=f"seed={seed} q={q} pose=({ox!r}, {oy!r}, {heading!r})")
            want = shapely_beams(ox, oy, heading, all_segs, n_beams, max_range)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-6,
                                       err_msg=f"seed={seed} q={q} pose=({ox!r}, {oy!r}, {heading!r})")


@settings(PROPS, max_examples=200)
@given(
    st.floats(-math.pi, math.pi),
    st.floats(-20, 20),
    st.floats(0.01, 3.0),
    st.floats(0.5, 12.0),
    st.floats(0.05, 6.0),
    st.integers(1, 130),
)
def test_cast_beams_single_segment_binning(heading, seg_dir, half_len, dist, extra, n_beams):
    """One segment at every angle relative to the heading (including across beam 0 and the ±π wrap) and any
    beam count: the binned kernel equals the brute-force loop bit for bit."""
    a = heading + seg_dir  # where the segment's centre lies (any multiple of 2π off the heading)
    cx, cy = dist * math.cos(a), dist * math.sin(a)
    tx, ty = -math.sin(a + extra), math.cos(a + extra)
    segs = np.array([[cx - half_len * tx, cy - half_len * ty, cx + half_len * tx, cy + half_len * ty]])
    got = _run_cast(0.0, 0.0, heading, segs, n_beams, 10.0)
    np.testing.assert_array_equal(got, brute_force_beams(0.0, 0.0, heading, segs, n_beams, 10.0))
    np.testing.assert_allclose(got, shapely_beams(0.0, 0.0, heading, segs, n_beams, 10.0), rtol=0, atol=1e-6)


def test_cast_beams_hand_case():
    """Wall x = 5, |y| <= 6, heading 0, 8 beams: beam 0 sees 5 m, the ±45° beams 5√2 m, the others nothing."""
    segs = np.array([[5.0, -6.0, 5.0, 6.0]])
    out = _run_cast(0.0, 0.0, 0.0, segs, 8, 10.0)
    assert out[0] == 5.0
    assert out[1] == pytest.approx(5.0 * math.sqrt(2.0), rel=1e-12)
    assert out[7] == pytest.approx(5.0 * math.sqrt(2.0), rel=1e-12)
    assert np.all(out[2:7] == 10.0)
    out = _run_cast(0.0, 0.0, math.pi / 2, segs, 8, 10.0)
    assert out[6] == 5.0  # heading +y: the wall straight right of it (x = 5) is beam 6 (−90°, counter-clockwise)
    assert out[0] == 10.0


# ---------------------------------------------------------------------------------------------- polygon / circle


def _overlap(a, b) -> bool:
    return bool(polygons_overlap(a, len(a), b, len(b)))


@PROPS
@given(grid_polygons(), grid_polygons())
def test_polygons_overlap_matches_shapely(pa, pb):
    (a, sa), (b, sb) = pa, pb
    want = sa.intersects(sb)
    assert _overlap(a, b) == want and _overlap(b, a) == want, (a.tolist(), b.tolist())


@PROPS
@given(grid_polygons(), st.integers(0, 7), st.integers(0, 7), st.sampled_from([-1.0, -0.5, 0.5, 1.0]))
def test_polygons_overlap_touching_copies(pa, i, j, flip):
    """b = a reflected/scaled about a vertex of a, pinned so that vertex j of b sits exactly on vertex i of a:
    the polygons at least touch (shapely agrees)."""
    a, sa = pa
    i %= len(a)
    j %= len(a)
    b = a[i] + flip * (a - a[j])  # exact on the grid (flip is a power of two or −1)
    sb = Polygon(b)
    assume(sb.is_valid)
    assert sa.intersects(sb)
    assert _overlap(a, b) and _overlap(b, a)


def test_polygons_overlap_hand_cases():
    big = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    small = np.array([[4.0, 4.0], [5.0, 4.0], [5.0, 5.0]])
    assert _overlap(big, small) and _overlap(small, big)  # containment, no edge contact
    assert _overlap(big, big + [10.0, 10.0])  # corner touch
    assert _overlap(big, big + [10.0, 3.0])  # edge touch
    assert not _overlap(big, big + [10.0 + 1e-12, 0.0])
    assert not _overlap(small, small + [5.0, 0.0])


def _rect_circle(pose, local, c, r) -> bool:
    return bool(rect_circle_overlap(pose[0], pose[1], pose[2], local, c[0], c[1], r))


@PROPS
@given(
    st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-4, 4)),
    st.tuples(st.floats(-12, 12), st.floats(-12, 12)),
    st.floats(0.01, 4.0),
)
def test_rect_circle_overlap_matches_shapely(pose, c, r):
    spec = VehicleSpec()
    rect = Polygon(spec.footprint(pose))
    dist = rect.distance(Point(c))
    assume(abs(dist - r) > 1e-9)  # exact ties are pinned below with dyadic sizes
    assert _rect_circle(pose, spec.footprint_local(), c, r) == (dist <= r)


def test_rect_circle_overlap_exact_touching():
    local = np.array([[-1.0, -1.0], [3.0, -1.0], [3.0, 1.0], [-1.0, 1.0]])
    pose = (2.0, -3.0, 0.0)  # world rectangle [1, 5] × [-4, -2]
    assert _rect_circle(pose, local, (7.0, -3.0), 2.0)  # tangent to the front edge: touching counts
    assert not _rect_circle(pose, local, (7.0, -3.0), 2.0 - 2.0**-40)
    assert _rect_circle(pose, local, (5.0 + 3.0, -2.0 + 4.0), 5.0)  # 3-4-5 to the front-left corner
    assert not _rect_circle(pose, local, (8.0, 2.0), 5.0 - 2.0**-40)
    assert _rect_circle(pose, local, (3.0, -3.0), 0.01)  # centre inside
    rect = Polygon([(1, -4), (5, -4), (5, -2), (1, -2)])
    assert rect.distance(Point(8, 2)) == 5.0 and rect.distance(Point(7, -3)) == 2.0


@FEW
@given(st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-10, 10)))
def test_footprint_corners_match_vehicle_spec(pose):
    spec = VehicleSpec()
    out = np.empty((4, 2))
    footprint_corners(pose[0], pose[1], pose[2], spec.footprint_local(), out)
    np.testing.assert_allclose(out, spec.footprint(pose), rtol=0, atol=1e-12)
