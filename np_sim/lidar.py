"""Ego-centric LiDAR (paper §III-B, eq:lidar-clearance, App. A).

Beam i points at θ + 2πi/n (beam 0 along the heading, counter-clockwise). ``d_i`` is the reference-point
distance to the first obstacle or boundary crossing (exact, zero-tolerance segment-bound tests: corners hit;
circles as 16-segment rings),
capped at the range; ``b_i`` the distance from the reference point to the footprint rectangle along the beam;
the policy sees ``max(d_i − b_i, 0)``, written once, in the observation kernel (``np_sim.kernels.step``).
"""

from __future__ import annotations

import math

import numpy as np

from np_sim.kernels.geometry import cast_beams
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.vehicle import VehicleSpec


def cast_rays(scene: Scene, pose, n_beams: int = 120, max_range: float = 10.0) -> np.ndarray:
    """Distances d (n_beams,) from the pose's reference point to the first crossing, capped at ``max_range``."""
    if int(n_beams) < 1 or not max_range > 0:
        raise ValueError(f"cast_rays: need n_beams >= 1 and max_range > 0, got {n_beams}, {max_range}")
    arrays = packed_scene(scene)
    out = np.empty(int(n_beams))
    p = np.asarray(pose, float)
    cast_beams(p[0], p[1], p[2], arrays.segs[0], int(arrays.n_segs[0]), int(n_beams), float(max_range), out)
    return out


def footprint_ranges(vehicle: VehicleSpec | None = None, n_beams: int = 120) -> np.ndarray:
    """b (n_beams,): distance from the reference point to the footprint rectangle along each beam direction.

    For direction (cos φ, sin φ) in the vehicle frame, b = min(t_x, t_y) with t_x the distance to the front
    (cos φ > 0) or rear (cos φ < 0) edge and t_y to the left/right edge.
    """
    vehicle = VehicleSpec() if vehicle is None else vehicle
    phi = 2.0 * math.pi * np.arange(int(n_beams)) / int(n_beams)
    c, s = np.cos(phi), np.sin(phi)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, vehicle.front_m / np.where(c > 0, c, 1.0),
                      np.where(c < 0, vehicle.rear_overhang_m / np.where(c < 0, -c, 1.0), np.inf))
        ty = np.where(np.abs(s) > 0, 0.5 * vehicle.width_m / np.where(np.abs(s) > 0, np.abs(s), 1.0), np.inf)
    return np.minimum(tx, ty)
