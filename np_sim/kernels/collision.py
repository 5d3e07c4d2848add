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


@njit(cache=True, error_model="numpy")
def rect_inside_boundary(corners: np.ndarray, verts: np.ndarray, n: int) -> bool:
    """The closed rectangle ``corners`` (4, 2) lies strictly inside the simple polygon ``verts[:n]``: every corner
    INSIDE and no rectangle edge touching a polygon edge.

    When no polygon edge's bounding box meets the rectangle's (closed boxes), no polygon edge can touch the
    rectangle, so the rectangle (connected) lies wholly inside or wholly outside and its first corner's
    point-in-polygon test decides (exact); otherwise every corner and every pair of edges is tested."""
    xmin = min(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0])
    xmax = max(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0])
    ymin = min(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1])
    ymax = max(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1])
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
    boundary, n_boundary, poly, poly_nv, n_poly, aabb, circle, n_circle = geo[0], geo[1], geo[2], geo[3], geo[4], geo[5], geo[6], geo[7]
    footprint_corners(x, y, th, local, corners)
    if not rect_inside_boundary(corners, boundary[k], n_boundary[k]):
        return False
    xmin = min(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0])
    xmax = max(corners[0, 0], corners[1, 0], corners[2, 0], corners[3, 0])
    ymin = min(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1])
    ymax = max(corners[0, 1], corners[1, 1], corners[2, 1], corners[3, 1])
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
    """Every row (x, y, θ) of ``poses`` is valid under the chosen convention; stops at the first invalid one."""
    corners = np.empty((4, 2))
    for i in range(poses.shape[0]):
        if not pose_valid(geo, k, poses[i, 0], poses[i, 1], poses[i, 2], footprint, local, corners):
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
