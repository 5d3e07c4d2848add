"""Procedural generator of the Topology-Stress Benchmark (paper §IV-A "Scenario Design", spec §4.2).

Three route-choice families × {medium, hard}; 8 training and 3 test scenes per cell (48 + 18). Each layout is
built in the target frame (target at the origin heading +ỹ, the car reverses into a bay that opens to +ỹ),
mirrored at random (x̃ → −x̃) and placed in the world with the target heading along one of the four axes.

* ``type1`` (roof + side wall): a roof spans the bay's entrance zone from a side wall on one side to a little
  past the bay on the other; the zone is open only on the far side of the roof's end, so the car must come round
  that end and swing in from the opposite side of the wall. Beyond the wall lies a dead-end area.
* ``type2`` (pocket opening away): the target is inside a three-sided pocket whose open side faces away from the
  arrival area; a direct approach meets the closed back wall and must detour round the pocket (hard: wings
  extend the back wall, and one side of the pocket is closed by the boundary, so only one detour remains).
* ``type3`` (outer barrier): a barrier across the lot between the arrival area and the target leaves one
  passage displaced 8–15 m sideways from the target's axis.

The start region lies in the arrival area with every point at least ``structure_clearance_m`` (10.5 m) from the
family structure (roof/wall, pocket, barrier), i.e. beyond the 10 m LiDAR range. Each scene records its
**decisive opening** — the segment every route to the target must cross: the gap between the roof's end and the
next obstacle or boundary (type1), the pocket's mouth (type2), the passage (type3) — in its tags
``opening_x0, opening_y0, opening_x1, opening_y1`` (world frame), and the number of family-structure
obstacles, which come first in the obstacle list, as ``n_structure``.

**Route blocked** (reported by the summary, enforced here on the start region): a start is *route-blocked* when
the straight segment from its reference point to the target's touches an obstacle AND the distance from the
start to the decisive opening's segment exceeds 10 m. A draw is regenerated (counter ``route_stress``) unless at
least ``min_route_blocked`` of the start region's reachable free cells (cell centres) are route-blocked.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, Point
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.ops import unary_union

from np_sim.benchmarks.common import (
    ClutterSpec,
    DraftRejected,
    box,
    jsonable,
    finish_scene,
    irregular_boundary,
    place_clutter,
    rectangle,
    region_cells,
    segment_blocked,
    union_of,
)
from np_sim.benchmarks.frozen import BenchmarkBuild, build_benchmark
from np_sim.benchmarks.layout import DISJOINTNESS_FLOOR_M
from np_sim.benchmarks.validity import ValidityConfig
from np_sim.errors import ConfigError
from np_sim.frames import from_target_frame
from np_sim.geodesic import GeodesicGrid
from np_sim.scene import Obstacle, PolygonObstacle, Scene
from np_sim.vehicle import VehicleSpec

FAMILIES = ("type1", "type2", "type3")
"""Route-choice families: roof + side wall, pocket opening away, outer barrier with displaced passage."""
DIFFICULTIES = ("medium", "hard")
"""Difficulty levels."""
LIDAR_RANGE_M = 10.0
"""The local LiDAR range the family structure must lie beyond for most starts (paper §IV-A)."""


@dataclass(frozen=True)
class TopologyConfig:
    """Parameters of the Topology-Stress generator; pairs indexed by difficulty (medium, hard)."""

    seed: int = 20251
    """Root seed; scene (cell c, slot s, attempt a) uses ``default_rng([seed, layout_seed])`` with
    ``layout_seed = (16 c + s) · 1000 + a``."""
    n_train_per_cell: int = 8
    """Training scenes per cell."""
    n_test_per_cell: int = 3
    """Test scenes per cell."""
    bay_gap_m: tuple[float, float] = (3.3, 2.9)
    """Gap between the bay's side obstacles (m)."""
    entrance_depth_m: tuple[tuple[float, float], tuple[float, float]] = ((7.5, 8.5), (6.8, 7.5))
    """Free depth in front of the bay up to the roof / boundary / barrier (m)."""
    roof_overhang_m: tuple[tuple[float, float], tuple[float, float]] = ((1.5, 3.0), (2.5, 4.0))
    """Type 1: how far the roof reaches past the bay axis on the open side (m)."""
    side_passage_m: tuple[tuple[float, float], tuple[float, float]] = ((7.5, 10.0), (6.0, 7.5))
    """Type 1: width of the way round the roof's end (m)."""
    pocket_side_m: tuple[tuple[float, float], tuple[float, float]] = ((6.0, 9.0), (5.5, 7.0))
    """Type 2: width of the lanes beside the pocket (m)."""
    wing_m: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (3.0, 6.0))
    """Type 2: extra length of the back wall beyond the pocket on each side (m)."""
    passage_width_m: tuple[tuple[float, float], tuple[float, float]] = ((5.5, 6.5), (4.6, 5.2))
    """Type 3: passage width (m)."""
    passage_offset_m: tuple[tuple[float, float], tuple[float, float]] = ((8.0, 11.0), (11.0, 15.0))
    """Type 3: lateral displacement of the passage centre from the target axis (m)."""
    structure_clearance_m: float = 10.5
    """Least distance (m) from the start region to the family structure (beyond the LiDAR range)."""
    region_depth_m: tuple[float, float] = (5.0, 7.0)
    """Start-region extent along the target axis (m)."""
    region_width_m: tuple[float, float] = (7.0, 10.0)
    """Start-region extent across the target axis (m)."""
    clutter_count: tuple[tuple[int, int], tuple[int, int]] = ((2, 4), (4, 7))
    """Clutter items (inclusive range)."""
    clutter_gap_m: tuple[float, float] = (2.8, 2.4)
    """Least gap between clutter and other obstacles (m)."""
    boundary_segments: tuple[tuple[int, int], tuple[int, int]] = ((4, 6), (7, 10))
    """Boundary segment budget (inclusive range)."""
    min_route_blocked: float = 0.75
    """Least route-blocked fraction of the start region's reachable cells (module docstring)."""
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
class TopologyCell:
    """One cell: a route-choice family and a difficulty."""

    family: str
    """Family (`FAMILIES`)."""
    difficulty: str
    """Difficulty (`DIFFICULTIES`)."""

    @property
    def name(self) -> str:
        """``family-difficulty``, the scene's ``cell`` tag."""
        return f"{self.family}-{self.difficulty}"


def topology_cells() -> list[TopologyCell]:
    """The 6 cells in benchmark order: family outer, difficulty inner."""
    return [TopologyCell(f, q) for f in FAMILIES for q in DIFFICULTIES]


@dataclass
class _Draft:
    """A target-frame layout: structure, then the rest; the region, opening and areas kept free."""

    x_range: tuple[float, float]
    y_range: tuple[float, float]
    structure: list[np.ndarray]
    """Family-structure polygons (target frame)."""
    others: list[np.ndarray]
    """Other structural polygons (bay neighbours)."""
    region: np.ndarray
    opening: np.ndarray
    """(2, 2) decisive-opening segment (target frame)."""
    free_zones: list
    """Shapely areas kept free of clutter and boundary irregularity (target frame)."""


_CAR_L, _CAR_W = 4.689, 1.942
_REF_TO_CENTRE = 0.5 * (2.8 + 0.96 - 0.929)
_BAY_BACK = -0.929 - 0.35  # ỹ of the bay's back line (rear bumper 0.35 m in front of it)
_SEAL = 3.0  # how far sealing structure reaches past the lot's rectangle before it is cut by the final boundary
_CELL = 1.5  # geodesic-grid cell (m): the lot's sides sit on the lattice through the target, so the target is a
#              cell centre whatever the world rotation


def _neighbour(rng: np.random.Generator, side: float, gap: float, wall: bool) -> np.ndarray:
    """A bay neighbour on ``side`` (±1 in x̃): a parked car or a wall piece whose inner face is at ±gap/2."""
    inner = side * 0.5 * gap
    if wall:
        t = rng.uniform(0.3, 0.8)
        return box(min(inner, inner + side * t), _BAY_BACK - 0.2, max(inner, inner + side * t), rng.uniform(3.6, 4.2))
    return rectangle(inner + side * 0.5 * _CAR_W, _REF_TO_CENTRE + rng.uniform(-0.3, 0.3), rng.uniform(4.3, 4.9),
                     rng.uniform(1.8, 1.95), 0.5 * math.pi + rng.uniform(-0.04, 0.04))


def _region(rng: np.random.Generator, cfg: TopologyConfig, x_centre: float, y_near: float, toward: float) -> np.ndarray:
    """Start-region quadrilateral with its near edge at ỹ = y_near, extending in direction ``toward`` (±1)."""
    depth, width = rng.uniform(*cfg.region_depth_m), rng.uniform(*cfg.region_width_m)
    y_far = y_near + toward * depth
    corners = box(x_centre - 0.5 * width, min(y_near, y_far), x_centre + 0.5 * width, max(y_near, y_far))
    jitter = rng.uniform(-0.4, 0.4, corners.shape)
    near_rows = np.isclose(corners[:, 1], y_near)
    jitter[near_rows, 1] = np.abs(jitter[near_rows, 1]) * toward  # never closer to the structure
    return corners + jitter


def _type1(rng: np.random.Generator, q: int, cfg: TopologyConfig) -> _Draft:
    """Roof over the entrance zone, wall on the left (x̃ < 0), open on the right past the roof's end."""
    gap = cfg.bay_gap_m[q] * rng.uniform(0.98, 1.04)
    depth = rng.uniform(*cfg.entrance_depth_m[q])
    y_roof = 4.0 + depth
    t_roof = rng.uniform(0.8, 2.0)
    x_wall = -rng.uniform(6.0, 9.0)
    x_end = rng.uniform(*cfg.roof_overhang_m[q])
    y_bottom = _BAY_BACK - 1.0
    roof = np.array([[x_wall - 0.5, y_bottom - _SEAL], [x_wall, y_bottom - _SEAL], [x_wall, y_roof], [x_end, y_roof],
                     [x_end, y_roof + t_roof], [x_wall - 0.5, y_roof + t_roof]])
    others = [_neighbour(rng, 1.0, gap, rng.random() < 0.4)]
    if -0.5 * gap - _CAR_W - 0.3 > x_wall:
        others.append(_neighbour(rng, -1.0, gap, rng.random() < 0.4))
    x_right = x_end + rng.uniform(*cfg.side_passage_m[q])
    x_left = x_wall - 0.5 - rng.uniform(3.0, 7.0)
    y_near = y_roof + t_roof + cfg.structure_clearance_m
    region = _region(rng, cfg, rng.uniform(x_wall + 4.0, x_end - 2.0), y_near, 1.0)
    y_top = region[:, 1].max() + rng.uniform(2.0, 5.0)
    opening = np.array([[x_end, y_roof + 0.5 * t_roof], [x_right, y_roof + 0.5 * t_roof]])
    zones = [ShapelyPolygon(box(x_wall + 0.3, 3.9, x_end + 0.5, y_roof - 0.2)),
             ShapelyPolygon(box(x_end, 3.9, x_right - 0.3, y_roof + t_roof + 3.0))]
    return _Draft((x_left, x_right), (y_bottom, y_top), [roof], others, region, opening, zones)


def _type2(rng: np.random.Generator, q: int, cfg: TopologyConfig) -> _Draft:
    """Three-sided pocket opening to +ỹ; arrivals from −ỹ meet its back wall."""
    gap = cfg.bay_gap_m[q] * rng.uniform(0.98, 1.04)
    t = rng.uniform(0.3, 0.6)
    d_in = rng.uniform(4.1, 4.8)
    g2, yb = 0.5 * gap, _BAY_BACK
    pocket = np.array([[-g2 - t, yb - t], [g2 + t, yb - t], [g2 + t, d_in], [g2, d_in], [g2, yb], [-g2, yb],
                       [-g2, d_in], [-g2 - t, d_in]])
    structure = [pocket]
    wl, wr = (rng.uniform(*cfg.wing_m[q]) for _ in range(2))
    if wl > 0:
        structure.append(box(-g2 - t - wl, yb - t, -g2 - t + 0.01, yb - t + rng.uniform(0.3, 0.6)))
    if wr > 0:
        structure.append(box(g2 + t - 0.01, yb - t, g2 + t + wr, yb - t + rng.uniform(0.3, 0.6)))
    lane_l, lane_r = (rng.uniform(*cfg.pocket_side_m[q]) for _ in range(2))
    x_left, x_right = -g2 - t - wl - lane_l, g2 + t + wr + lane_r
    if q == 1:  # hard: one side of the pocket sealed against the boundary, one detour left
        seal_top = rng.uniform(0.5, d_in)
        if rng.random() < 0.5:
            x_left = -g2 - t - rng.uniform(0.3, 0.8)
            structure[1:] = [s for s in structure[1:] if s[:, 0].min() >= 0]
            structure.append(box(x_left - _SEAL, yb - t, -g2 - t + 0.01, seal_top))
            x_right += rng.uniform(0.0, 2.0)
        else:
            x_right = g2 + t + rng.uniform(0.3, 0.8)
            structure[1:] = [s for s in structure[1:] if s[:, 0].max() <= 0]
            structure.append(box(g2 + t - 0.01, yb - t, x_right + _SEAL, seal_top))
            x_left -= rng.uniform(0.0, 2.0)
    y_top = d_in + rng.uniform(*cfg.entrance_depth_m[q])
    y_near = yb - t - cfg.structure_clearance_m
    half = 0.5 * rng.uniform(*cfg.region_width_m)
    x_c = float(np.clip(rng.uniform(-2.0, 2.0), x_left + half + 0.5, x_right - half - 0.5))
    region = _region(rng, cfg, x_c, y_near, -1.0)
    y_bottom = region[:, 1].min() - rng.uniform(2.0, 5.0)
    opening = np.array([[-g2, d_in], [g2, d_in]])
    zones = [ShapelyPolygon(box(x_left, d_in + 0.1, x_right, y_top))]
    return _Draft((x_left, x_right), (y_bottom, y_top), structure, [], region, opening, zones)


def _type3(rng: np.random.Generator, q: int, cfg: TopologyConfig) -> _Draft:
    """Barrier across the lot beyond the bay with one passage displaced sideways."""
    gap = cfg.bay_gap_m[q] * rng.uniform(0.98, 1.04)
    others = [_neighbour(rng, s, gap, rng.random() < 0.3) for s in (-1.0, 1.0)]
    y_bar = 4.0 + rng.uniform(*cfg.entrance_depth_m[q]) + 0.5
    t_bar = rng.uniform(0.4, 1.2)
    side = 1.0 if rng.random() < 0.5 else -1.0
    centre = side * rng.uniform(*cfg.passage_offset_m[q])
    width = rng.uniform(*cfg.passage_width_m[q])
    p0, p1 = sorted((centre - 0.5 * width, centre + 0.5 * width))
    at_end = rng.random() < 0.4  # passage between the barrier's end and the boundary (on the lattice)
    far_side = rng.uniform(8.0, 12.0)  # extent of the lot on the side away from the passage
    if side > 0:
        x_left = -far_side
        if at_end:
            x_right = p1 = _CELL * math.ceil(p1 / _CELL)
            p0 = p1 - width
        else:
            x_right = p1 + rng.uniform(3.0, 6.0)
    else:
        x_right = far_side
        if at_end:
            x_left = p0 = _CELL * math.floor(p0 / _CELL)
            p1 = p0 + width
        else:
            x_left = p0 - rng.uniform(3.0, 6.0)
    pieces = []
    if p0 > x_left + 0.5:
        pieces.append(box(x_left - _SEAL, y_bar, p0, y_bar + t_bar))
    if p1 < x_right - 0.5:
        pieces.append(box(p1, y_bar, x_right + _SEAL, y_bar + t_bar))
    y_near = y_bar + t_bar + cfg.structure_clearance_m
    half = 0.5 * rng.uniform(*cfg.region_width_m)
    x_c = -side * rng.uniform(0.0, 4.0)
    x_c = float(np.clip(x_c, x_left + half + 0.5, x_right - half - 0.5))
    region = _region(rng, cfg, x_c, y_near, 1.0)
    y_top = region[:, 1].max() + rng.uniform(2.0, 5.0)
    opening = np.array([[p0, y_bar + 0.5 * t_bar], [p1, y_bar + 0.5 * t_bar]])
    zones = [ShapelyPolygon(box(min(-4.0, p0), 3.9, max(4.0, p1), y_bar - 0.2)),
             ShapelyPolygon(box(p0, y_bar - 3.0, p1, y_bar + t_bar + 3.0))]
    return _Draft((x_left, x_right), (_BAY_BACK - 1.0, y_top), pieces, others, region, opening, zones)


_BUILDERS = {"type1": _type1, "type2": _type2, "type3": _type3}


def layout_seed_of(cell_index: int, slot: int, attempt: int) -> int:
    """The ``layout_seed`` tag of draw ``attempt`` for scene ``slot`` of cell ``cell_index`` (training slots
    first, then test slots)."""
    return (16 * cell_index + slot) * 1000 + attempt


def topology_scene(cell: TopologyCell, layout_seed: int, split: str, index: int,
                   config: TopologyConfig | None = None, vehicle: VehicleSpec | None = None) -> Scene:
    """Draw one Topology-Stress scene of ``cell`` from ``layout_seed`` (paper §IV-A); no validity checks yet."""
    cfg = TopologyConfig() if config is None else config
    if cell.family not in FAMILIES or cell.difficulty not in DIFFICULTIES:
        raise ConfigError(f"topology_scene: unknown cell {cell}; expected family in {FAMILIES}, difficulty in "
                          f"{DIFFICULTIES}")
    q = DIFFICULTIES.index(cell.difficulty)
    rng = np.random.default_rng([cfg.seed, layout_seed])
    draft = _BUILDERS[cell.family](rng, q, cfg)
    x0, x1 = (_CELL * math.floor(draft.x_range[0] / _CELL), _CELL * math.ceil(draft.x_range[1] / _CELL))
    y0, y1 = (_CELL * math.floor(draft.y_range[0] / _CELL), _CELL * math.ceil(draft.y_range[1] / _CELL))
    corners = box(x0, y0, x1, y1)
    outline = ShapelyPolygon(corners)
    others = [o for o in draft.others if outline.buffer(-0.2).contains(ShapelyPolygon(o))]
    target_zone = ShapelyPolygon(box(-2.5, _BAY_BACK - 0.5, 2.5, 4.5))
    all_polys = [ShapelyPolygon(p) for p in draft.structure + others]
    protected = unary_union([p.buffer(0.6) for p in all_polys] + draft.free_zones
                            + [ShapelyPolygon(draft.region).buffer(1.0), target_zone])
    n_seg = int(rng.integers(cfg.boundary_segments[q][0], cfg.boundary_segments[q][1] + 1))
    boundary = irregular_boundary(rng, corners, protected, n_seg, chamfer_m=(1.5, 4.0), notch_depth_m=(1.0, 2.0),
                                  notch_width_m=(2.5, 6.0), jitter_m=(0.5, 1.0)[q])
    # structure that reaches past the rectangle is cut by the final boundary, so it seals against it
    structure = []
    for s in draft.structure:
        piece = ShapelyPolygon(s).intersection(ShapelyPolygon(boundary))
        if piece.geom_type != "Polygon" or piece.is_empty:
            raise DraftRejected("draft", "family structure split by the boundary")
        structure.append(np.array(shapely.simplify(piece, 1e-6).exterior.coords)[:-1])
    obstacles: list[Obstacle] = [PolygonObstacle(p) for p in structure + others]
    keepout = unary_union(draft.free_zones + [ShapelyPolygon(draft.region).buffer(1.0), target_zone,
                                              LineString(draft.opening).buffer(2.5)])
    lo, hi = cfg.clutter_count[q]
    count = min(int(rng.integers(lo, hi + 1)), cfg.validity.capacity.max_obstacles - len(obstacles))
    obstacles += place_clutter(rng, count, boundary, obstacles, keepout, ClutterSpec(gap_m=cfg.clutter_gap_m[q]))
    if rng.random() < 0.5:  # mirror x̃ → −x̃
        flip = np.array([-1.0, 1.0])
        boundary, region, opening = boundary * flip, draft.region * flip, draft.opening * flip
        obstacles = [_scaled(o, flip) for o in obstacles]
    else:
        region, opening = draft.region, draft.opening
    heading = [0.0, 0.5 * math.pi, math.pi, -0.5 * math.pi][int(rng.integers(4))]
    pose = np.array([0.0, 0.0, heading])
    world_boundary = from_target_frame(boundary, pose)
    shift = -world_boundary.min(axis=0)
    place = np.array([shift[0], shift[1], heading])

    def to_w(points):
        return from_target_frame(np.asarray(points, float), place)

    obstacles = [_placed(o, to_w) for o in obstacles]
    ow = np.round(to_w(opening), 3)
    tags = {"benchmark": "topology", "split": split, "family": cell.family, "difficulty": cell.difficulty,
            "cell": cell.name, "layout_seed": int(layout_seed), "n_structure": len(structure),
            "opening_x0": float(ow[0, 0]), "opening_y0": float(ow[0, 1]),
            "opening_x1": float(ow[1, 0]), "opening_y1": float(ow[1, 1])}
    return finish_scene(to_w(boundary), obstacles, place, to_w(region), f"topology-{split}-{cell.name}-{index}", tags)


def _scaled(obstacle: Obstacle, flip: np.ndarray) -> Obstacle:
    """Mirror an obstacle by componentwise ``flip``."""
    if isinstance(obstacle, PolygonObstacle):
        return PolygonObstacle(obstacle.vertices * flip)
    return type(obstacle)(obstacle.center * flip, obstacle.radius)


def _placed(obstacle: Obstacle, to_w) -> Obstacle:
    """An obstacle mapped to the world frame by ``to_w``."""
    if isinstance(obstacle, PolygonObstacle):
        return PolygonObstacle(to_w(obstacle.vertices))
    return type(obstacle)(to_w(obstacle.center), obstacle.radius)


def opening_segment(scene: Scene) -> np.ndarray:
    """(2, 2) world-frame decisive opening of a Topology-Stress scene, from its tags (module docstring)."""
    t = scene.tags
    return np.array([[t["opening_x0"], t["opening_y0"]], [t["opening_x1"], t["opening_y1"]]], float)


def route_blocked(scene: Scene, starts_xy) -> np.ndarray:
    """Bool per start (n, 2): the straight segment start → target touches an obstacle AND the decisive opening
    lies more than 10 m (`LIDAR_RANGE_M`) from the start (module docstring)."""
    obstacles = union_of(scene.obstacles)
    opening = LineString(opening_segment(scene))
    xy = np.asarray(starts_xy, float).reshape(-1, 2)
    return np.array([segment_blocked(p, scene.target[:2], obstacles) and opening.distance(Point(p)) > LIDAR_RANGE_M
                     for p in xy], bool)


def structure_beyond_range(scene: Scene, starts_xy) -> np.ndarray:
    """Bool per start (n, 2): every family-structure obstacle (the first ``n_structure``) lies more than 10 m away."""
    structure = union_of(scene.obstacles[: int(scene.tags["n_structure"])])
    xy = np.asarray(starts_xy, float).reshape(-1, 2)
    return np.array([structure.distance(Point(p)) > LIDAR_RANGE_M for p in xy], bool)


def route_stress_check(scene: Scene, grid: GeodesicGrid, config: TopologyConfig | None = None) -> str | None:
    """Generator check: None when at least ``min_route_blocked`` of the start region's reachable free cells are
    route-blocked and have the structure beyond 10 m, else a reason (counted as ``route_stress``)."""
    cfg = TopologyConfig() if config is None else config
    rows, cols = region_cells(grid, scene.start_region)
    keep = grid.free[rows, cols] & np.isfinite(grid.distance[rows, cols])
    centres = grid.origin + grid.cell_m * np.stack([cols[keep], rows[keep]], axis=1)
    if len(centres) == 0:
        return "start region has no reachable cell"
    fraction = float(np.mean(route_blocked(scene, centres) & structure_beyond_range(scene, centres)))
    if fraction < cfg.min_route_blocked:
        return f"route-blocked fraction {fraction:.2f} < {cfg.min_route_blocked}"
    return None


def generate_topology(config: TopologyConfig | None = None, on_scene=None,
                      vehicle: VehicleSpec | None = None) -> BenchmarkBuild:
    """Generate the whole Topology-Stress Benchmark (48 train + 18 test scenes and the 18 × 40 frozen starts)
    from ``config``'s fixed seeds (paper §IV-A); ``on_scene`` is called with each accepted scene."""
    cfg = TopologyConfig() if config is None else config

    def draft(cell: TopologyCell, seed: int, split: str, index: int) -> Scene:
        return topology_scene(cell, seed, split, index, cfg, vehicle)

    return build_benchmark(
        "topology", topology_cells(), draft, layout_seed_of, cfg.n_train_per_cell, cfg.n_test_per_cell,
        cfg.validity, cfg.disjointness_floor_m, cfg.max_attempts, cfg.to_dict(),
        extra_checks=(("route_stress", lambda scene, grid: route_stress_check(scene, grid, cfg)),),
        on_scene=on_scene, vehicle=vehicle,
    )
