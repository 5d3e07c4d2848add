"""The obstacle-aware holonomic heuristic of Hybrid A* (Dolgov et al. 2010, §III "2D holonomic-with-obstacles").

A square grid over the boundary's bounding box; a cell is *free* when the reference point is valid (spec §2
reference-point convention) at its centre — a footprint-valid pose has a valid reference point, so one grid serves
both conventions. Free cells connect to their eight neighbours; Dijkstra from the goal's cell gives each cell its
shortest grid distance (m) to the goal, ``inf`` where none exists. Walls thinner than a cell can fall between
cell centres and leak; the default cell (0.25 m) is below every wall thickness of the shipped benchmarks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from np_sim.kernels.collision import point_clear_of_obstacles
from np_sim.kernels.geometry import INSIDE, point_in_polygon
from np_sim.planners.heap import heap_pop, heap_push


@dataclass(frozen=True, eq=False)
class HolonomicGrid:
    """Grid distances to one goal position."""

    origin: np.ndarray
    """(2,) world position of cell (0, 0)'s centre (m)."""
    cell_m: float
    """Cell size (m)."""
    distance: np.ndarray
    """(ny, nx) shortest 8-connected grid distance to the goal's cell (m); inf where unreachable."""


@njit(cache=True, error_model="numpy")
def inside_cells(boundary: np.ndarray, n: int, origin_x: float, origin_y: float, cell_m: float, nx: int,
                 ny: int) -> np.ndarray:
    """(ny, nx) bool: the cell's centre is strictly inside the boundary polygon ``boundary[:n]`` (``point_valid``'s
    boundary half)."""
    inside = np.zeros((ny, nx), np.bool_)
    for r in range(ny):
        for c in range(nx):
            inside[r, c] = point_in_polygon(origin_x + c * cell_m, origin_y + r * cell_m, boundary, n) == INSIDE
    return inside


@njit(cache=True, error_model="numpy")
def free_cells_inside(geo, inside: np.ndarray, origin_x: float, origin_y: float, cell_m: float) -> np.ndarray:
    """(ny, nx) bool: the reference point is valid at the cell's centre (``point_valid``), given its boundary half
    ``inside`` (``inside_cells``): only the obstacles are tested here."""
    ny, nx = inside.shape
    free = np.zeros((ny, nx), np.bool_)
    for r in range(ny):
        for c in range(nx):
            free[r, c] = inside[r, c] and point_clear_of_obstacles(geo, 0, origin_x + c * cell_m, origin_y + r * cell_m)
    return free


BOUNDARY_CELLS_KEPT = 8
"""Boundary masks ``boundary_cells`` keeps (a site's clips share one boundary, replanned in every frame)."""
_boundary_cells: dict[tuple, np.ndarray] = {}


def boundary_cells(boundary: np.ndarray, origin_x: float, origin_y: float, cell_m: float, nx: int,
                   ny: int) -> np.ndarray:
    """``inside_cells`` of ``boundary`` (its n × 2 vertices) on this grid, computed once per boundary and grid: the
    boundary test is most of the free-cell work on a site lot, whose boundary stays while its objects move."""
    verts = np.ascontiguousarray(boundary, dtype=float)
    key = (verts.tobytes(), len(verts), origin_x, origin_y, cell_m, nx, ny)
    mask = _boundary_cells.get(key)
    if mask is None:
        mask = inside_cells(verts, len(verts), origin_x, origin_y, cell_m, nx, ny)
        if len(_boundary_cells) >= BOUNDARY_CELLS_KEPT:
            _boundary_cells.pop(next(iter(_boundary_cells)))
        _boundary_cells[key] = mask
    return mask


@njit(cache=True, error_model="numpy")
def grid_dijkstra(free: np.ndarray, goal_row: int, goal_col: int, cell_m: float) -> np.ndarray:
    """Dijkstra distances (m) over free cells from the goal cell (always treated as free).

    Straight steps cost one cell, diagonal steps √2 cells and need both orthogonal neighbours free (no cutting
    through a wall's corner). A blocked cell then takes the smallest distance of its free neighbours plus the
    step to it, so that a valid pose whose cell centre is blocked (beside a wall) still gets a finite estimate.
    """
    ny, nx = free.shape
    dist = np.full((ny, nx), np.inf)
    dist[goal_row, goal_col] = 0.0
    keys = np.empty(8 * ny * nx + 1)
    ids = np.empty(8 * ny * nx + 1, np.int64)
    size = heap_push(keys, ids, 0, 0.0, goal_row * nx + goal_col)
    diag = math.sqrt(2.0) * cell_m
    while size > 0:
        d, idx, size = heap_pop(keys, ids, size)
        r, c = idx // nx, idx % nx
        if d > dist[r, c]:
            continue
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                if dr == 0 and dc == 0:
                    continue
                rr, cc = r + dr, c + dc
                if rr < 0 or rr >= ny or cc < 0 or cc >= nx or not free[rr, cc]:
                    continue
                if dr != 0 and dc != 0 and not (free[r + dr, c] and free[r, c + dc]):
                    continue
                nd = d + (diag if dr != 0 and dc != 0 else cell_m)
                if nd < dist[rr, cc]:
                    dist[rr, cc] = nd
                    size = heap_push(keys, ids, size, nd, rr * nx + cc)
    out = dist.copy()
    for r in range(ny):
        for c in range(nx):
            if free[r, c] or (r == goal_row and c == goal_col):
                continue
            for dr in range(-1, 2):
                for dc in range(-1, 2):
                    rr, cc = r + dr, c + dc
                    if 0 <= rr < ny and 0 <= cc < nx and free[rr, cc]:
                        out[r, c] = min(out[r, c], dist[rr, cc] + (diag if dr != 0 and dc != 0 else cell_m))
    return out


def holonomic_grid(geo, boundary: np.ndarray, goal_xy, cell_m: float) -> HolonomicGrid:
    """Build the grid over ``boundary``'s bounding box and its distances to ``goal_xy`` (packed scene ``geo``)."""
    lo, hi = boundary.min(axis=0), boundary.max(axis=0)
    nx = int(math.floor((hi[0] - lo[0]) / cell_m)) + 1
    ny = int(math.floor((hi[1] - lo[1]) / cell_m)) + 1
    inside = boundary_cells(geo[0][0][:geo[1][0]], float(lo[0]), float(lo[1]), float(cell_m), nx, ny)
    free = free_cells_inside(geo, inside, float(lo[0]), float(lo[1]), float(cell_m))
    col = min(max(int(math.floor((goal_xy[0] - lo[0]) / cell_m + 0.5)), 0), nx - 1)
    row = min(max(int(math.floor((goal_xy[1] - lo[1]) / cell_m + 0.5)), 0), ny - 1)
    return HolonomicGrid(lo.astype(float), float(cell_m), grid_dijkstra(free, row, col, float(cell_m)))
