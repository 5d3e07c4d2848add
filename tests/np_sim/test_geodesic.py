"""Geodesic grid: free cells by footprint fit, Dijkstra distances, detours and enclosed targets."""

import math

import numpy as np
import pytest

from np_sim.examples import example_scenes
from np_sim.geodesic import geodesic_grid
from np_sim.scene import Scene

LOT = {"boundary": [[0, 0], [30, 0], [30, 30], [0, 30]], "obstacles": [], "target": [15.0, 3.0, math.pi / 2]}


def test_open_lot_distance_is_the_8_connected_grid_metric():
    g = geodesic_grid(Scene.from_dict(LOT))
    tr, tc = g.target_cell
    # a cell straight above the target: cell size per step; a diagonal one: √2 × cell size per step
    assert g.distance[tr + 6, tc] == pytest.approx(6 * 1.5)
    assert g.distance[tr + 4, tc + 4] == pytest.approx(4 * 1.5 * math.sqrt(2))
    assert g.distance_at(np.array([15.0, 3.0])) == 0.0
    assert np.isinf(g.distance_at(np.array([-50.0, 0.0])))


def test_a_wall_forces_a_detour():
    wall = {"polygon": [[3, 12], [27, 12], [27, 13], [3, 13]]}
    g_open = geodesic_grid(Scene.from_dict(LOT))
    g_wall = geodesic_grid(Scene.from_dict(dict(LOT, obstacles=[wall])))
    above = np.array([15.0, 22.0])
    assert g_wall.distance_at(above) > g_open.distance_at(above) + 5.0
    assert np.isfinite(g_wall.distance_at(above))
    # cells whose centre is inside the wall are not free
    r, c = g_wall.cell_of(np.array([15.0, 12.5]))
    assert not g_wall.free[r, c]


def test_enclosed_target_is_unreachable_from_outside():
    scene = next(s for s in example_scenes() if s.name == "enclosed_target")
    g = geodesic_grid(scene)
    assert np.isfinite(g.distance).sum() < 0.1 * g.free.sum()
