"""The obstacle-aware holonomic heuristic of Hybrid A* (Dolgov et al. 2010, §III "2D holonomic-with-obstacles").

A square grid over the boundary's bounding box; a cell is *free* when the reference point is valid (spec §2
reference-point convention) at its centre — a footprint-valid pose has a valid reference point, so one grid serves
both conventions. Free cells connect to their eight neighbours; Dijkstra from the goal's cell gives each cell its
shortest grid distance (m) to the goal, ``inf`` where none exists. The Dijkstra is lazy: it runs only until the
cells a search asks for are settled, and resumes on the next ask (a search near the goal never pays for the far
corners of a large site); the distances are bit for bit those of a run to the end. Walls thinner than a cell can
fall between cell centres and leak; the default cell (0.25 m) is below every wall thickness of the shipped benchmarks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from np_sim.kernels.geometry import INSIDE, OUTSIDE, point_in_polygon
from np_sim.planners.heap import heap_pop, heap_push


@dataclass(frozen=True, eq=False)
class HolonomicGrid:
    """Grid distances to one goal position."""

    origin: np.ndarray
    """(2,) world position of cell (0, 0)'s centre (m)."""
    cell_m: float
    """Cell size (m)."""
    state: tuple
    """The lazy Dijkstra to the goal's cell (``lazy_grid``); ``grid_distance`` reads a cell's shortest
    8-connected grid distance (m) from it, inf where unreachable."""


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
def _cell_span(lo: float, hi: float, origin: float, cell_m: float, n: int) -> tuple[int, int]:
    """Index range [first, last) of the cells whose centre may lie in [lo, hi] (one cell of slack each side)."""
    first = max(int(math.floor((lo - origin) / cell_m)) - 1, 0)
    last = min(int(math.ceil((hi - origin) / cell_m)) + 2, n)
    return first, last


@njit(cache=True, error_model="numpy")
def free_cells_inside(geo, inside: np.ndarray, origin_x: float, origin_y: float, cell_m: float) -> np.ndarray:
    """(ny, nx) bool: the reference point is valid at the cell's centre (``point_valid``), given its boundary half
    ``inside`` (``inside_cells``): each obstacle blocks the cells around it that its own test of
    ``point_clear_of_obstacles`` hits (its bounding box, then the polygon or disc), so the work is the obstacles'
    area rather than every cell times every obstacle. The per-obstacle test is written out here as in
    ``point_clear_of_obstacles``: moving it into a shared per-obstacle function made that hot kernel's reference-point
    checks slower (Hybrid A*'s median Factorial query 0.8–1.4 → 1.5–1.8 ms, beside training, 2026-12-07)."""
    ny, nx = inside.shape
    free = inside.copy()
    poly, poly_nv, n_poly, aabb, circle, n_circle = geo[2], geo[3], geo[4], geo[5], geo[6], geo[7]
    for j in range(n_poly[0]):
        r0, r1 = _cell_span(aabb[0, j, 1], aabb[0, j, 3], origin_y, cell_m, ny)
        c0, c1 = _cell_span(aabb[0, j, 0], aabb[0, j, 2], origin_x, cell_m, nx)
        for r in range(r0, r1):
            py = origin_y + r * cell_m
            for c in range(c0, c1):
                px = origin_x + c * cell_m
                if (not free[r, c] or px < aabb[0, j, 0] or px > aabb[0, j, 2] or py < aabb[0, j, 1]
                        or py > aabb[0, j, 3]):
                    continue
                free[r, c] = point_in_polygon(px, py, poly[0, j], poly_nv[0, j]) == OUTSIDE
    for j in range(n_circle[0]):
        cx, cy, radius = circle[0, j, 0], circle[0, j, 1], circle[0, j, 2]
        r0, r1 = _cell_span(cy - radius, cy + radius, origin_y, cell_m, ny)
        c0, c1 = _cell_span(cx - radius, cx + radius, origin_x, cell_m, nx)
        for r in range(r0, r1):
            for c in range(c0, c1):
                dx, dy = origin_x + c * cell_m - cx, origin_y + r * cell_m - cy
                if dx * dx + dy * dy <= radius * radius:
                    free[r, c] = False
    return free


BOUNDARY_CELLS_KEPT = 8
"""Boundary masks ``boundary_cells`` keeps (a site's clips share one boundary, replanned in every frame)."""
_boundary_cells: dict[tuple, np.ndarray] = {}


def boundary_cells(boundary: np.ndarray, origin_x: float, origin_y: float, cell_m: float, nx: int,
                   ny: int) -> np.ndarray:
    """``inside_cells`` of ``boundary`` (its n × 2 vertices) on this grid, computed once per boundary and grid: the
    boundary test is most of the free-cell work on a site lot, whose boundary stays while its objects move."""
    verts = np.array(boundary, dtype=float, order="C")  # writeable: numba compiles a read-only array apart
    key = (verts.tobytes(), len(verts), origin_x, origin_y, cell_m, nx, ny)
    mask = _boundary_cells.get(key)
    if mask is None:
        mask = inside_cells(verts, len(verts), origin_x, origin_y, cell_m, nx, ny)
        if len(_boundary_cells) >= BOUNDARY_CELLS_KEPT:
            _boundary_cells.pop(next(iter(_boundary_cells)))
        _boundary_cells[key] = mask
    return mask


SETTLED = 1
"""Bit of the ``status`` array of ``lazy_grid``: the cell was popped from the queue, its ``dist`` is final."""
KNOWN = 2
"""Bit of the ``status`` array of ``lazy_grid``: the cell's heuristic value ``out`` is computed."""


def lazy_grid(free: np.ndarray, goal_row: int, goal_col: int) -> tuple:
    """The state of a Dijkstra from the goal cell over ``free`` that runs only as far as the queries need:
    (free, dist, out, status, heap keys, heap ids, [heap size, goal row, goal col]); ``grid_distance`` reads it."""
    ny, nx = free.shape
    dist = np.full((ny, nx), np.inf)
    dist[goal_row, goal_col] = 0.0
    keys, ids = np.empty(8 * ny * nx + 1), np.empty(8 * ny * nx + 1, np.int64)
    keys[0], ids[0] = 0.0, goal_row * nx + goal_col
    meta = np.array([1, goal_row, goal_col], np.int64)
    return (np.ascontiguousarray(free, np.bool_), dist, np.full((ny, nx), np.inf), np.zeros((ny, nx), np.int8),
            keys, ids, meta)


@njit(cache=True, error_model="numpy")
def settle(grid, cell_m: float, row: int, col: int) -> None:
    """Pop Dijkstra's queue until cell (row, col) is settled or the queue is empty (then it is unreachable).

    Straight steps cost one cell, diagonal steps √2 cells and need both orthogonal neighbours free (no cutting
    through a wall's corner). Every call continues the same pop order, so a settled distance is the one a
    Dijkstra run to the end gives, bit for bit.
    """
    free, dist, _, status, keys, ids, meta = grid
    ny, nx = free.shape
    diag = math.sqrt(2.0) * cell_m
    size = meta[0]
    while size > 0 and not status[row, col] & SETTLED:
        d, idx, size = heap_pop(keys, ids, size)
        r, c = idx // nx, idx % nx
        if d > dist[r, c]:
            continue
        status[r, c] |= SETTLED
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
    meta[0] = size


@njit(cache=True, error_model="numpy", inline="always")
def grid_distance(grid, cell_m: float, row: int, col: int) -> float:
    """Grid distance (m) from cell (row, col) to the goal cell (always treated as free); ``inf`` where none exists.

    A free cell's is its Dijkstra distance. A blocked cell takes the smallest distance of its free neighbours plus
    the step to it, so that a valid pose whose cell centre is blocked (beside a wall) still gets a finite estimate.
    Computed on the first query (``settle``), then kept; the kept value is read inline in the caller, which is
    most of a search's lookups.
    """
    if grid[3][row, col] & KNOWN:
        return grid[2][row, col]
    return _first_distance(grid, cell_m, row, col)


@njit(cache=True, error_model="numpy")
def _first_distance(grid, cell_m: float, row: int, col: int) -> float:
    """``grid_distance`` of a cell not yet known: settles what it needs, then keeps the value."""
    free, dist, out, status, _, _, meta = grid
    ny, nx = free.shape
    value = math.inf
    if free[row, col] or (row == meta[1] and col == meta[2]):
        settle(grid, cell_m, row, col)
        value = dist[row, col]
    else:
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                rr, cc = row + dr, col + dc
                if 0 <= rr < ny and 0 <= cc < nx and free[rr, cc]:
                    settle(grid, cell_m, rr, cc)
                    value = min(value, dist[rr, cc] + (math.sqrt(2.0) * cell_m if dr != 0 and dc != 0 else cell_m))
    out[row, col] = value
    status[row, col] |= KNOWN
    return value


@njit(cache=True, error_model="numpy")
def _all_distances(grid, cell_m: float) -> np.ndarray:
    ny, nx = grid[0].shape
    out = np.empty((ny, nx))
    for r in range(ny):
        for c in range(nx):
            out[r, c] = grid_distance(grid, cell_m, r, c)
    return out


def grid_dijkstra(free: np.ndarray, goal_row: int, goal_col: int, cell_m: float) -> np.ndarray:
    """(ny, nx) ``grid_distance`` of every cell: the Dijkstra run to the end."""
    return _all_distances(lazy_grid(free, goal_row, goal_col), float(cell_m))


def holonomic_grid(geo, boundary: np.ndarray, goal_xy, cell_m: float) -> HolonomicGrid:
    """The grid over ``boundary``'s bounding box with its free cells (packed scene ``geo``) and a lazy Dijkstra
    from ``goal_xy``'s cell: each cell's distance is computed when the search first asks for it."""
    lo, hi = boundary.min(axis=0), boundary.max(axis=0)
    nx = int(math.floor((hi[0] - lo[0]) / cell_m)) + 1
    ny = int(math.floor((hi[1] - lo[1]) / cell_m)) + 1
    inside = boundary_cells(geo[0][0][:geo[1][0]], float(lo[0]), float(lo[1]), float(cell_m), nx, ny)
    free = free_cells_inside(geo, inside, float(lo[0]), float(lo[1]), float(cell_m))
    col = min(max(int(math.floor((goal_xy[0] - lo[0]) / cell_m + 0.5)), 0), nx - 1)
    row = min(max(int(math.floor((goal_xy[1] - lo[1]) / cell_m + 0.5)), 0), ny - 1)
    return HolonomicGrid(lo.astype(float), float(cell_m), lazy_grid(free, row, col))
