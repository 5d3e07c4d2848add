"""Training resets on the delivery site (paper App. C) and the fixed pool of them a training run draws from.

`sample_training_scene` samples one recorded detection state, a free spot as the target and a connected
footprint-free start, and keeps the ten detections nearest to the start. `sample_recorded_reset` (beyond the
paper) replays a clip's own recorded task. `training_pool` draws a seeded pool of resets, and
`cached_training_pool` keeps it in a pickle file of the training run's folder.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import asdict, replace
from pathlib import Path
from typing import Sequence

import numpy as np
import shapely
from shapely.geometry import LinearRing
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips.config import ClipConfig
from np_sim.clips.geometry import clip_grid, geodesic_at, polygon_distances
from np_sim.clips.model import Clip
from np_sim.clips.splits import load_clips
from np_sim.errors import ConfigError, SceneError
from np_sim.kinematics import wrap_angle
from np_sim.scene import PolygonObstacle, Scene
from np_sim.site import SITE_OBSERVATION
from np_sim.vehicle import VehicleSpec


def sample_training_scene(rng: np.random.Generator, clips: Sequence[Clip], *,
                          observation=SITE_OBSERVATION, vehicle: VehicleSpec | None = None,
                          max_tries: int = 50, start_draws: int = 200) -> tuple[Scene, np.ndarray]:
    """One training reset on the site (paper App. C): a random clip and frame, a random spot as target whose
    footprint is free of that frame's detections, a uniform footprint-free start (position over the site,
    heading uniform) connected to the target on the 1.5 m geodesic grid of all the frame's detections, and the
    scene of the ``observation.max_obstacles`` detections nearest to that start (validated for ``observation``).

    Returns ``(scene, start_pose)``. Raises RuntimeError after ``max_tries`` clip/frame/target draws without a
    start (never expected on the shipped site).
    """
    if not clips:
        raise ConfigError("sample_training_scene: expected at least one clip, got none")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    capacity = observation.capacity()
    for _ in range(max_tries):
        clip = clips[int(rng.integers(len(clips)))]
        frame = clip.detection_frame(int(rng.integers(clip.n_frames)))
        _, polygons = clip.detections(frame)
        shapes = _detection_shapes(polygons)
        site = clip.site
        region, ring = ShapelyPolygon(site.boundary), LinearRing(site.boundary)
        target = None
        for index in rng.permutation(len(site.spots)):
            footprint = ShapelyPolygon(vehicle.footprint(site.spots[index].pose))
            if not np.any(shapely.intersects(shapes, footprint)):
                target = site.spots[index].pose
                target_fp = footprint
                break
        if target is None:
            continue
        grid = clip_grid(site, target, list(polygons), ClipConfig(), vehicle)
        lo, hi = site.boundary.min(axis=0), site.boundary.max(axis=0)
        for _ in range(start_draws):
            start = np.array([*rng.uniform(lo, hi), rng.uniform(-math.pi, math.pi)])
            footprint = ShapelyPolygon(vehicle.footprint(start))
            if (not _start_fits(footprint, region, ring, shapes) or not footprint.disjoint(target_fp)
                    or math.isinf(geodesic_at(grid, start[:2]))):
                continue
            order = np.lexsort((np.arange(len(polygons)), polygon_distances(start[:2], polygons)))
            kept = [PolygonObstacle(polygons[j]) for j in order[: observation.max_obstacles]]
            scene = site.scene(target, kept, name=f"{clip.name}/f{frame:03d}/reset",
                               tags={"benchmark": "site", "split": clip.split, "clip": clip.name, "frame": frame,
                                     "source": "detections"})
            scene.validate(source=f"sample_training_scene ({clip.name} frame {frame})", vehicle=vehicle,
                           capacity=capacity)
            return scene, start
    raise RuntimeError(f"sample_training_scene: no valid target and start in {max_tries} clip/frame draws")


def _detection_shapes(polygons: np.ndarray) -> np.ndarray:
    """A frame's detection polygons as a shapely array (empty when the frame has none)."""
    return shapely.polygons(polygons) if len(polygons) else np.array([], dtype=object)


def _start_fits(footprint: ShapelyPolygon, region: ShapelyPolygon, ring: LinearRing, shapes: np.ndarray) -> bool:
    """A start footprint lies strictly inside the site ``region`` (off its boundary ``ring``) and touches none of
    the detection polygons ``shapes`` (built once per frame by the caller: they serve many start draws)."""
    return (region.contains_properly(footprint) and footprint.distance(ring) > 0.0
            and not np.any(shapely.intersects(shapes, footprint)))


def sample_recorded_reset(rng: np.random.Generator, clips: Sequence[Clip], *, vehicle: VehicleSpec | None = None,
                          exact_share: float = 1 / 3, position_sd_m: float = 0.5, heading_sd_deg: float = 10.0,
                          max_tries: int = 200) -> tuple[Scene, np.ndarray]:
    """One reset from a clip's own recorded task (beyond the paper; App. C draws start and target at random): a
    random clip of ``clips`` and frame, the clip's target, and its recorded start — kept exactly with probability
    ``exact_share``, else moved by Gaussian noise (sd ``position_sd_m`` per axis, ``heading_sd_deg``) — with the
    scene the closed loop plans in from that pose (`Clip.frame_scene`: that frame's ten detections nearest to it).

    The clips' starts are chosen hard (tight spots, target-averse headings, detours: `clip_difficulty`), which
    uniform App. C starts rarely are; training on the training clips' own starts puts those situations into the
    pool. A start whose footprint leaves the site, touches its boundary or a detection of the frame is drawn
    again, and so is a frame whose detections touch ``vehicle``'s footprint at the target (never the real
    vehicle's on the recorded clips; a body grown by a training margin, `TrainConfig.train_margin_m`). Returns
    ``(scene, start_pose)``; RuntimeError after ``max_tries`` draws without a free start."""
    if not clips:
        raise ConfigError("sample_recorded_reset: expected at least one clip, got none")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    for _ in range(max_tries):
        clip = clips[int(rng.integers(len(clips)))]
        frame = int(rng.integers(clip.n_frames))
        start = np.array(clip.start, dtype=np.float64)
        if rng.random() >= exact_share:
            start[:2] += rng.normal(0.0, position_sd_m, 2)
            start[2] = wrap_angle(start[2] + math.radians(rng.normal(0.0, heading_sd_deg)))
        _, polygons = clip.detections(clip.detection_frame(frame))
        shapes = _detection_shapes(polygons)
        boundary = clip.site.boundary
        footprint = ShapelyPolygon(vehicle.footprint(start))
        if not _start_fits(footprint, ShapelyPolygon(boundary), LinearRing(boundary), shapes):
            continue
        try:
            scene = clip.frame_scene(frame, pose=start, vehicle=vehicle)
        except SceneError:  # the frame's detections leave the target no room for this body (a grown one)
            continue
        return replace(scene, name=f"{clip.name}/f{frame:03d}/recorded"), start
    raise RuntimeError(f"sample_recorded_reset: no free start in {max_tries} clip/frame draws")


def training_pool(n: int, seed: int, *, observation=SITE_OBSERVATION, vehicle: VehicleSpec | None = None,
                  clips: Sequence[Clip] | None = None, progress: bool = False, recorded_share: float = 0.0,
                  recorded_clips: Sequence[Clip] = ()) -> tuple[list[Scene], np.ndarray]:
    """``n`` training resets of the site (paper App. C, `sample_training_scene`) drawn from ``clips`` (default: the
    1,000 training clips) with ``numpy.random.default_rng(seed)``: the scenes and their (n, 3) start poses, paired
    by index.

    ``recorded_share`` > 0 (beyond the paper) replaces the last ``round(recorded_share · n)`` resets by
    `sample_recorded_reset` draws from ``recorded_clips`` (own generator ``default_rng([seed, 1])``), so the App. C
    part is the same as in a pool drawn without them.

    Training samples resets from this fixed pool (each env reset picks one pair uniformly), so a run is
    reproducible and resumable without storing scenes; a larger pool is closer to a fresh draw per reset.
    """
    if n < 1:
        raise ConfigError(f"training_pool: expected n >= 1 resets, got {n}")
    if not 0.0 <= recorded_share <= 1.0:
        raise ConfigError(f"training_pool: recorded_share must be in [0, 1], got {recorded_share!r}")
    n_recorded = int(round(recorded_share * n))
    if n_recorded and not recorded_clips:
        raise ConfigError("training_pool: recorded_share > 0 needs recorded_clips, got none")
    from tqdm import tqdm

    rng = np.random.default_rng(seed)
    recorded_rng = np.random.default_rng([seed, 1])
    if n_recorded < n:
        clips = load_clips("train") if clips is None else clips
    scenes, starts = [], np.zeros((n, 3))
    for i in tqdm(range(n), desc="site training resets", unit="reset", disable=not progress):
        if i < n - n_recorded:
            scene, starts[i] = sample_training_scene(rng, clips, observation=observation, vehicle=vehicle)
        else:
            scene, starts[i] = sample_recorded_reset(recorded_rng, recorded_clips, vehicle=vehicle)
        scenes.append(scene)
    return scenes, starts


def cached_training_pool(path: str | Path, n: int, seed: int, *, observation=SITE_OBSERVATION,
                         vehicle: VehicleSpec | None = None, clips: Sequence[Clip] | None = None,
                         progress: bool = False, recorded_share: float = 0.0,
                         recorded_clips: Sequence[Clip] = ()) -> tuple[list[Scene], np.ndarray]:
    """`training_pool`, kept in the pickle file ``path`` (a training run's folder): a file drawn with the same
    ``n``, ``seed``, observation, vehicle and recorded resets (share and clip names) is read back (a resumed run
    trains on exactly the pool it started with, without the ~5 min of drawing it again); a missing, unreadable or
    differently drawn file is redrawn and rewritten. ``clips`` given explicitly are not part of the key: pass them
    only with a fresh path."""
    path = Path(path)
    key = {"format": 1, "n": n, "seed": seed, "observation": asdict(observation),
           "vehicle": asdict(vehicle or VehicleSpec())}
    if recorded_share:
        key["recorded"] = {"share": recorded_share, "clips": [c.name for c in recorded_clips]}
    if path.exists():
        try:
            with path.open("rb") as f:
                payload = pickle.load(f)
            if payload.get("key") == key:
                return payload["scenes"], payload["starts"]
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, TypeError):
            pass  # unreadable: drawn again below
    scenes, starts = training_pool(n, seed, observation=observation, vehicle=vehicle, clips=clips, progress=progress,
                                   recorded_share=recorded_share, recorded_clips=recorded_clips)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as f:
        pickle.dump({"key": key, "scenes": scenes, "starts": starts}, f, protocol=pickle.HIGHEST_PROTOCOL)
    tmp.replace(path)
    return scenes, starts
