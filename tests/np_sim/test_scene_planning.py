"""Scenes a planner must handle or refuse: an obstacle crossing the boundary plans; a lattice beyond
``HybridAStarConfig.max_lattice_bytes`` is refused before any allocation.

The returned path is checked with shapely on poses integrated here from the closed form of eq:arc, not with the
planner's own sampler or collision kernels.
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from np_sim.errors import CapacityError, SceneError
from np_sim.planners import HybridAStar, HybridAStarConfig
from np_sim.scene import Scene

PENINSULA = [[-4.0, 8.0], [12.0, 8.0], [12.0, 12.0], [-4.0, 12.0]]
"""A wall that starts beyond the left boundary edge and reaches 12 m into the lot."""


def _arc_poses(start, arcs, ds: float) -> np.ndarray:
    """Poses every ≤ ``ds`` m along (κ, l) arcs, by the closed form of eq:arc (written out here on purpose).

    The paper's signs: θ' = θ − sgn(κ)|lκ| in either gear, so along signed length s the heading is
    θ(s) = θ − k s with k = κ sgn(l), and x(s) = x + (sin θ − sin θ(s))/k, y(s) = y + (cos θ(s) − cos θ)/k.
    """
    x, y, th = (float(v) for v in start)
    poses = [(x, y, th)]
    for kappa, length in arcs:
        n = max(1, math.ceil(abs(length) / ds))
        for j in range(1, n + 1):
            s = length * j / n
            k = kappa * math.copysign(1.0, length)
            if abs(k) < 1e-12:
                poses.append((x + s * math.cos(th), y + s * math.sin(th), th))
            else:
                t = th - k * s
                poses.append((x + (math.sin(th) - math.sin(t)) / k, y + (math.cos(t) - math.cos(th)) / k, t))
        x, y, th = poses[-1]
    return np.array(poses)


def test_an_obstacle_crossing_the_boundary_loads_and_plans_around_it():
    scene = Scene.from_dict({
        "name": "cut_lot",
        "boundary": [[0, 0], [30, 0], [30, 20], [0, 20]],
        "obstacles": [{"polygon": PENINSULA}],
        "target": [6.0, 4.0, 0.0],
        "start_region": [[1, 14], [10, 14], [10, 19], [1, 19]],
    })
    start = np.array([4.0, 16.0, 0.0])  # above the wall; the target lies below it, 12 m of wall in between
    plan = HybridAStar(HybridAStarConfig(time_budget_s=20.0)).plan(scene, start)
    assert plan.success, plan.reason
    poses = _arc_poses(start, plan.arcs, 0.01)
    assert poses[:, 0].max() > 12.0  # it went round the wall's free end, the only way through
    boundary, wall = Polygon(scene.boundary), Polygon(PENINSULA).buffer(-0.02)  # 2 cm: corner clips between samples
    assert all(boundary.contains(Point(p)) and not wall.contains(Point(p)) for p in poses[:, :2])
    assert math.hypot(*(poses[-1, :2] - scene.target[:2])) <= 0.1
    assert abs(math.remainder(poses[-1, 2] - scene.target[2], 2 * math.pi)) <= math.radians(10)


def _box_scene(width_m: float, height_m: float) -> Scene:
    """An empty width × height lot with the target near its origin corner."""
    return Scene.from_dict({
        "name": f"box_{width_m:g}x{height_m:g}",
        "boundary": [[0, 0], [width_m, 0], [width_m, height_m], [0, height_m]],
        "obstacles": [],
        "target": [5.0, 5.0, 0.0],
    })


def test_a_huge_lot_is_refused_before_any_allocation():
    scene = _box_scene(5000.0, 5000.0)  # 0.5 m × 72 headings: 7 GB of lattice alone
    tracemalloc.start()
    try:
        with pytest.raises(CapacityError, match=r"box_5000x5000: boundary: a 5000 x 5000 m extent needs "
                           r"[0-9,]+ MiB of Hybrid A\* lattice and heuristic grid, over "
                           r"HybridAStarConfig\.max_lattice_bytes = 1,024 MiB; raise the bound"):
            HybridAStar().plan(scene, [10.0, 5.0, 0.0])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 2**20
    assert isinstance(CapacityError("x"), SceneError)


def test_the_memory_bound_is_the_lattice_and_grid_size():
    # 100 × 50 m: lattice 201 × 101 cells × 72 headings × 24 B (int64 stamp, float64 g, int64 closed) and
    # heuristic grid 401 × 201 cells × 147 B (bool inside and free, int8 status, float64 distance and value,
    # 8 float64 keys, 8 int64 ids)
    need = 201 * 101 * 72 * 24 + 401 * 201 * 147
    scene = _box_scene(100.0, 50.0)
    plan = HybridAStar(HybridAStarConfig(max_lattice_bytes=need)).plan(scene, [5.0, 5.0, 0.0])
    assert plan.success
    with pytest.raises(CapacityError, match=r"HybridAStarConfig\.max_lattice_bytes"):
        HybridAStar(HybridAStarConfig(max_lattice_bytes=need - 1)).plan(scene, [5.0, 5.0, 0.0])


def test_the_memory_bound_must_be_a_positive_integer():
    from np_sim.errors import ConfigError

    for bad in (0, -1, 1.5e9):
        with pytest.raises(ConfigError, match=r"HybridAStarConfig\.max_lattice_bytes: expected an integer >= 1"):
            HybridAStarConfig(max_lattice_bytes=bad)
