"""Geometry of the clips: point-to-polygon distances, the outlines of ground-truth objects, and the geodesic grid
on which feasibility and the detour criterion are measured (`np_sim.geodesic`, 1.5 m cells)."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from np_sim.clips.config import ClipConfig
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.scene import PolygonObstacle
from np_sim.site import Site
from np_sim.vehicle import VehicleSpec


def polygon_distances(point, polygons: np.ndarray) -> np.ndarray:
    """Euclidean distance from ``point`` (2,) to each polygon of ``polygons`` (n, k, 2); 0 inside or on an edge."""
    p = np.asarray(point, dtype=np.float64)
    polys = np.asarray(polygons, dtype=np.float64)
    if len(polys) == 0:
        return np.zeros(0)
    a, b = polys, np.roll(polys, -1, axis=1)
    ab = b - a
    t = np.clip(np.einsum("nkd,nkd->nk", p - a, ab) / np.maximum(np.einsum("nkd,nkd->nk", ab, ab), 1e-300), 0, 1)
    closest = a + t[..., None] * ab
    edge = np.sqrt(((closest - p) ** 2).sum(axis=-1)).min(axis=1)
    # even-odd crossing test of a ray towards +x
    crosses = ((a[..., 1] > p[1]) != (b[..., 1] > p[1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = a[..., 0] + (p[1] - a[..., 1]) * ab[..., 0] / ab[..., 1]
    inside = (crosses & (x_at > p[0])).sum(axis=1) % 2 == 1
    return np.where(inside, 0.0, edge)


def rectangle(length: float, width: float) -> np.ndarray:
    """(4, 2) centred rectangle, counter-clockwise, rounded to the millimetre."""
    h, w = 0.5 * length, 0.5 * width
    return np.round(np.array([[-h, -w], [h, -w], [h, w], [-h, w]]), 3)


def octagon(radius: float) -> np.ndarray:
    """(8, 2) regular octagon of circumradius ``radius``, counter-clockwise, rounded to the millimetre."""
    angles = 2.0 * np.pi * np.arange(8) / 8
    return np.round(radius * np.stack([np.cos(angles), np.sin(angles)], axis=1), 3)


def geodesic_at(grid: GeodesicGrid, xy) -> float:
    """Geodesic distance (m) of a point: its own cell if free, else the nearest free cell of its 3 × 3 block
    (plus the straight distance to that cell's centre); inf when none is connected."""
    row, col = (int(v) for v in grid.cell_of(np.asarray(xy, dtype=np.float64)))
    ny, nx = grid.free.shape
    if 0 <= row < ny and 0 <= col < nx and grid.free[row, col]:
        return float(grid.distance[row, col])
    cells = [(row + dr, col + dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]
    for r, c in sorted(cells, key=lambda rc: math.dist(xy, grid.origin + grid.cell_m * np.array([rc[1], rc[0]]))):
        if 0 <= r < ny and 0 <= c < nx and grid.free[r, c]:
            centre = grid.origin + grid.cell_m * np.array([c, r])
            return float(grid.distance[r, c]) + math.dist(xy, centre)
    return math.inf


def clip_grid(site: Site, target, polygons: Sequence[np.ndarray], config: ClipConfig,
              vehicle: VehicleSpec) -> GeodesicGrid:
    """The footprint-inflated geodesic grid of the site with ``polygons`` as obstacles."""
    scene = site.scene(target, [PolygonObstacle(p) for p in polygons])
    return geodesic_grid(scene, cell_m=config.grid_m, vehicle=vehicle)
