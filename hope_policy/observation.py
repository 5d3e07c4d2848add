"""Observation parts of the adapted HOPE environment (paper App. B; HOPE ``car_parking_base.py``
``_get_targt_repr`` and ``lidar_simulator.py``), compiled.

* ``lidar``: the signed footprint clearance d_i − b_i of the benchmark ray distances d_i (``np_sim.lidar``: beam 0
  along the heading, counter-clockwise, capped at 10 m) minus the footprint range b_i of each beam. Negative
  values are kept (NeuralParker rectifies them, paper eq:lidar-clearance; the adapted HOPE does not).
* ``target``: HOPE's target representation (ρ, cos α, sin α, cos φ, sin φ) with ρ the distance from the reference
  point to the target, α the bearing of the target and φ the target heading, both relative to the ego heading.
  HOPE's published code writes cos φ twice; the intended (cos φ, sin φ) is used here.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.geometry import cast_beams_offsets


@njit(cache=True, error_model="numpy")
def target_representation(x: float, y: float, th: float, target: np.ndarray, out: np.ndarray) -> None:
    """(ρ, cos α, sin α, cos φ, sin φ) of the target seen from the pose (x, y, θ) into ``out`` (5,):
    ρ = |p^g − p|, α = atan2(y^g − y, x^g − x) − θ, φ = θ^g − θ (HOPE's target representation, sin φ fixed)."""
    dx = target[0] - x
    dy = target[1] - y
    alpha = math.atan2(dy, dx) - th
    phi = target[2] - th
    out[0] = math.sqrt(dx * dx + dy * dy)
    out[1] = math.cos(alpha)
    out[2] = math.sin(alpha)
    out[3] = math.cos(phi)
    out[4] = math.sin(phi)


@njit(cache=True, error_model="numpy")
def signed_clearance(x: float, y: float, th: float, segs: np.ndarray, n_segs: int, off_c: np.ndarray,
                     off_s: np.ndarray, lidar_range: float, b_ranges: np.ndarray, distances: np.ndarray,
                     out: np.ndarray) -> None:
    """Benchmark ray distances d (into ``distances``) and the signed clearances d_i − b_i (into ``out``)."""
    cast_beams_offsets(x, y, th, segs, n_segs, off_c, off_s, lidar_range, distances)
    for i in range(out.shape[0]):
        out[i] = distances[i] - b_ranges[i]
