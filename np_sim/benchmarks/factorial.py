"""Procedural generator of the Factorial Parking Benchmark (paper §IV-A "Scenario Design", spec §4.1).

3 × 3 × 3 cells: start distance {near, medium, long} × parking type {reverse, lateral, random} × difficulty
{easy, medium, hard}; 3 training scenes and 1 test scene per cell (81 + 27), every scene a fresh layout drawn
from its own seed.

**Parking types** (every layout is built in a canonical frame, kerb along y = 0, then used as world frame):

* ``reverse`` — a row of perpendicular bays on the kerb, parked cars in most of them; the target bay between
  two parked cars (an easy bay may miss a neighbour); the target heading points out of the bay (+y), so the car
  reverses in. An aisle runs along the row; across it: a wall, an opposite row of parked cars, or an island
  (building blocks) with a second aisle behind it.
* ``lateral`` — a parallel slot on the kerb between two parked cars; the target heading runs along the kerb
  (either way); across the street a wall, a parallel row, or an island.
* ``random`` — an open lot with irregular clutter; the target anywhere inside with a uniformly random heading,
  flanked by parked cars or irregular walls (and maybe a back wall), approached from ahead.

**Difficulty** sets slot clearance (bay gap between the neighbours 3.6 / 3.0 / 2.6 m; parallel-slot length
7.6 / 6.9 / 6.3 m; random-type flank gap 3.8 / 3.2 / 2.8 m), aisle width, clutter count and boundary
irregularity (4–5 / 5–7 / 8–10 boundary segments from chamfers, notches and jitter).

**Distance regime** is a property of the scene's start region (spec §4.1): the region is placed so that the
median geodesic distance (1.5 m footprint-inflated grid, `np_sim.geodesic`) of its free cells lies in the
regime's band — near 6–11 m, medium 13.5–20.5 m, long 24–36 m — and a scene whose final layout (after clutter)
leaves the band is regenerated. Starts are never rejected by distance at sampling time.

**Grid lattice.** Every target sits on the 1.5 m lattice from the lot's corner (the geodesic grid's origin),
i.e. exactly on a grid-cell centre, so the cells along a bay's axis are centred on it and a narrow bay does not
drop out of the free component by aliasing (for reverse and lateral targets the reference point is 1.5 m from
the kerb: rear bumper 0.57 m, side 0.53 m).

Scenes that fail a validity check (`np_sim.benchmarks.validity`), leave their band, or come within the
disjointness floor (`np_sim.benchmarks.layout`) of an earlier scene of their cell are regenerated with the next
sub-seed; `generate_factorial` reports the rejection counts.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.ops import unary_union

from np_sim.benchmarks.common import (
    ClutterSpec,
    box,
    jsonable,
    choose_start_region,
    draft_grid,
    finish_scene,
    irregular_boundary,
    place_clutter,
    rectangle,
    region_distances,
    to_world,
)
from np_sim.benchmarks.frozen import BenchmarkBuild, build_benchmark
from np_sim.benchmarks.layout import DISJOINTNESS_FLOOR_M
from np_sim.benchmarks.validity import ValidityConfig
from np_sim.errors import ConfigError
from np_sim.geodesic import GeodesicGrid
from np_sim.scene import Obstacle, PolygonObstacle, Scene
from np_sim.vehicle import VehicleSpec

DISTANCES = ("near", "medium", "long")
"""Start-distance regimes, nearest first."""
PARKING_TYPES = ("reverse", "lateral", "random")
"""Parking types."""
DIFFICULTIES = ("easy", "medium", "hard")
"""Difficulty levels."""


@dataclass(frozen=True)
class FactorialConfig:
    """Parameters of the Factorial Parking generator; tuples indexed by regime or difficulty (in the orders of
    `DISTANCES` and `DIFFICULTIES`)."""

    seed: int = 20250
    """Root seed; scene (cell c, slot s, attempt a) uses ``default_rng([seed, layout_seed])`` with
    ``layout_seed = (16 c + s) · 1000 + a``."""
    n_train_per_cell: int = 3
    """Training scenes per cell."""
    n_test_per_cell: int = 1
    """Test scenes per cell."""
    band_m: tuple[tuple[float, float], ...] = ((6.0, 11.0), (13.5, 20.5), (24.0, 36.0))
    """Accepted median geodesic distance of the start region's free cells per regime (m)."""
    aim_m: tuple[tuple[float, float], ...] = ((7.0, 10.0), (14.5, 19.5), (25.5, 33.5))
    """Range of the aimed region-centre geodesic distance per regime (m)."""
    region_size_m: tuple[tuple[float, float], ...] = ((6.0, 4.5), (8.0, 5.0), (10.0, 5.0))
    """Start-region rectangle (length, width) per regime before jitter (m)."""
    lot_length_m: tuple[tuple[float, float], ...] = ((24.0, 30.0), (32.0, 40.0), (42.0, 50.0))
    """Lot length along the kerb per regime (m)."""
    bay_gap_m: tuple[float, ...] = (3.6, 3.0, 2.6)
    """Reverse type: gap between the target bay's neighbours per difficulty (m; the car is 1.942 m wide)."""
    slot_length_m: tuple[float, ...] = (7.6, 6.9, 6.3)
    """Lateral type: parallel-slot length between the neighbours per difficulty (m; the car is 4.689 m long)."""
    flank_gap_m: tuple[float, ...] = (3.8, 3.2, 2.8)
    """Random type: gap between the target's flank obstacles per difficulty (m)."""
    flank_probability: tuple[float, ...] = (0.7, 0.85, 1.0)
    """Random type: probability of each flank obstacle per difficulty."""
    aisle_m: tuple[tuple[float, float], ...] = ((7.0, 8.0), (6.2, 7.0), (5.6, 6.2))
    """Aisle (street) width range per difficulty (m)."""
    clutter_count: tuple[tuple[int, int], ...] = ((1, 3), (3, 6), (6, 9))
    """Clutter items per difficulty for the reverse and lateral types (inclusive range)."""
    random_clutter_count: tuple[tuple[int, int], ...] = ((5, 7), (8, 11), (11, 15))
    """Clutter items per difficulty for the random type (inclusive range)."""
    clutter_gap_m: tuple[float, ...] = (3.0, 2.6, 2.2)
    """Least gap between clutter and other obstacles per difficulty (m)."""
    boundary_segments: tuple[tuple[int, int], ...] = ((4, 5), (5, 7), (8, 10))
    """Boundary segment budget per difficulty (inclusive range; irregularity)."""
    disjointness_floor_m: float = DISJOINTNESS_FLOOR_M
    """Least layout distance between two scenes of one cell (m), see `np_sim.benchmarks.layout`."""
    max_attempts: int = 400
    """Draws per scene before the generator gives up (raises)."""
    validity: ValidityConfig = field(default_factory=ValidityConfig)
    """Thresholds of the four validity checks."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict of every field (tuples as lists)."""
        return jsonable(dataclasses.asdict(self))


@dataclass(frozen=True)
class FactorialCell:
    """One cell of the 3 × 3 × 3 design."""

    distance: str
    """Start-distance regime (`DISTANCES`)."""
    parking_type: str
    """Parking type (`PARKING_TYPES`)."""
    difficulty: str
    """Difficulty (`DIFFICULTIES`)."""

    @property
    def name(self) -> str:
        """``distance-type-difficulty``, the scene's ``cell`` tag."""
        return f"{self.distance}-{self.parking_type}-{self.difficulty}"


def factorial_cells() -> list[FactorialCell]:
    """The 27 cells in benchmark order: distance outer, then parking type, then difficulty."""
    return [FactorialCell(d, t, q) for d in DISTANCES for t in PARKING_TYPES for q in DIFFICULTIES]


@dataclass
class _Layout:
    """A structural layout before boundary irregularity, start region and clutter (canonical frame)."""

    corners: np.ndarray
    """Convex boundary ring before irregularity."""
    obstacles: list[Obstacle]
    """Structural obstacles (parked cars, blocks, flanks)."""
    target: np.ndarray
    """Target pose."""
    corridor: Any
    """Shapely area in front of the target kept free of clutter."""
    protected: Any
    """Shapely area the irregular boundary must keep inside."""
    straight_edges: tuple[int, ...] = ()
    """Boundary edges kept straight (the kerb)."""


_CAR_L, _CAR_W = 4.689, 1.942
_REF_TO_CENTRE = 0.5 * (2.8 + 0.96 - 0.929)  # rear-axle reference point to footprint centre (m)
_CELL = 1.5  # geodesic-grid cell (m): targets sit on the lattice from the lot's corner, i.e. on a cell centre


def _parked(rng: np.random.Generator, cx: float, cy: float, angle: float) -> PolygonObstacle:
    """A parked car: a slightly varied 4.3–4.9 × 1.8–1.95 m rectangle with a small skew."""
    return PolygonObstacle(rectangle(cx + rng.uniform(-0.08, 0.08), cy + rng.uniform(-0.08, 0.08),
                                     rng.uniform(4.3, 4.9), rng.uniform(1.8, 1.95), angle + rng.uniform(-0.04, 0.04)))


def _block(rng: np.random.Generator, x0: float, y0: float, x1: float, y1: float) -> PolygonObstacle:
    """A building / planter block filling [x0, x1] × [y0, y1] with up to two corners cut (4–6 vertices)."""
    pts = [np.array(p, float) for p in box(x0, y0, x1, y1)]
    out = []
    cut = min(1.5, 0.3 * (x1 - x0), 0.3 * (y1 - y0))
    for i, p in enumerate(pts):
        if cut > 0.4 and rng.random() < 0.35:
            prev, nxt = pts[i - 1], pts[(i + 1) % 4]
            c = rng.uniform(0.4, cut)
            out += [p + c * (prev - p) / np.linalg.norm(prev - p), p + c * (nxt - p) / np.linalg.norm(nxt - p)]
        else:
            out.append(p)
    return PolygonObstacle(np.array(out[:8]))


def _perpendicular_row(rng: np.random.Generator, x_from: float, x_to: float, y0: float, facing_up: bool,
                       budget: int, p_empty: float, direction: int = 1) -> list[Obstacle]:
    """Parked cars in perpendicular bays from ``x_from`` towards ``x_to`` (``direction`` ±1) with the car's kerb
    end at ``y0``; bays left empty with probability ``p_empty``; at most ``budget`` cars, the rest of the row
    may become one block."""
    out: list[Obstacle] = []
    edge = x_from
    depth = _CAR_L
    sign = 1.0 if facing_up else -1.0
    while len(out) < budget:
        far = edge + direction * _CAR_W
        if (far - x_to) * direction > 0:
            return out
        if not out or rng.random() >= p_empty:
            cx = edge + direction * 0.5 * _CAR_W
            out.append(_parked(rng, cx, y0 + sign * (rng.uniform(0.25, 0.45) + 0.5 * depth), 0.5 * math.pi))
        edge = far + direction * rng.uniform(0.5, 1.0)
    if (x_to - edge) * direction > 4.0 and rng.random() < 0.6:
        a, b = sorted((edge + direction * 0.6, x_to - direction * 0.4))
        y_lo, y_hi = sorted((y0 + sign * 0.3, y0 + sign * 5.0))
        out.append(_block(rng, a, y_lo, b, y_hi))
    return out


def _parallel_row(rng: np.random.Generator, x_from: float, x_to: float, y_kerb: float, up: bool, budget: int,
                  direction: int = 1) -> list[Obstacle]:
    """Parallel-parked cars along a kerb at ``y_kerb`` from ``x_from`` towards ``x_to``; gaps 0.8–2.5 m, at most
    ``budget`` cars."""
    out: list[Obstacle] = []
    edge = x_from
    sign = 1.0 if up else -1.0
    while len(out) < budget:
        length = rng.uniform(4.3, 4.9)
        far = edge + direction * length
        if (far - x_to) * direction > 0:
            break
        out.append(PolygonObstacle(rectangle(edge + direction * 0.5 * length,
                                             y_kerb + sign * (rng.uniform(0.2, 0.4) + 0.5 * _CAR_W),
                                             length, rng.uniform(1.8, 1.95), rng.uniform(-0.03, 0.03))))
        edge = far + direction * (rng.uniform(0.8, 2.5) if rng.random() < 0.8 else rng.uniform(5.0, 8.0))
    return out


def _upper(rng: np.random.Generator, d: int, L: float, y0: float, budget: int, parallel: bool
           ) -> tuple[float, list[Obstacle]]:
    """The side across the aisle starting at ``y0`` — a wall, an opposite row, or an island of blocks with a
    second aisle behind it (more islands for longer regimes): returns (lot height, obstacles)."""
    kind = rng.choice(["wall", "row", "island"], p=[(0.5, 0.5, 0.0), (0.3, 0.4, 0.3), (0.25, 0.35, 0.4)][d])
    if kind == "wall":
        return y0 + rng.uniform(0.0, 0.8), []
    if kind == "row":
        depth = 2.4 if parallel else 5.4
        top = y0 + depth
        if parallel:
            cars = _parallel_row(rng, rng.uniform(0.5, 4.0), L - 0.5, top, False, budget)
        else:
            cars = _perpendicular_row(rng, rng.uniform(0.5, 3.0), L - 0.5, top, False, budget, 0.3)
        return top, cars
    width = rng.uniform(5.0, 9.0)
    aisle2 = rng.uniform(6.5, 9.0)
    open_end = rng.uniform(7.5, 10.0)
    which = rng.choice(["left", "right", "both"])
    xa = open_end if which in ("left", "both") else rng.uniform(0.6, 1.0)
    xb = L - (open_end if which in ("right", "both") else rng.uniform(0.6, 1.0))
    if xb - xa < 8.0:
        return y0 + rng.uniform(0.0, 0.8), []
    blocks = []
    if xb - xa > 20.0 and rng.random() < 0.5:
        gap_at = rng.uniform(xa + 6.0, xb - 12.0)
        gap = rng.uniform(6.5, 9.0)
        blocks = [_block(rng, xa, y0, gap_at, y0 + width), _block(rng, gap_at + gap, y0, xb, y0 + width)]
    else:
        blocks = [_block(rng, xa, y0, xb, y0 + width)]
    return y0 + width + aisle2, blocks


def _reverse_layout(rng: np.random.Generator, d: int, q: int, cfg: FactorialConfig) -> _Layout:
    """Perpendicular bays on the kerb, the target bay reversed into (heading out of the bay, +y)."""
    L = rng.uniform(*cfg.lot_length_m[d])
    A = rng.uniform(*cfg.aisle_m[q])
    depth = 5.4
    gap = cfg.bay_gap_m[q] * rng.uniform(0.98, 1.04)
    xt = _CELL * rng.integers(3, int((L - 4.0) / _CELL) + 1)
    target = np.array([xt, _CELL, 0.5 * math.pi])
    obstacles: list[Obstacle] = []
    p_missing = (0.25, 0.0, 0.0)[q]
    for direction in (-1, 1):
        budget = int(rng.integers(2, 6))
        end = 0.3 if direction < 0 else L - 0.3
        row = _perpendicular_row(rng, xt + direction * 0.5 * gap, end, 0.0, True, budget, 0.25, direction=direction)
        if row and rng.random() < p_missing:
            row = row[1:]
        obstacles += row
    y0 = depth + A
    top, upper = _upper(rng, d, L, y0, 6, parallel=False)
    obstacles += upper
    corridor = ShapelyPolygon(box(xt - 3.5, depth - 0.6, xt + 3.5, y0 - 0.2))
    structure = unary_union([ShapelyPolygon(o.vertices) for o in obstacles]).buffer(0.6)
    protected = unary_union([structure, corridor, ShapelyPolygon(box(3.0, depth, L - 3.0, y0 - 1.6)),
                             ShapelyPolygon(box(xt - 3.0, 0.1, xt + 3.0, depth))])
    return _Layout(box(0.0, 0.0, L, top), obstacles, target, corridor, protected, straight_edges=(0,))


def _lateral_layout(rng: np.random.Generator, d: int, q: int, cfg: FactorialConfig) -> _Layout:
    """A parallel slot on the kerb between two parked cars; target heading along the kerb (either way)."""
    L = rng.uniform(*cfg.lot_length_m[d])
    A = rng.uniform(*cfg.aisle_m[q]) - 0.6
    row = 2.4
    slot = cfg.slot_length_m[q] * rng.uniform(0.98, 1.04)
    heading = 1 if rng.random() < 0.5 else -1
    margin = 0.5 * slot + 6.0  # room for the slot and a neighbour on either side
    xt = _CELL * rng.integers(math.ceil(margin / _CELL), math.floor((L - margin) / _CELL) + 1)
    xc = xt + heading * _REF_TO_CENTRE
    target = np.array([xt, _CELL, 0.0 if heading > 0 else math.pi])
    obstacles: list[Obstacle] = []
    for direction in (-1, 1):
        obstacles += _parallel_row(rng, xc + direction * 0.5 * slot, 0.3 if direction < 0 else L - 0.3, 0.0, True,
                                   int(rng.integers(1, 5)), direction=direction)
    y0 = row + A
    top, upper = _upper(rng, d, L, y0, 6, parallel=True)
    obstacles += upper
    corridor = ShapelyPolygon(box(xc - 0.5 * slot - 4.0, row - 0.1, xc + 0.5 * slot + 4.0, y0 - 0.2))
    structure = unary_union([ShapelyPolygon(o.vertices) for o in obstacles]).buffer(0.6)
    protected = unary_union([structure, corridor, ShapelyPolygon(box(3.0, row, L - 3.0, y0 - 1.4)),
                             ShapelyPolygon(box(xc - 0.5 * slot, 0.1, xc + 0.5 * slot, row))])
    return _Layout(box(0.0, 0.0, L, top), obstacles, target, corridor, protected, straight_edges=(0,))


def _random_layout(rng: np.random.Generator, d: int, q: int, cfg: FactorialConfig) -> _Layout:
    """An open lot, target anywhere with a uniform heading, flanked by cars or irregular walls."""
    L = rng.uniform(*cfg.lot_length_m[d])
    H = L * rng.uniform(0.65, 0.85)
    target = np.array([_CELL * rng.integers(5, int((L - 7.0) / _CELL) + 1),
                       _CELL * rng.integers(5, int((H - 7.0) / _CELL) + 1), rng.uniform(-math.pi, math.pi)])
    gap = cfg.flank_gap_m[q] * rng.uniform(0.98, 1.05)
    local: list[np.ndarray] = []
    for side in (-1.0, 1.0):
        if rng.random() >= cfg.flank_probability[q]:
            continue
        inner = side * 0.5 * gap
        if rng.random() < 0.5:
            local.append(rectangle(inner + side * 0.5 * _CAR_W, _REF_TO_CENTRE + rng.uniform(-0.5, 0.5),
                                   rng.uniform(4.3, 4.9), rng.uniform(1.8, 1.95),
                                   0.5 * math.pi + rng.uniform(-0.06, 0.06)))
        else:
            w = rng.uniform(0.8, 2.5)
            y_lo, y_hi = rng.uniform(-1.8, -0.8), rng.uniform(3.2, 4.2)
            pts = [(inner, y_lo), (inner, y_hi),
                   (inner + side * w * rng.uniform(0.5, 1.0), y_hi + rng.uniform(0, 0.8)),
                   (inner + side * w, rng.uniform(y_lo, y_hi)),
                   (inner + side * w * rng.uniform(0.4, 1.0), y_lo - rng.uniform(0, 0.8))]
            local.append(np.array(pts))
    if rng.random() < (0.3, 0.5, 0.7)[q]:
        y_back = -0.929 - rng.uniform(0.3, 0.7)
        local.append(np.array([(-rng.uniform(1.5, 3.0), y_back), (rng.uniform(1.5, 3.0), y_back),
                               (rng.uniform(1.0, 2.5), y_back - rng.uniform(0.5, 1.2)),
                               (-rng.uniform(1.0, 2.5), y_back - rng.uniform(0.5, 1.2))]))
    obstacles: list[Obstacle] = [PolygonObstacle(to_world(p, target)) for p in local]
    corridor = ShapelyPolygon(to_world(box(-3.2, 3.9, 3.2, 10.0), target))
    near = ShapelyPolygon(to_world(box(-0.5 * gap - 2.0, -2.5, 0.5 * gap + 2.0, 4.5), target))
    protected = unary_union([corridor, near] + [ShapelyPolygon(o.vertices).buffer(0.6) for o in obstacles])
    return _Layout(box(0.0, 0.0, L, H), obstacles, target, corridor, protected)


_BUILDERS = {"reverse": _reverse_layout, "lateral": _lateral_layout, "random": _random_layout}


def layout_seed_of(cell_index: int, slot: int, attempt: int) -> int:
    """The ``layout_seed`` tag of draw ``attempt`` for scene ``slot`` of cell ``cell_index`` (slots: training
    scenes first, then test scenes)."""
    return (16 * cell_index + slot) * 1000 + attempt


def factorial_scene(cell: FactorialCell, layout_seed: int, split: str, index: int,
                    config: FactorialConfig | None = None, vehicle: VehicleSpec | None = None) -> Scene:
    """Draw one Factorial scene of ``cell`` from ``layout_seed`` (paper §IV-A); no validity checks yet.

    Raises `DraftRejected` ("start_region") when no start region with the regime's geodesic band fits.
    """
    cfg = FactorialConfig() if config is None else config
    if cell.distance not in DISTANCES or cell.parking_type not in PARKING_TYPES or cell.difficulty not in DIFFICULTIES:
        raise ConfigError(f"factorial_scene: unknown cell {cell}; expected distance in {DISTANCES}, type in "
                          f"{PARKING_TYPES}, difficulty in {DIFFICULTIES}")
    d, q = DISTANCES.index(cell.distance), DIFFICULTIES.index(cell.difficulty)
    rng = np.random.default_rng([cfg.seed, layout_seed])
    layout = _BUILDERS[cell.parking_type](rng, d, q, cfg)
    n_seg = int(rng.integers(cfg.boundary_segments[q][0], cfg.boundary_segments[q][1] + 1))
    boundary = irregular_boundary(rng, layout.corners, layout.protected, n_seg, jitter_m=(0.0, 0.6, 1.2)[q],
                                  straight_edges=layout.straight_edges)
    interior = ShapelyPolygon(boundary).buffer(-0.1)
    structural = [o for o in layout.obstacles if interior.contains(ShapelyPolygon(o.vertices))]
    grid = draft_grid(boundary, structural, layout.target, vehicle, cfg.validity.cell_m)
    target_zone = ShapelyPolygon((vehicle or VehicleSpec()).footprint(layout.target)).buffer(1.5)
    region = choose_start_region(rng, Scene(boundary, tuple(structural), layout.target, None), grid, cfg.band_m[d],
                                 cfg.aim_m[d], cfg.region_size_m[d], keepout=target_zone)
    lo, hi = (cfg.random_clutter_count if cell.parking_type == "random" else cfg.clutter_count)[q]
    count = min(int(rng.integers(lo, hi + 1)), cfg.validity.capacity.max_obstacles - len(structural))
    keepout = unary_union([layout.corridor, target_zone, ShapelyPolygon(region).buffer(1.0)])
    if cell.parking_type == "random":
        spec = ClutterSpec(gap_m=cfg.clutter_gap_m[q], blob_radius_m=(0.8, 2.2))
        focus = (float(layout.target[0]), float(layout.target[1]), 12.0)
    else:
        spec, focus = ClutterSpec(gap_m=cfg.clutter_gap_m[q]), None
    clutter = place_clutter(rng, count, boundary, structural, keepout, spec, focus=focus)
    tags = {"benchmark": "factorial", "split": split, "distance": cell.distance, "type": cell.parking_type,
            "difficulty": cell.difficulty, "cell": cell.name, "layout_seed": int(layout_seed)}
    return finish_scene(boundary, structural + clutter, layout.target, region,
                        f"factorial-{split}-{cell.name}-{index}", tags)


def distance_band_check(scene: Scene, grid: GeodesicGrid, config: FactorialConfig | None = None) -> str | None:
    """The regime check of a finished scene: None when the median geodesic distance of its start region's
    reachable free cells lies in its regime's band, else a reason (counted as ``distance_band``)."""
    cfg = FactorialConfig() if config is None else config
    band = cfg.band_m[DISTANCES.index(scene.tags["distance"])]
    distances = region_distances(grid, scene.start_region)
    distances = distances[np.isfinite(distances)]
    if len(distances) == 0:
        return "start region has no reachable cell"
    median = float(np.median(distances))
    if not band[0] <= median <= band[1]:
        return f"median start-region geodesic distance {median:.1f} m outside {band}"
    return None


def generate_factorial(config: FactorialConfig | None = None, on_scene=None,
                       vehicle: VehicleSpec | None = None) -> BenchmarkBuild:
    """Generate the whole Factorial Parking Benchmark (81 train + 27 test scenes and the 27 × 40 frozen starts)
    from ``config``'s fixed seeds (paper §IV-A); ``on_scene`` is called with each accepted scene."""
    cfg = FactorialConfig() if config is None else config

    def draft(cell: FactorialCell, seed: int, split: str, index: int) -> Scene:
        return factorial_scene(cell, seed, split, index, cfg, vehicle)

    return build_benchmark(
        "factorial", factorial_cells(), draft, layout_seed_of, cfg.n_train_per_cell, cfg.n_test_per_cell,
        cfg.validity, cfg.disjointness_floor_m, cfg.max_attempts, cfg.to_dict(),
        extra_checks=(("distance_band", lambda scene, grid: distance_band_check(scene, grid, cfg)),),
        on_scene=on_scene, vehicle=vehicle,
    )
