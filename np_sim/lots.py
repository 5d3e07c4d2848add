"""Seeded parking lots with more parked cars than the policy has slots: rows of perpendicular bays along aisles.

``generate_lot(LotConfig(), seed)`` lays out ``rows`` rows of ``bays_per_row`` bays inside a rectangular boundary:
one row against the bottom wall facing up, back-to-back double rows in the middle, one row against the top wall
facing down, and a driving aisle of ``aisle_m`` between facing rows and a cross aisle of ``cross_aisle_m`` at both
ends. Each bay holds a parked car (a rectangle of jittered size, offset and heading) with probability
``occupancy``; the target is one bay left empty, entered in reverse (the parked heading points into its aisle),
and the start region is the aisle in front of the target's row, ``start_offset_m`` along it, with a heading range
along the aisle. Everything random comes from ``numpy.random.default_rng(seed)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from np_sim.scene import PolygonObstacle, Scene
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class LotConfig:
    """Layout of a generated lot (metres, radians)."""

    rows: int = 4
    """Rows of bays (even, >= 2): bottom row, back-to-back double rows, top row."""
    bays_per_row: int = 22
    """Bays in each row."""
    bay_width_m: float = 2.6
    """Bay width along the row (m)."""
    bay_depth_m: float = 5.2
    """Bay depth across the row (m)."""
    aisle_m: float = 7.0
    """Driving aisle between facing rows (m)."""
    cross_aisle_m: float = 6.0
    """Aisle across the rows at each end (m)."""
    wall_gap_m: float = 0.5
    """Gap between the outer rows and the boundary (m)."""
    occupancy: float = 0.95
    """Probability that a bay other than the target holds a parked car."""
    car_length_m: tuple[float, float] = (4.2, 4.9)
    """Range of parked-car lengths (m), drawn uniformly."""
    car_width_m: tuple[float, float] = (1.75, 1.95)
    """Range of parked-car widths (m), drawn uniformly."""
    offset_m: float = 0.15
    """Largest sideways offset of a parked car from its bay's centre line (m)."""
    yaw_rad: float = 0.05
    """Largest heading deviation of a parked car from its bay's axis (rad)."""
    start_offset_m: float = 16.0
    """Distance along the aisle from the target bay to the start region's centre (m)."""
    start_length_m: float = 8.0
    """Length of the start region along the aisle (m); it spans the aisle's middle half across."""
    start_heading_rad: float = 0.35
    """Half-width of the start heading range around the direction along the aisle towards the target (rad)."""


def _row_layout(config: LotConfig) -> tuple[list[tuple[float, int]], list[float]]:
    """Per row (y of its wall-side edge, +1 facing up / −1 facing down), and the y of each aisle's centre."""
    rows, y, aisles = [], config.wall_gap_m, []
    for r in range(config.rows):
        facing = 1 if r % 2 == 0 else -1
        rows.append((y, facing))
        y += config.bay_depth_m
        if facing == 1 and r + 1 < config.rows:
            aisles.append(y + 0.5 * config.aisle_m)
            y += config.aisle_m
    return rows, aisles


def _car(rng: np.random.Generator, centre: np.ndarray, axis: float, config: LotConfig) -> PolygonObstacle:
    """A parked car: jittered rectangle around ``centre`` along heading ``axis``, vertices rounded to the mm."""
    length, width = rng.uniform(*config.car_length_m), rng.uniform(*config.car_width_m)
    yaw = axis + rng.uniform(-config.yaw_rad, config.yaw_rad)
    offset = rng.uniform(-config.offset_m, config.offset_m)
    side = np.array([-math.sin(axis), math.cos(axis)])
    local = 0.5 * np.array([[-length, -width], [length, -width], [length, width], [-length, width]])
    c, s = math.cos(yaw), math.sin(yaw)
    world = local @ np.array([[c, s], [-s, c]]) + centre + offset * side
    return PolygonObstacle(np.round(world, 3))


def generate_lot(config: LotConfig = LotConfig(), seed: int = 0, vehicle: VehicleSpec | None = None,
                 name: str | None = None) -> Scene:
    """A validated lot scene (module docstring); the same config and seed give the same scene."""
    if config.rows < 2 or config.rows % 2 or config.bays_per_row < 2:
        raise ValueError(f"generate_lot: expected an even rows >= 2 and bays_per_row >= 2, got {config.rows}, "
                         f"{config.bays_per_row}")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    rng = np.random.default_rng(seed)
    rows, aisles = _row_layout(config)
    width = 2 * config.cross_aisle_m + config.bays_per_row * config.bay_width_m
    height = rows[-1][0] + config.bay_depth_m + config.wall_gap_m
    target_row = int(rng.integers(config.rows))
    target_bay = int(rng.integers(config.bays_per_row // 4, config.bays_per_row - config.bays_per_row // 4))
    obstacles, target = [], None
    for r, (y0, facing) in enumerate(rows):
        axis = 0.5 * math.pi * facing
        for b in range(config.bays_per_row):
            x = config.cross_aisle_m + (b + 0.5) * config.bay_width_m
            if (r, b) == (target_row, target_bay):
                back = y0 if facing == 1 else y0 + config.bay_depth_m
                rear_axle = back + facing * (vehicle.rear_overhang_m + 0.3)
                target = np.array([x, rear_axle, axis])
            elif rng.random() < config.occupancy:
                obstacles.append(_car(rng, np.array([x, y0 + 0.5 * config.bay_depth_m]), axis, config))
    aisle = aisles[min(target_row // 2, len(aisles) - 1)]
    direction = 1.0 if target[0] < 0.5 * width else -1.0
    centre = float(np.clip(target[0] + direction * config.start_offset_m, config.cross_aisle_m, width
                           - config.cross_aisle_m))
    half_l, half_w = 0.5 * config.start_length_m, 0.25 * config.aisle_m
    region = [[centre - half_l, aisle - half_w], [centre + half_l, aisle - half_w],
              [centre + half_l, aisle + half_w], [centre - half_l, aisle + half_w]]
    towards = 0.0 if direction < 0 else math.pi
    scene = Scene(boundary=np.round([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]], 3),
                  obstacles=tuple(obstacles), target=np.round(target, 6), start_region=np.round(region, 3),
                  name=name or f"lot_seed{seed}",
                  tags={"source": "np_sim.lots.generate_lot", "seed": int(seed)},
                  start_headings=np.array([towards - config.start_heading_rad, towards + config.start_heading_rad]))
    scene.validate(source=scene.name, vehicle=vehicle)
    return scene
