"""Compiled pieces of the planners against slow exact versions on seeded random inputs: the heap (vs heapq), the
guide distance (vs shapely), the holonomic grid Dijkstra (vs a plain-Python Dijkstra with the same step rules; its
lazy form vs the run to the end),
the free cells from a kept boundary mask (vs every cell's ``point_valid``) and the lattice binning (vs its
formula), and the open list's lower-bound key (vs the full heuristic)."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
from numba import njit
from shapely.geometry import LineString, Point

from clip_frames import first_frame  # tests/clip_frames.py
from np_sim.benchmarks import load_benchmark
from np_sim.planners.heap import heap_pop, heap_push
from np_sim.kernels.collision import point_valid
from np_sim.planners.heuristic import (boundary_cells, free_cells_inside, grid_dijkstra, grid_distance, holonomic_grid,
                                       lazy_grid)
from np_sim.planners.search_kernels import heuristic, heuristic_bound, lattice_cell, polyline_distance
from np_sim.scene_arrays import packed_scene


def test_heap_pops_in_heapq_order():
    rng = np.random.default_rng(0)
    keys, ids = np.empty(500), np.empty(500, np.int64)
    size, reference = 0, []
    for step in range(2000):
        if size < 500 and (size == 0 or rng.random() < 0.6):
            key = float(rng.integers(0, 50))  # many ties
            size = heap_push(keys, ids, size, key, step)
            heapq.heappush(reference, (key, step))
        else:
            key, item, size = heap_pop(keys, ids, size)
            want_key, _ = heapq.heappop(reference)
            assert key == want_key
    assert size == len(reference)


def test_polyline_distance_matches_shapely():
    rng = np.random.default_rng(1)
    for _ in range(300):
        pts = rng.uniform(-10, 10, (int(rng.integers(2, 8)), 2))
        q = rng.uniform(-15, 15, 2)
        assert polyline_distance(q[0], q[1], pts) == pytest.approx(LineString(pts).distance(Point(q)), abs=1e-12)
    assert polyline_distance(3.0, 4.0, np.zeros((1, 2))) == pytest.approx(5.0)


def _slow_dijkstra(free: np.ndarray, goal: tuple[int, int], cell: float) -> np.ndarray:
    ny, nx = free.shape
    dist = {goal: 0.0}
    queue = [(0.0, goal)]
    while queue:
        d, (r, c) = heapq.heappop(queue)
        if d > dist[(r, c)]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (dr, dc) == (0, 0) or not (0 <= rr < ny and 0 <= cc < nx) or not free[rr, cc]:
                    continue
                if dr and dc and not (free[r + dr, c] and free[r, c + dc]):
                    continue
                nd = d + cell * math.hypot(dr, dc)
                if nd < dist.get((rr, cc), math.inf):
                    dist[(rr, cc)] = nd
                    heapq.heappush(queue, (nd, (rr, cc)))
    out = np.full((ny, nx), np.inf)
    for (r, c), d in dist.items():
        out[r, c] = d
    filled = out.copy()
    for r in range(ny):
        for c in range(nx):
            if free[r, c] or (r, c) == goal:
                continue
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    rr, cc = r + dr, c + dc
                    if 0 <= rr < ny and 0 <= cc < nx and free[rr, cc]:
                        filled[r, c] = min(filled[r, c], out[rr, cc] + cell * math.hypot(dr, dc))
    return filled


@pytest.mark.parametrize("seed", range(5))
def test_grid_dijkstra_matches_slow_version(seed):
    rng = np.random.default_rng(seed)
    free = rng.random((17, 23)) > 0.3
    goal = (int(rng.integers(0, 17)), int(rng.integers(0, 23)))
    got = grid_dijkstra(free, goal[0], goal[1], 0.5)
    want = _slow_dijkstra(free, goal, 0.5)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
    np.testing.assert_allclose(got[np.isfinite(want)], want[np.isfinite(want)], rtol=0, atol=1e-9)


def test_the_lazy_dijkstra_answers_any_query_order_as_the_full_run_and_settles_only_what_it_needs():
    """Cells asked in a random order (each twice) get the full run's distances bit for bit; on a site frame, the
    cells around a start 8 m from the goal are answered with a part of the grid settled."""
    rng = np.random.default_rng(7)
    free = rng.random((17, 23)) > 0.3
    full = grid_dijkstra(free, 4, 5, 0.5)
    state = lazy_grid(free, 4, 5)
    cells = [(int(r), int(c)) for r, c in zip(rng.integers(0, 17, 200), rng.integers(0, 23, 200))]
    for r, c in cells + cells[::-1]:
        assert grid_distance(state, 0.5, r, c) == full[r, c] or (math.isinf(full[r, c]) and
                                                                 math.isinf(grid_distance(state, 0.5, r, c)))
    scene = first_frame(10)[0]
    goal = np.asarray(scene.target, float)
    grid = holonomic_grid(packed_scene(scene).geometry, np.asarray(scene.boundary, float), goal[:2], 0.25)
    row, col = (int(math.floor((goal[1] - grid.origin[1]) / 0.25 + 0.5)) + 32,
                int(math.floor((goal[0] - grid.origin[0]) / 0.25 + 0.5)))
    asked = [(row + dr, col + dc) for dr in range(-4, 5) for dc in range(-4, 5)]
    lazy = [grid_distance(grid.state, 0.25, r, c) for r, c in asked]
    settled = np.mean(grid.state[3] & 1 > 0)
    whole = grid_dijkstra(grid.state[0], *np.argwhere(grid.state[1] == 0.0)[0], 0.25)
    assert lazy == [whole[r, c] for r, c in asked] and all(math.isfinite(d) for d in lazy)
    assert 0 < settled < 0.5


def test_lattice_cell_bins_position_and_heading():
    rng = np.random.default_rng(2)
    nx, ny, nth, res = 40, 30, 72, 0.5
    for _ in range(500):
        x, y, th = rng.uniform(-1, 21), rng.uniform(-1, 16), rng.uniform(-4, 4)
        ix, iy = math.floor(x / res), math.floor(y / res)
        it = math.floor((math.remainder(th, 2 * math.pi) + math.pi) / (2 * math.pi) * nth) % nth
        want = (iy * nx + ix) * nth + it if (0 <= ix < nx and 0 <= iy < ny) else -1
        assert lattice_cell(x, y, th, 0.0, 0.0, res, nx, ny, nth) == want


@njit(cache=True)
def free_cells(geo, origin_x: float, origin_y: float, cell_m: float, nx: int, ny: int) -> np.ndarray:
    """The oracle: (ny, nx) bool, ``point_valid`` at every cell's centre."""
    free = np.zeros((ny, nx), np.bool_)
    for r in range(ny):
        for c in range(nx):
            free[r, c] = point_valid(geo, 0, origin_x + c * cell_m, origin_y + r * cell_m)
    return free


def test_free_cells_from_a_kept_boundary_mask_are_every_cells_point_test():
    """On benchmark scenes and a site frame (sharing its boundary with the other frames of the site): the boundary
    mask kept per boundary and grid, with the obstacles tested per call, gives exactly ``free_cells`` (every cell's
    ``point_valid``); the same boundary and grid reuse one mask."""
    scenes = [*load_benchmark("factorial", "test"), *load_benchmark("topology", "test"), first_frame(10)[0],
              first_frame(24)[0]]
    assert sum(packed_scene(scene).geometry[7][0] for scene in scenes) > 0  # discs as well as polygons
    for scene in scenes:
        geo = packed_scene(scene).geometry
        b = np.asarray(scene.boundary, float)
        lo, hi, cell = b.min(axis=0), b.max(axis=0), 0.25
        nx, ny = int((hi[0] - lo[0]) / cell) + 1, int((hi[1] - lo[1]) / cell) + 1
        inside = boundary_cells(b, float(lo[0]), float(lo[1]), cell, nx, ny)
        np.testing.assert_array_equal(free_cells_inside(geo, inside, float(lo[0]), float(lo[1]), cell),
                                      free_cells(geo, float(lo[0]), float(lo[1]), cell, nx, ny))
    site = [np.asarray(first_frame(k)[0].boundary, float) for k in (10, 24)]
    np.testing.assert_array_equal(site[0], site[1])
    lo = site[0].min(axis=0)
    args = (float(lo[0]), float(lo[1]), 0.25, 20, 10)
    assert boundary_cells(site[0], *args) is boundary_cells(site[1].copy(), *args)
    assert boundary_cells(site[0], *args) is not boundary_cells(site[0], float(lo[0]), float(lo[1]), 0.5, 20, 10)


def test_the_open_lists_key_never_exceeds_the_full_heuristic():
    """Hybrid A* keys a new node with ``heuristic_bound`` and computes the full h only when it is popped; that
    order is A*'s only if the bound never exceeds h: at random poses on a benchmark scene's grid it does not, it
    equals the grid term where that dominates, and for a region goal (no Reeds–Shepp term) it is h itself."""
    scene = load_benchmark("factorial", "test")[0]
    goal = np.asarray(scene.target, float)
    grid = holonomic_grid(packed_scene(scene).geometry, np.asarray(scene.boundary, float), goal[:2], 0.25)
    rng = np.random.default_rng(3)
    lo, hi = np.min(scene.boundary, axis=0), np.max(scene.boundary, axis=0)
    equal = 0
    for x, y, th in zip(rng.uniform(lo[0], hi[0], 400), rng.uniform(lo[1], hi[1], 400), rng.uniform(-4, 4, 400)):
        for region in (0.0, 3.0):
            args = (grid.state, grid.origin[0], grid.origin[1], grid.cell_m)
            bound = heuristic_bound(x, y, region, *args)
            full = heuristic(x, y, th, goal[0], goal[1], goal[2], 0.68, region, *args)
            assert bound <= full or (math.isinf(bound) and math.isinf(full))
            if region > 0:
                assert bound == full or (math.isinf(bound) and math.isinf(full))
            else:
                equal += bound == full
    assert 0 < equal < 400  # both terms dominate somewhere
