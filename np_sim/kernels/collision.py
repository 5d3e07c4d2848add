"""Compiled collision checks of poses against a packed scene (``SceneArrays.geometry``, scene index ``k``).

Two conventions (spec §2):

* reference point: the point is strictly inside the boundary and strictly outside every obstacle
  (a point on an edge or on a circle is a collision);
* footprint: the closed vehicle rectangle lies strictly inside the boundary and shares no point with any
  obstacle.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from np_sim.kernels.kinematics import arc_point
from np_sim.kernels.geometry import (
    INSIDE,
    OUTSIDE,
    footprint_corners,
    polygon_edges_cross,
    polygons_overlap,
    point_in_polygon,
    rect_circle_overlap,
    segments_intersect,
)


@njit(cache=True, error_model="numpy", inline="always")
def point_valid(geo, k: int, px: float, py: float) -> bool:
    """Reference-point convention for one point of scene k."""
    if point_in_polygon(px, py, geo[0][k], geo[1][k]) != INSIDE:
        return False
    return point_clear_of_obstacles(geo, k, px, py)


@njit(cache=True, error_model="numpy", inline="always")
def point_clear_of_obstacles(geo, k: int, px: float, py: float) -> bool:
    """The obstacle half of ``point_valid``: the point is strictly outside every obstacle of scene k."""
    poly, poly_nv, n_poly, aabb, circle, n_circle = geo[2], geo[3], geo[4], geo[5], geo[6], geo[7]
    for j in range(n_poly[k]):
        if px < aabb[k, j, 0] or px > aabb[k, j, 2] or py < aabb[k, j, 1] or py > aabb[k, j, 3]:
            continue
        if point_in_polygon(px, py, poly[k, j], poly_nv[k, j]) != OUTSIDE:
            return False
    for j in range(n_circle[k]):
        dx = px - circle[k, j, 0]
        dy = py - circle[k, j, 1]
        if dx * dx + dy * dy <= circle[k, j, 2] * circle[k, j, 2]:
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _corner_box(corners: np.ndarray) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) of the rectangle's four corners ``corners`` (4, 2)."""
    return (min(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0]),
            max(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0]),
            min(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1]),
            max(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1]))


@njit(cache=True, error_model="numpy")
def rect_inside_boundary(corners: np.ndarray, verts: np.ndarray, n: int) -> bool:
    """The closed rectangle ``corners`` (4, 2) lies strictly inside the simple polygon ``verts[:n]``: every corner
    INSIDE and no rectangle edge touching a polygon edge.

    When no polygon edge's bounding box meets the rectangle's (closed boxes), no polygon edge can touch the
    rectangle, so the rectangle (connected) lies wholly inside or wholly outside and its first corner's
    point-in-polygon test decides (exact); otherwise every corner and every pair of edges is tested."""
    xmin, xmax, ymin, ymax = _corner_box(corners)
    near = False
    j = n - 1
    for i in range(n):
        if (max(verts[i, 0], verts[j, 0]) >= xmin and min(verts[i, 0], verts[j, 0]) <= xmax
                and max(verts[i, 1], verts[j, 1]) >= ymin and min(verts[i, 1], verts[j, 1]) <= ymax):
            near = True
            break
        j = i
    if not near:
        return point_in_polygon(corners[0, 0], corners[0, 1], verts, n) == INSIDE
    for i in range(4):
        if point_in_polygon(corners[i, 0], corners[i, 1], verts, n) != INSIDE:
            return False
    return not polygon_edges_cross(corners, 4, verts, n)


@njit(cache=True, error_model="numpy", inline="always")
def footprint_valid(geo, k: int, x: float, y: float, th: float, local: np.ndarray, corners: np.ndarray) -> bool:
    """Footprint convention for the vehicle rectangle ``local`` (4, 2) at pose (x, y, θ); ``corners`` is scratch."""
    boundary, n_boundary, poly, poly_nv = geo[0], geo[1], geo[2], geo[3]
    n_poly, aabb, circle, n_circle = geo[4], geo[5], geo[6], geo[7]
    footprint_corners(x, y, th, local, corners)
    if not rect_inside_boundary(corners, boundary[k], n_boundary[k]):
        return False
    xmin, xmax, ymin, ymax = _corner_box(corners)
    for j in range(n_poly[k]):
        if xmax < aabb[k, j, 0] or xmin > aabb[k, j, 2] or ymax < aabb[k, j, 1] or ymin > aabb[k, j, 3]:
            continue
        if polygons_overlap(corners, 4, poly[k, j], poly_nv[k, j]):
            return False
    for j in range(n_circle[k]):
        if rect_circle_overlap(x, y, th, local, circle[k, j, 0], circle[k, j, 1], circle[k, j, 2]):
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def pose_valid(geo, k: int, x: float, y: float, th: float, footprint: bool, local: np.ndarray,
               corners: np.ndarray) -> bool:
    """One pose under the chosen convention (``footprint`` False = reference point)."""
    if footprint:
        return footprint_valid(geo, k, x, y, th, local, corners)
    return point_valid(geo, k, x, y)


@njit(cache=True, error_model="numpy")
def poses_valid(geo, k: int, poses: np.ndarray, footprint: bool, local: np.ndarray) -> bool:
    """Every row (x, y, θ) of ``poses`` is valid under the chosen convention; stops at the first invalid one. The
    footprint convention checks the rows in chunks (``footprints_valid``)."""
    if footprint:
        return footprints_valid(geo, k, poses, local)
    corners = np.empty((4, 2))
    for i in range(poses.shape[0]):
        if not pose_valid(geo, k, poses[i, 0], poses[i, 1], poses[i, 2], footprint, local, corners):
            return False
    return True


CHUNK_POSES = 16
"""Poses per chunk of ``footprints_valid``: consecutive path samples a few centimetres apart share their nearby
edges."""
CHUNK_CLEARANCE_M = 1e-6
"""A boundary edge counts as near a chunk unless its box lies this far (m) outside the chunk's box, so that a chunk
far from every edge is classified by one point robustly (rounding in the crossing test is far below this)."""


@njit(cache=True, error_model="numpy")
def footprints_valid(geo, k: int, poses: np.ndarray, local: np.ndarray) -> bool:
    """The footprint convention (``footprint_valid``) at every row (x, y, θ) of ``poses``, the same verdict, checked
    in chunks of ``CHUNK_POSES``: only the boundary edges and obstacles whose boxes meet the chunk's box (its
    rectangles' corners) can touch a rectangle of the chunk, so each rectangle is tested against those alone; a
    chunk with no boundary edge near it lies wholly inside or wholly outside the boundary and one point decides."""
    verts, nb, poly, poly_nv, n_poly, aabb, circle, n_circle = (geo[0][k], geo[1][k], geo[2], geo[3], geo[4], geo[5],
                                                                geo[6], geo[7])
    rects = np.empty((CHUNK_POSES, 4, 2))
    edges = np.empty(nb, np.int64)
    near_poly = np.empty(max(n_poly[k], 1), np.int64)
    sub = np.empty((2, 2))
    for start in range(0, poses.shape[0], CHUNK_POSES):
        stop = min(poses.shape[0], start + CHUNK_POSES)
        box = _chunk_corners(poses, start, stop, local, rects)
        n_edges = _near_edges(verts, nb, box, CHUNK_CLEARANCE_M, edges)
        if n_edges == 0 and point_in_polygon(rects[0, 0, 0], rects[0, 0, 1], verts, nb) != INSIDE:
            return False
        n_near = 0
        for j in range(n_poly[k]):
            if not (box[2] < aabb[k, j, 0] or box[0] > aabb[k, j, 2] or box[3] < aabb[k, j, 1]
                    or box[1] > aabb[k, j, 3]):
                near_poly[n_near] = j
                n_near += 1
        for r in range(stop - start):
            corners = rects[r]
            if n_edges > 0 and not _rect_inside_near(corners, verts, nb, edges, n_edges, sub):
                return False
            if not _rect_clear(corners, poly[k], poly_nv[k], aabb[k], near_poly, n_near):
                return False
            i = start + r
            for j in range(n_circle[k]):
                if rect_circle_overlap(poses[i, 0], poses[i, 1], poses[i, 2], local, circle[k, j, 0], circle[k, j, 1],
                                       circle[k, j, 2]):
                    return False
    return True


@njit(cache=True, error_model="numpy")
def _chunk_corners(poses, start, stop, local, rects):
    """Corners of the rectangles at rows ``start:stop`` into ``rects``; returns their box (x0, y0, x1, y1)."""
    box = np.array([np.inf, np.inf, -np.inf, -np.inf])
    for r in range(stop - start):
        footprint_corners(poses[start + r, 0], poses[start + r, 1], poses[start + r, 2], local, rects[r])
        for c in range(4):
            box[0] = min(box[0], rects[r, c, 0])
            box[1] = min(box[1], rects[r, c, 1])
            box[2] = max(box[2], rects[r, c, 0])
            box[3] = max(box[3], rects[r, c, 1])
    return box


@njit(cache=True, error_model="numpy")
def _near_edges(verts, n, box, slack, out):
    """Indices j of the ring's edges (vertex j to j+1) whose box comes within ``slack`` of ``box``, into ``out``;
    returns their count."""
    count = 0
    j = n - 1
    for i in range(n):
        if not (max(verts[i, 0], verts[j, 0]) < box[0] - slack or min(verts[i, 0], verts[j, 0]) > box[2] + slack
                or max(verts[i, 1], verts[j, 1]) < box[1] - slack or min(verts[i, 1], verts[j, 1]) > box[3] + slack):
            out[count] = j
            count += 1
        j = i
    return count


@njit(cache=True, error_model="numpy")
def _rect_inside_near(corners, verts, n, edges, n_edges, sub):
    """``rect_inside_boundary`` of the rectangle against the ring ``verts[:n]``, given the ring's edges ``edges`` that
    can meet the rectangle's box (the others cannot touch it); ``sub`` is scratch for one edge at a time."""
    xmin, xmax, ymin, ymax = _corner_box(corners)
    near = False
    for e in range(n_edges):
        j = edges[e]
        i = (j + 1) % n
        if (max(verts[i, 0], verts[j, 0]) >= xmin and min(verts[i, 0], verts[j, 0]) <= xmax
                and max(verts[i, 1], verts[j, 1]) >= ymin and min(verts[i, 1], verts[j, 1]) <= ymax):
            near = True
            break
    if not near:
        return point_in_polygon(corners[0, 0], corners[0, 1], verts, n) == INSIDE
    for c in range(4):
        if point_in_polygon(corners[c, 0], corners[c, 1], verts, n) != INSIDE:
            return False
    for e in range(n_edges):
        j = edges[e]
        sub[0] = verts[j]
        sub[1] = verts[(j + 1) % n]
        if _rect_touches_segment(corners, sub):
            return False
    return True


@njit(cache=True, error_model="numpy")
def _rect_touches_segment(corners, seg):
    """Some closed edge of the rectangle ``corners`` touches or crosses the closed segment ``seg`` (2, 2)."""
    for c in range(4):
        c2 = (c + 1) % 4
        if segments_intersect(corners[c, 0], corners[c, 1], corners[c2, 0], corners[c2, 1], seg[0, 0], seg[0, 1],
                              seg[1, 0], seg[1, 1]):
            return True
    return False


@njit(cache=True, error_model="numpy")
def _rect_clear(corners, polys, poly_nv, boxes, near, n_near):
    """The rectangle shares no point with the polygons ``near[:n_near]`` (``footprint_valid``'s obstacle test)."""
    xmin, xmax, ymin, ymax = _corner_box(corners)
    for e in range(n_near):
        j = near[e]
        if xmax < boxes[j, 0] or xmin > boxes[j, 2] or ymax < boxes[j, 1] or ymin > boxes[j, 3]:
            continue
        if polygons_overlap(corners, 4, polys[j], poly_nv[j]):
            return False
    return True


@njit(cache=True, error_model="numpy")
def arc_valid(geo, k: int, x: float, y: float, th: float, kappa: float, length: float, n_samples: int,
              footprint: bool, local: np.ndarray, corners: np.ndarray) -> bool:
    """The arc (κ, l) from (x, y, θ) checked at arc lengths l·j/n, j = 1..n (paper: n = 30, eq:arc), stopping at
    the first invalid sample."""
    for j in range(n_samples):
        px, py, pth = arc_point(x, y, th, kappa, length * (j + 1) / n_samples)
        if not pose_valid(geo, k, px, py, pth, footprint, local, corners):
            return False
    return True
