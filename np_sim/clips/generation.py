"""Generation of the clips: each clip comes from one seed (`generate_candidate`).

The steps, each drawing from the seed's one generator in this order: the number of frames and the target spot;
the other spots occupied with a per-clip probability (some vehicles parked sloppily, off-centre or skewed,
`_park_vehicles`); maybe one clutter object right beside the target bay (`_clutter_beside_target`); clutter along
kerbs and in the open, where carts and pedestrians decide whether they move (`_clutter`); a footprint-free start
(`_draw_start`: 30 %: in the aisle in front of the target, half of those driving across the bay axis; 20 %: 3–9 m
from the target at a random bearing; 50 %: anywhere on the site; heading uniform unless stated); then movers whose
straight paths avoid the start and target footprints (`_moving_objects`); last the detections
(`np_sim.clips.detections`). Ground-truth objects never come within 0.2 m of the target footprint (any frame) or
of the start footprint (frame 0).

A candidate is **feasible** when, on the footprint-inflated 1.5 m geodesic grid (`np_sim.geodesic`) of the
ground-truth scene, the start is connected to the target at frame 0 and at the last frame (the start's own
cell, or if that cell is blocked the nearest free cell of its 3 × 3 neighbourhood). Infeasible candidates are
rejected (reasons ``no_free_start``, ``start_disconnected``, ``disconnected_last_frame``).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from shapely.geometry import LinearRing, LineString
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips.config import SEED_BASE, ClipConfig
from np_sim.clips.detections import draw_detections
from np_sim.clips.difficulty import DifficultyRule, measure_difficulty, target_clearance
from np_sim.clips.geometry import clip_grid, geodesic_at, octagon, rectangle
from np_sim.clips.model import Clip, TrackedObject
from np_sim.errors import ConfigError, SceneError
from np_sim.frames import place
from np_sim.kinematics import wrap_angle
from np_sim.site import Site, load_site
from np_sim.vehicle import VehicleSpec

Placed = tuple[str, np.ndarray, np.ndarray]
"""A ground-truth object before it gets its id: kind, outline (k, 2), pose (3,) or poses (n_frames, 3)."""


class ClipRejected(SceneError):
    """`generate_clip` was asked for a seed whose candidate is infeasible; ``reason`` says why."""

    def __init__(self, message: str, reason: str):
        super().__init__(message)
        self.reason = reason


class Candidate(NamedTuple):
    """The outcome of one seed: a clip (feasible) or None, and the rejection reason ("" when feasible)."""

    clip: Clip | None
    """The feasible clip, or None."""
    reason: str
    """"" or one of `np_sim.clips.config.REJECTION_REASONS` (all but ``not_difficult``)."""


def split_of_seed(seed: int) -> str:
    """The split whose seed stream holds ``seed`` (train: 0 ≤ seed < 1,000,000; eval: seed ≥ 1,000,000)."""
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ConfigError(f"clip seed: expected an integer >= 0, got {seed!r}")
    return "eval" if seed >= SEED_BASE["eval"] else "train"


def generate_candidate(seed: int, *, site: Site | None = None, config: ClipConfig | None = None,
                       rule: DifficultyRule | None = None, vehicle: VehicleSpec | None = None) -> Candidate:
    """Generate the clip candidate of ``seed`` (this module's docstring), deterministic in the seed.

    Returns a `Candidate`: the clip when feasible (its difficulty measured, detections generated), else None
    and the rejection reason. Difficulty does not reject here; the eval stream filters on it.
    """
    split = split_of_seed(seed)
    site = load_site() if site is None else site
    config = ClipConfig() if config is None else config
    vehicle = VehicleSpec() if vehicle is None else vehicle
    rng = np.random.default_rng(seed)
    n_frames = int(rng.integers(config.n_frames_range[0], config.n_frames_range[1] + 1))
    spot_index = int(rng.integers(len(site.spots)))
    target = site.spots[spot_index].pose
    target_fp = ShapelyPolygon(vehicle.footprint(target))
    placer = _Placer(site, target_fp, config)
    static = _park_vehicles(rng, site, spot_index, placer, config, vehicle)
    static += _clutter_beside_target(rng, target, placer, config, vehicle)
    clutter, movers = _clutter(rng, site, placer, config)
    start = _draw_start(rng, site, target, placer, config, vehicle)
    if start is None:
        return Candidate(None, "no_free_start")
    placer.start = ShapelyPolygon(vehicle.footprint(start))
    moving = _moving_objects(rng, site, placer, movers, n_frames, config)
    objects = tuple(TrackedObject(i, kind, outline, np.asarray(pose).reshape(-1, 3))
                    for i, (kind, outline, pose) in enumerate(static + clutter + moving))
    geodesic, reason = _connectivity(site, target, start, objects, n_frames, config, vehicle)
    if reason:
        return Candidate(None, reason)
    clearance = target_clearance(site, target, objects, n_frames, vehicle)
    difficulty = measure_difficulty(start, target, site.spots[spot_index].kind, geodesic, clearance, rule)
    detections = draw_detections(rng, objects, n_frames, target_fp, placer.start, config)
    clip = Clip(name=f"{split}-{seed:07d}", seed=int(seed), split=split, start=start, target=np.array(target),
                target_spot=spot_index, objects=objects, difficulty=difficulty, frame_dt_s=config.frame_dt_s,
                site=site, **detections)
    return Candidate(clip, "")


def generate_clip(seed: int, **kwargs) -> Clip:
    """The feasible clip of ``seed`` (keyword arguments as `generate_candidate`); `ClipRejected` if infeasible."""
    candidate = generate_candidate(seed, **kwargs)
    if candidate.clip is None:
        raise ClipRejected(f"generate_clip: seed {seed} gives no clip: {candidate.reason}", candidate.reason)
    return candidate.clip


class _Placer:
    """Ground-truth placement with the clip's gap rules (shapely geometry, rounded poses)."""

    def __init__(self, site: Site, target_footprint: ShapelyPolygon, config: ClipConfig):
        self.region = ShapelyPolygon(site.boundary)
        self.ring = LinearRing(site.boundary)
        self.target = target_footprint
        self.config = config
        self.placed: list[ShapelyPolygon] = []
        self.start: ShapelyPolygon | None = None

    def clear(self, shape, *, gap: float, target_gap: float, start_gap: float) -> bool:
        """``shape`` lies strictly inside the site, at least ``gap`` from the boundary and every placed object,
        ``target_gap`` from the target footprint and ``start_gap`` from the start footprint (once drawn)."""
        return (self.region.contains_properly(shape) and shape.distance(self.ring) >= gap
                and shape.distance(self.target) >= target_gap
                and (self.start is None or shape.distance(self.start) >= start_gap)
                and all(shape.distance(other) >= gap for other in self.placed))

    def try_place(self, outline: np.ndarray, pose) -> np.ndarray | None:
        """Round ``pose`` (mm, 1e-4 rad); place and return it if the outline fits there, else None."""
        pose = np.array([round(float(pose[0]), 3), round(float(pose[1]), 3), round(float(wrap_angle(pose[2])), 4)])
        polygon = ShapelyPolygon(place(outline, pose))
        c = self.config
        if not self.clear(polygon, gap=c.object_gap_m, target_gap=c.target_gap_m, start_gap=c.start_gap_m):
            return None
        self.placed.append(polygon)
        return pose


def _uniform(rng: np.random.Generator, bounds) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def _axes(heading: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors along ``heading`` and to its left."""
    return np.array([math.cos(heading), math.sin(heading)]), np.array([-math.sin(heading), math.cos(heading)])


def _park_vehicles(rng: np.random.Generator, site: Site, spot_index: int, placer: _Placer, config: ClipConfig,
                   vehicle: VehicleSpec) -> list[Placed]:
    """Parked vehicles in the occupied spots other than the target; a sloppy parker that does not fit its
    offset pose is put in the spot's centre. Draws the same numbers for every spot, occupied or not."""
    occupancy = _uniform(rng, config.occupancy_range)
    centre_shift = 0.5 * (vehicle.front_m - vehicle.rear_overhang_m)
    parked: list[Placed] = []
    for index, spot in enumerate(site.spots):
        occupied = rng.random() < occupancy
        outline = rectangle(_uniform(rng, config.vehicle_length_range_m), _uniform(rng, config.vehicle_width_range_m))
        sloppy = rng.random() < config.sloppy_probability
        side = 1.0 if rng.random() < 0.5 else -1.0
        lateral = (side * _uniform(rng, config.sloppy_offset_range_m) if sloppy
                   else config.parking_offset_sd_m * float(np.clip(rng.normal(), -2, 2)))
        along = config.parking_offset_sd_m * float(np.clip(rng.normal(), -2, 2))
        yaw = math.radians(rng.uniform(-config.sloppy_yaw_deg, config.sloppy_yaw_deg) if sloppy
                           else config.parking_yaw_sd_deg * float(np.clip(rng.normal(), -2, 2)))
        if index == spot_index or not occupied:
            continue
        th = float(spot.pose[2])
        h, left = _axes(th)
        centre = spot.pose[:2] + centre_shift * h
        for lat, alo, dyaw in ((lateral, along, yaw), (0.0, 0.0, 0.0)):
            xy = centre + alo * h + lat * left
            pose = placer.try_place(outline, (xy[0], xy[1], th + dyaw))
            if pose is not None:
                parked.append(("vehicle", outline, pose))
                break
    return parked


def _clutter_beside_target(rng: np.random.Generator, target: np.ndarray, placer: _Placer, config: ClipConfig,
                           vehicle: VehicleSpec) -> list[Placed]:
    """With ``config.near_target_probability``, one bin, pallet or cart beside the target bay (up to 8 tries)."""
    if rng.random() >= config.near_target_probability:
        return []
    kind = ("bin", "pallet", "cart")[int(rng.integers(3))]
    outline = _clutter_outline(kind, rng)
    th = float(target[2])
    h, left = _axes(th)
    centre = target[:2] + 0.5 * (vehicle.front_m - vehicle.rear_overhang_m) * h
    half = float(np.max(np.abs(outline[:, 1])))
    for _ in range(8):
        side = 1.0 if rng.random() < 0.5 else -1.0
        offset = 0.5 * vehicle.width_m + _uniform(rng, config.near_target_gap_range_m) + half
        xy = centre + side * offset * left + rng.uniform(-0.4, 0.4) * vehicle.length_m * h
        pose = placer.try_place(outline, (xy[0], xy[1], th + rng.normal(0.0, 0.05)))
        if pose is not None:
            return [(kind, outline, pose)]
    return []


def _clutter(rng: np.random.Generator, site: Site, placer: _Placer,
             config: ClipConfig) -> tuple[list[Placed], list[tuple[str, np.ndarray]]]:
    """Bins, pallets, carts and pedestrians: the static ones placed along kerbs or in the open (up to 20 tries
    each), and the kinds and outlines of the carts that are pushed and the pedestrians that walk."""
    counts = {kind: int(rng.integers(lo, hi + 1)) for kind, (lo, hi) in (
        ("bin", config.n_bins_range), ("pallet", config.n_pallets_range), ("cart", config.n_carts_range),
        ("pedestrian", config.n_pedestrians_range))}
    static: list[Placed] = []
    movers: list[tuple[str, np.ndarray]] = []
    for kind, count in counts.items():
        for _ in range(count):
            outline = _clutter_outline(kind, rng)
            moving = ((kind == "cart" and rng.random() < config.moving_cart_probability)
                      or (kind == "pedestrian" and rng.random() < config.walking_probability))
            if moving:
                movers.append((kind, outline))
                continue
            pose = _place_clutter(rng, site, placer, kind, outline, config)
            if pose is not None:
                static.append((kind, outline, pose))
    return static, movers


def _place_clutter(rng: np.random.Generator, site: Site, placer: _Placer, kind: str, outline: np.ndarray,
                   config: ClipConfig) -> np.ndarray | None:
    """Place one static clutter object along a kerb (not pedestrians) or anywhere; its pose, or None after 20
    tries."""
    half = float(np.max(np.abs(outline[:, 1])))
    for _ in range(20):
        if kind != "pedestrian" and rng.random() < config.kerb_clutter_probability:
            pose = _kerb_pose(rng, site, half)
        else:
            pose = np.array([*_random_site_point(rng, site), rng.uniform(-math.pi, math.pi)])
        pose = placer.try_place(outline, pose)
        if pose is not None:
            return pose
    return None


def _clutter_outline(kind: str, rng: np.random.Generator) -> np.ndarray:
    """A ground-truth outline for a clutter kind (cart, pallet, bin, pedestrian)."""
    if kind == "cart":
        return rectangle(_uniform(rng, (0.9, 1.6)), _uniform(rng, (0.6, 0.9)))
    if kind == "pallet":
        return rectangle(1.2, 1.0 if rng.random() < 0.5 else 0.8)
    if kind == "bin":
        return octagon(_uniform(rng, (0.3, 0.45)))
    return octagon(_uniform(rng, (0.25, 0.32)))


def _random_site_point(rng: np.random.Generator, site: Site) -> np.ndarray:
    lo, hi = site.boundary.min(axis=0), site.boundary.max(axis=0)
    return rng.uniform(lo, hi)


def _kerb_pose(rng: np.random.Generator, site: Site, half_depth: float) -> np.ndarray:
    """A pose along a random boundary edge (chosen by length), set back from it, aligned with it."""
    a = site.boundary
    b = np.roll(a, -1, axis=0)
    lengths = np.linalg.norm(b - a, axis=1)
    i = int(rng.choice(len(a), p=lengths / lengths.sum()))
    t = (b[i] - a[i]) / lengths[i]
    inward = np.array([-t[1], t[0]])  # counter-clockwise ring: interior on the left
    xy = a[i] + rng.uniform(0.0, 1.0) * (b[i] - a[i]) + (half_depth + rng.uniform(0.2, 0.8)) * inward
    return np.array([xy[0], xy[1], math.atan2(t[1], t[0]) + rng.normal(0.0, 0.15)])


def _draw_start(rng: np.random.Generator, site: Site, target: np.ndarray, placer: _Placer, config: ClipConfig,
                vehicle: VehicleSpec) -> np.ndarray | None:
    """The start pose: the first of ``config.start_draws`` draws (`_start_draw`) whose footprint keeps its gaps
    to the boundary, the placed objects and the target footprint; None when none does."""
    for _ in range(config.start_draws):
        pose = _start_draw(rng, site, target, config)
        footprint = ShapelyPolygon(vehicle.footprint(pose))
        if placer.clear(footprint, gap=config.start_gap_m, target_gap=config.start_target_gap_m, start_gap=0.0):
            return pose
    return None


def _start_draw(rng: np.random.Generator, site: Site, target: np.ndarray, config: ClipConfig) -> np.ndarray:
    """One start draw, rounded (mm, 1e-4 rad): in front of the target, near it, or anywhere on the site."""
    mode = rng.random()
    heading = rng.uniform(-math.pi, math.pi)
    if mode < config.front_start_probability:
        th = float(target[2])
        h, left = _axes(th)
        xy = (target[:2] + _uniform(rng, config.front_start_along_m) * h
              + rng.uniform(-1.0, 1.0) * config.front_start_lateral_m * left)
        if rng.random() < config.front_start_cross_probability:
            heading = th + (0.5 * math.pi if rng.random() < 0.5 else -0.5 * math.pi) + rng.normal(0.0, 0.3)
    elif mode < config.front_start_probability + config.near_start_probability:
        r, phi = _uniform(rng, config.near_start_range_m), rng.uniform(-math.pi, math.pi)
        xy = target[:2] + r * np.array([math.cos(phi), math.sin(phi)])
    else:
        xy = _random_site_point(rng, site)
    return np.array([round(float(xy[0]), 3), round(float(xy[1]), 3), round(float(wrap_angle(heading)), 4)])


def _moving_objects(rng: np.random.Generator, site: Site, placer: _Placer, movers: Sequence[tuple[str, np.ndarray]],
                    n_frames: int, config: ClipConfig) -> list[Placed]:
    """The movers on straight paths (up to 30 draws each) whose swept outline keeps its gaps to the boundary,
    the static objects, the target and the start; a mover without such a path is left out."""
    times = np.arange(n_frames) * config.frame_dt_s
    moving: list[Placed] = []
    for kind, outline in movers:
        radius = float(np.max(np.linalg.norm(outline, axis=1)))
        speed = _uniform(rng, config.cart_speed_range_mps if kind == "cart" else config.pedestrian_speed_range_mps)
        for _ in range(30):
            a = _random_site_point(rng, site)
            phi = rng.uniform(-math.pi, math.pi)
            length = _uniform(rng, config.path_length_range_m)
            direction = np.array([math.cos(phi), math.sin(phi)])
            swept = LineString([a, a + length * direction]).buffer(radius)
            if placer.clear(swept, gap=config.object_gap_m, target_gap=config.mover_target_gap_m,
                            start_gap=config.mover_start_gap_m):
                moving.append((kind, outline, mover_poses(kind, a, phi, length, speed * times)))
                break
    return moving


def mover_poses(kind: str, a: np.ndarray, phi: float, length: float, travelled: np.ndarray) -> np.ndarray:
    """(n, 3) poses, rounded (mm, 1e-4 rad), of a mover on the straight path of ``length`` from ``a`` at heading
    ``phi`` after ``travelled`` (n,) metres: a cart stops at the path's end, a pedestrian turns back at either
    end (and faces the way it walks)."""
    direction = np.array([math.cos(phi), math.sin(phi)])
    if kind == "cart":
        s = np.minimum(travelled, length)
        yaw = np.full(len(travelled), phi)
    else:
        m = np.mod(travelled, 2.0 * length)
        back = m > length
        s = np.where(back, 2.0 * length - m, m)
        yaw = np.where(back, phi + math.pi, phi)
    xy = a + s[:, None] * direction
    return np.stack([np.round(xy[:, 0], 3), np.round(xy[:, 1], 3), np.round(np.vectorize(wrap_angle)(yaw), 4)],
                    axis=1)


def _connectivity(site: Site, target: np.ndarray, start: np.ndarray, objects: Sequence[TrackedObject],
                  n_frames: int, config: ClipConfig, vehicle: VehicleSpec) -> tuple[float, str]:
    """The start's geodesic distance on the frame-0 ground-truth grid, and "" when the start is connected to the
    target at frame 0 and (with movers) at the last frame, else the rejection reason."""
    grid = clip_grid(site, target, [o.polygon(0) for o in objects], config, vehicle)
    geodesic = geodesic_at(grid, start[:2])
    if math.isinf(geodesic):
        return geodesic, "start_disconnected"
    if any(o.moving for o in objects):
        last_grid = clip_grid(site, target, [o.polygon(n_frames - 1) for o in objects], config, vehicle)
        if math.isinf(geodesic_at(last_grid, start[:2])):
            return geodesic, "disconnected_last_frame"
    return geodesic, ""
