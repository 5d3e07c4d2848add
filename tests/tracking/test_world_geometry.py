"""tracking.geometry: convex pieces tile obstacles; walls stay outside the boundary."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from tracking.geometry import convex_pieces, wall_pieces


def _star(seed: int, n: int) -> np.ndarray:
    """A seeded random star-shaped (simple, generally non-convex) polygon."""
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * np.pi, n))
    radii = rng.uniform(1.0, 4.0, n)
    return np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.integers(4, 12))
def test_convex_pieces_tile_the_polygon(seed, n):
    ring = _star(seed, n)
    poly = Polygon(ring)
    if not poly.is_valid or poly.area < 0.5:
        return
    pieces = [Polygon(p) for p in convex_pieces(ring)]
    for p in pieces:
        assert p.area >= p.convex_hull.area * (1 - 1e-9)
    assert abs(sum(p.area for p in pieces) - poly.area) < 1e-9 * max(1.0, poly.area)
    assert unary_union(pieces).symmetric_difference(poly).area < 1e-7


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.integers(4, 12), st.booleans())
def test_walls_cover_every_edge_from_outside_and_never_enter(seed, n, clockwise):
    ring = _star(seed, n)
    ring = ring[::-1] if clockwise else ring
    inside = Polygon(ring)
    if not inside.is_valid:
        return
    walls = wall_pieces(ring, 0.5)
    union = unary_union([Polygon(p) for _, p in walls])
    assert union.intersection(inside).area < 1e-7
    for e in range(n):
        a, b = ring[e], ring[(e + 1) % n]
        mid = 0.5 * (a + b)
        mine = unary_union([Polygon(p) for edge, p in walls if edge == e])
        assert mine.distance(Point(mid)) < 1e-6  # the edge's own wall touches its midpoint
