"""Convex pieces of scene geometry for MuJoCo, whose mesh collisions use convex hulls.

A convex obstacle polygon is one piece; a non-convex one is split into the triangles of its constrained Delaunay
triangulation (exact: the triangles tile the polygon). Boundary walls are built per boundary edge outside the
boundary: the edge's outward rectangle of the wall thickness minus the boundary polygon's interior, so no wall piece
enters the free space even at sharp reflex corners.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

_AREA_EPS_M2 = 1e-9
"""Pieces of smaller area are slivers of floating-point set operations, not geometry."""


def _is_ccw(points: np.ndarray) -> bool:
    """True when the ring is counter-clockwise (shoelace signed area > 0)."""
    x, y = points[:, 0], points[:, 1]
    return bool(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0)


def _ccw(points: np.ndarray) -> np.ndarray:
    """The ring in counter-clockwise order."""
    return points if _is_ccw(points) else points[::-1]


def _pieces_of(shape) -> list[np.ndarray]:
    """Convex pieces (CCW (k, 2) rings) tiling a shapely Polygon or MultiPolygon."""
    out = []
    for poly in getattr(shape, "geoms", [shape]):
        if poly.is_empty or poly.area < _AREA_EPS_M2:
            continue
        if poly.area >= poly.convex_hull.area * (1 - 1e-12):
            out.append(_ccw(np.asarray(poly.exterior.coords)[:-1]))
            continue
        for tri in shapely.constrained_delaunay_triangles(poly).geoms:
            if tri.area >= _AREA_EPS_M2:
                out.append(_ccw(np.asarray(tri.exterior.coords)[:-1]))
    return out


def convex_pieces(polygon) -> list[np.ndarray]:
    """Convex pieces (CCW (k, 2) rings) whose union is the simple polygon ``polygon`` ((n, 2) vertices)."""
    return _pieces_of(Polygon(np.asarray(polygon, dtype=float)))


def wall_pieces(boundary, thickness_m: float) -> list[tuple[int, np.ndarray]]:
    """(edge index, convex piece) of the walls outside ``boundary``: per edge i (vertex i → i+1), the rectangle
    of depth ``thickness_m`` on the outer side of the edge, minus the boundary's interior."""
    given = np.asarray(boundary, dtype=float)
    reversed_ring = not _is_ccw(given)  # edge indices refer to the boundary as given
    ring = given[::-1] if reversed_ring else given
    inside = Polygon(ring)
    out = []
    n = len(ring)
    for k in range(n):
        a, b = ring[k], ring[(k + 1) % n]
        tangent = (b - a) / np.linalg.norm(b - a)
        outward = np.array([tangent[1], -tangent[0]])  # right of a CCW edge
        rect = Polygon([a, b, b + thickness_m * outward, a + thickness_m * outward])
        edge = (n - 2 - k) % n if reversed_ring else k
        out.extend((edge, piece) for piece in _pieces_of(rect.difference(inside)))
    return out
