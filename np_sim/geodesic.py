"""Geodesic distance to the target on a footprint-inflated grid (paper §III-E curriculum, §IV-A validity checks).

The scene's bounding box is cut into square cells (1.5 m by default). A cell is *free* when the vehicle
footprint, with its reference point at the cell centre, fits for at least one of ``n_headings`` evenly spaced
headings (the configuration-space projection of the footprint: "footprint-inflated"). The target's cell is free
by definition (the target pose itself is footprint-free). Free cells connect to their eight neighbours; the
geodesic distance of a cell is its Dijkstra distance (cell size per straight step, √2 × cell size per diagonal
step) to the target's cell, and ``inf`` for cells in another component or blocked.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from np_sim.kernels.collision import footprint_valid
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True, eq=False)
class GeodesicGrid:
    """Free cells and geodesic distances of one scene."""

    origin: np.ndarray
    """(2,) world position of cell (0, 0)'s centre (m)."""
    cell_m: float
    """Cell size (m)."""
    free: np.ndarray
    """(ny, nx) bool: the footprint fits at the cell centre for some heading."""
    distance: np.ndarray
    """(ny, nx) geodesic distance to the target's cell (m); inf when unreachable."""
    target_cell: tuple[int, int]
    """(row, col) of the target's cell."""

    def cell_of(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of the cells holding world points (..., 2) (may lie outside the grid)."""
        p = np.asarray(xy, float)
        col = np.floor((p[..., 0] - self.origin[0]) / self.cell_m + 0.5).astype(np.int64)
        row = np.floor((p[..., 1] - self.origin[1]) / self.cell_m + 0.5).astype(np.int64)
        return row, col

    def distance_at(self, xy) -> np.ndarray:
        """Geodesic distance (m) of the cells holding world points (..., 2); inf outside the grid."""
        row, col = self.cell_of(xy)
        ny, nx = self.distance.shape
        inside = (row >= 0) & (row < ny) & (col >= 0) & (col < nx)
        out = np.full(row.shape, np.inf)
        out[inside] = self.distance[row[inside], col[inside]]
        return out


def geodesic_grid(scene: Scene, cell_m: float = 1.5, n_headings: int = 16,
                  vehicle: VehicleSpec | None = None) -> GeodesicGrid:
    """Build the footprint-inflated grid of ``scene`` and its geodesic distances to the target."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    local = vehicle.footprint_local()
    geo = packed_scene(scene).geometry
    b = np.asarray(scene.boundary, float)
    lo, hi = b.min(axis=0), b.max(axis=0)
    nx = int(math.floor((hi[0] - lo[0]) / cell_m)) + 1
    ny = int(math.floor((hi[1] - lo[1]) / cell_m)) + 1
    origin = lo.copy()
    headings = np.linspace(-math.pi, math.pi, n_headings, endpoint=False)
    corners = np.empty((4, 2))
    free = np.zeros((ny, nx), bool)
    for r in range(ny):
        y = origin[1] + r * cell_m
        for c in range(nx):
            x = origin[0] + c * cell_m
            for th in headings:
                if footprint_valid(geo, 0, x, y, th, local, corners):
                    free[r, c] = True
                    break
    grid = GeodesicGrid(origin, cell_m, free, np.full((ny, nx), np.inf), (0, 0))
    tr, tc = (int(v) for v in grid.cell_of(np.asarray(scene.target[:2])))
    if not (0 <= tr < ny and 0 <= tc < nx):
        raise ValueError(f"geodesic_grid: target {scene.target[:2].tolist()} lies outside the boundary's bounding box")
    free[tr, tc] = True
    distance = np.full((ny, nx), np.inf)
    distance[tr, tc] = 0.0
    heap = [(0.0, tr, tc)]
    steps = [(dr, dc, cell_m * math.hypot(dr, dc)) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]
    while heap:
        d, r, c = heapq.heappop(heap)
        if d > distance[r, c]:
            continue
        for dr, dc, w in steps:
            rr, cc = r + dr, c + dc
            if 0 <= rr < ny and 0 <= cc < nx and free[rr, cc] and d + w < distance[rr, cc]:
                distance[rr, cc] = d + w
                heapq.heappush(heap, (d + w, rr, cc))
    return GeodesicGrid(origin, cell_m, free, distance, (tr, tc))
