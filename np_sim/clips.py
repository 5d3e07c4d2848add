"""Recorded-style clips of the delivery site (SPEC §4.4, §8 "Closed loop on a clip"; paper §V-F, App. C).

A **clip** is what the paper's real vehicle recorded on the way back to its parking spot: an initial ego pose
(``start``), an assigned parking pose (``target``, one of the site's spots) and a 10 Hz sequence of frames. Per
frame the clip holds

* the **ground truth**: every object's exact outline (parked vehicles as rectangles, hand carts and pallets as
  rectangles, bins and pedestrians as octagons), world frame; most objects are static, a few carts are pushed
  slowly and most pedestrians walk (straight lines; carts stop at the end of their path, pedestrians turn back);
* the **detections**, stored apart from the ground truth: one five-vertex polygon per detected object (its
  outline resampled to exactly five vertices — a rectangle gains a vertex on its longest edge, a round object
  becomes its circumscribed pentagon — then Gaussian vertex jitter, sd 0.05–0.15 m per clip, truncated at 2.5
  sd, rounded to the centimetre), with drop-outs (an object goes missing for a few frames: a two-state Markov
  chain per object) and missed frames (no perception message at all; frame 0 is never missed).

`Clip.frame_scene` turns frame ``i`` into a `Scene` for a planner: the site boundary, the nearest ten detections
to the ego start (or to a given pose) as five-vertex polygons, the clip target, validated against
`SITE_OBSERVATION` (so the target footprint is free and the scene fits the site observation). On a missed frame
it holds the latest received detections, as a planner would.

**Generation.** Each clip comes from one seed (`generate_candidate`): the target spot, the other spots occupied
with a per-clip probability (some vehicles parked sloppily, off-centre or skewed), clutter along kerbs and in the
open (sometimes right beside the target bay), pedestrians, a footprint-free start (30 %: in the aisle in front of
the target, half of those driving across the bay axis; 20 %: 3–9 m from the target at a random bearing; 50 %:
anywhere on the site; heading uniform unless stated), then movers whose paths avoid the start
and target footprints. Ground-truth objects never come within 0.2 m of the target footprint (any frame) or of the
start footprint (frame 0); detections never overlap the target footprint, nor the start footprint at frame 0 (a
jitter draw that would, or that would make a non-simple polygon, is retried at half the jitter, down to none).

A candidate is **feasible** when, on the footprint-inflated 1.5 m geodesic grid (`np_sim.geodesic`) of the
ground-truth scene, the start is connected to the target at frame 0 and at the last frame (the start's own
cell, or if that cell is blocked the nearest free cell of its 3 × 3 neighbourhood). Infeasible candidates are
rejected (reasons ``no_free_start``, ``start_disconnected``, ``disconnected_last_frame``).

**Difficulty rule** (SPEC §4.4 asks for "high search effort or a required target-averse first manoeuvre"; this
is the measurable stand-in, `DifficultyRule`). A clip is *difficult* when at least one holds:

1. ``detour`` — geodesic detour: straight-line start→target distance d ≥ 5 m (below that the 1.5 m grid
   quantises too coarsely) and geodesic distance on the frame-0 grid / d ≥ 1.5;
2. ``averse_heading`` — the start faces away from the target's heading: cos(θ_start − θ_target) < −0.5 with the
   target within 8 m (the vehicle must turn round in a small space, first moving away);
3. ``front_of_reverse_bay`` — the target is a ``reverse`` bay and the start stands in front of it: in the
   target's frame, 0 < along-heading offset ≤ 9 m and |lateral offset| ≤ 2 m, and the start is not already
   lined up to reverse straight in (cos(θ_start − θ_target) < 0.5), so the vehicle must first pull away;
4. ``tight`` — tight final clearance: the least distance from the target footprint to any ground-truth object
   (over all frames) or to the boundary is < 0.5 m.

**Splits.** Train and eval use disjoint seed streams: train seeds 0, 1, 2, … (clips ``train-0000000`` …),
eval seeds 1,000,000, 1,000,001, … (``eval-1000000`` …). The **1,000 training clips** are the first 1,000
feasible candidates of the train stream (difficult ones included), generated on demand by `load_clips("train")`
and cached in memory. The **47 evaluation clips** are the first 47 difficult feasible candidates of the eval
stream; they ship as ``np_sim/data/clips_eval_v1.json.gz`` (`python -m np_sim.clips --regenerate` rewrites it
and the site file; regenerating reproduces them exactly).

**Training resets** (App. C): `sample_training_scene` samples one recorded detection state, a free spot as the
target and a connected footprint-free start, and keeps the ten detections nearest to the start.

CLI: ``python -m np_sim.clips [--summary] [--figure CLIP_NAME --out PNG] [--regenerate]``.
"""

from __future__ import annotations

import argparse
import gzip
import io
import json
import math
import pickle
import time
from dataclasses import asdict, dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, NamedTuple, Sequence

import numpy as np
import shapely
from shapely.geometry import LinearRing, LineString
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.cli import cli_boundary, positive_int
from np_sim.errors import ConfigError, SceneError
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.frames import place
from np_sim.kinematics import wrap_angle
from np_sim.scene import PolygonObstacle, Scene
from np_sim.site import (
    DATA_DIR,
    SITE_OBSERVATION,
    SITE_PATH,
    Site,
    generate_site,
    load_site,
)
from np_sim.vehicle import VehicleSpec

__all__ = [
    "SITE_OBSERVATION",
    "SPLITS",
    "Clip",
    "ClipConfig",
    "ClipRejected",
    "Difficulty",
    "DifficultyRule",
    "TrackedObject",
    "clip_difficulty",
    "generate_candidate",
    "generate_clip",
    "generate_split",
    "load_clips",
    "load_site",
    "polygon_distances",
    "sample_training_scene",
]

SPLITS = ("train", "eval")
"""Valid clip splits."""
N_CLIPS = {"train": 1000, "eval": 47}
"""Clips per split (paper App. C)."""
SEED_BASE = {"train": 0, "eval": 1_000_000}
"""First seed of each split's stream; train seeds stay below the eval base, so the streams are disjoint."""
EVAL_PATH = DATA_DIR / "clips_eval_v1.json.gz"
"""The shipped evaluation clips."""
CLIPS_FORMAT_VERSION = 1
"""The only clip-file version this module reads and writes."""
OBJECT_KINDS = ("vehicle", "cart", "pallet", "bin", "pedestrian")
"""Kinds of ground-truth objects."""
REJECTION_REASONS = ("no_free_start", "start_disconnected", "disconnected_last_frame", "not_difficult")
"""Why a candidate is not used (``not_difficult`` only in the eval stream)."""


class ClipRejected(SceneError):
    """`generate_clip` was asked for a seed whose candidate is infeasible; ``reason`` says why."""

    def __init__(self, message: str, reason: str):
        super().__init__(message)
        self.reason = reason


# ---------------------------------------------------------------------- configuration


@dataclass(frozen=True)
class ClipConfig:
    """Parameters of the clip generator; the defaults make the shipped and training clips."""

    frame_dt_s: float = 0.1
    """Frame period (s): 10 Hz."""
    n_frames_range: tuple[int, int] = (60, 100)
    """Frames per clip, drawn uniformly, both ends included."""
    occupancy_range: tuple[float, float] = (0.35, 0.75)
    """Per-clip probability that a non-target spot holds a parked vehicle, drawn uniformly."""
    vehicle_length_range_m: tuple[float, float] = (4.3, 5.2)
    """Parked-vehicle length (m)."""
    vehicle_width_range_m: tuple[float, float] = (1.75, 2.1)
    """Parked-vehicle width (m)."""
    parking_offset_sd_m: float = 0.12
    """Sd of a tidy parker's lateral and longitudinal offset from the spot centre (m), truncated at 2 sd."""
    parking_yaw_sd_deg: float = 1.5
    """Sd of a tidy parker's heading error (deg), truncated at 2 sd."""
    sloppy_probability: float = 0.15
    """Probability that a parked vehicle stands off-centre and skewed."""
    sloppy_offset_range_m: tuple[float, float] = (0.3, 0.65)
    """Lateral offset of a sloppy parker, to a random side (m)."""
    sloppy_yaw_deg: float = 6.0
    """Largest heading error of a sloppy parker (deg)."""
    n_bins_range: tuple[int, int] = (1, 5)
    """Bins per clip (both ends included)."""
    n_pallets_range: tuple[int, int] = (0, 3)
    """Pallets per clip (both ends included)."""
    n_carts_range: tuple[int, int] = (1, 3)
    """Hand carts per clip (both ends included)."""
    n_pedestrians_range: tuple[int, int] = (1, 4)
    """Pedestrians per clip (both ends included)."""
    kerb_clutter_probability: float = 0.7
    """Probability that a clutter object stands along a kerb rather than anywhere in the open."""
    near_target_probability: float = 0.2
    """Probability of one clutter object right beside the target bay."""
    near_target_gap_range_m: tuple[float, float] = (0.2, 0.6)
    """Gap between that object and the target footprint (m)."""
    moving_cart_probability: float = 0.35
    """Probability that a cart is being pushed."""
    walking_probability: float = 0.7
    """Probability that a pedestrian walks (else stands)."""
    cart_speed_range_mps: tuple[float, float] = (0.3, 0.8)
    """Speed of a pushed cart (m/s); it stops at the end of its path."""
    pedestrian_speed_range_mps: tuple[float, float] = (0.8, 1.4)
    """Walking speed (m/s); a pedestrian turns back at the ends of its path."""
    path_length_range_m: tuple[float, float] = (4.0, 14.0)
    """Length of a mover's straight path (m)."""
    object_gap_m: float = 0.15
    """Least gap between static ground-truth objects, and from the boundary (m)."""
    target_gap_m: float = 0.2
    """Least gap between any ground-truth object and the target footprint (m)."""
    start_gap_m: float = 0.2
    """Least gap between the start footprint and ground-truth objects or the boundary at frame 0 (m)."""
    start_target_gap_m: float = 0.5
    """Least gap between the start and target footprints (m)."""
    mover_target_gap_m: float = 0.6
    """Least gap between a mover's swept path and the target footprint (m)."""
    mover_start_gap_m: float = 0.5
    """Least gap between a mover's swept path and the start footprint (m)."""
    front_start_probability: float = 0.3
    """Probability that the start is drawn in the aisle in front of the target (arriving at the spot)."""
    front_start_along_m: tuple[float, float] = (4.5, 10.0)
    """Offset of a front start along the target heading (m)."""
    front_start_lateral_m: float = 4.0
    """Largest offset of a front start across the target heading (m)."""
    front_start_cross_probability: float = 0.5
    """Probability that a front start drives across the bay axis (heading ±90° ± 17°), else uniform heading."""
    near_start_probability: float = 0.2
    """Probability that the start is drawn at a random bearing near the target."""
    near_start_range_m: tuple[float, float] = (3.0, 9.0)
    """Distance band of a near start from the target reference point (m)."""
    start_draws: int = 300
    """Start draws before the candidate is rejected as ``no_free_start``."""
    jitter_sd_range_m: tuple[float, float] = (0.05, 0.15)
    """Per-clip sd of the Gaussian detection vertex jitter (m), drawn uniformly."""
    jitter_truncation_sd: float = 2.5
    """Jitter is truncated at this many sd (per coordinate)."""
    dropout_onset_range: tuple[float, float] = (0.01, 0.03)
    """Per-clip probability per frame that a detected object drops out, drawn uniformly."""
    dropout_persistence: float = 0.6
    """Probability that a dropped-out object stays dropped in the next frame (mean burst 2.5 frames)."""
    missed_frame_range: tuple[float, float] = (0.0, 0.02)
    """Per-clip probability that a whole frame is missed, drawn uniformly."""
    grid_m: float = 1.5
    """Cell size of the feasibility and detour grid (m)."""


@dataclass(frozen=True)
class DifficultyRule:
    """Thresholds of the difficulty rule (module docstring)."""

    detour_ratio: float = 1.5
    """Geodesic / straight-line distance at or above which a clip is a detour."""
    detour_min_straight_m: float = 5.0
    """Straight-line distance below which the detour criterion does not apply (m)."""
    averse_cos: float = -0.5
    """cos(θ_start − θ_target) below which the start faces away from the target heading."""
    averse_radius_m: float = 8.0
    """Averse heading counts only with the target this close (m)."""
    front_depth_m: float = 9.0
    """How far in front of a reverse bay (along the target heading) the start may stand (m)."""
    front_halfwidth_m: float = 2.0
    """How far sideways of the bay axis the start may stand (m)."""
    front_aligned_cos: float = 0.5
    """A start with cos(θ_start − θ_target) at or above this can reverse straight in: not target-averse."""
    tight_clearance_m: float = 0.5
    """Final clearance below which a clip is tight (m)."""


# ---------------------------------------------------------------------- data model


@dataclass(frozen=True, eq=False)
class TrackedObject:
    """One ground-truth object: its outline in its own frame and its pose per frame."""

    id: int
    """Object id, unique in the clip; detections refer to it."""
    kind: str
    """One of `OBJECT_KINDS`."""
    outline: np.ndarray
    """(k, 2) outline vertices in the object frame (m), centred on the object, read-only."""
    poses: np.ndarray
    """(1, 3) for a static object or (n_frames, 3) for a mover: x (m), y (m), yaw (rad) per frame, read-only."""

    def __post_init__(self) -> None:
        for name in ("outline", "poses"):
            array = np.array(getattr(self, name), dtype=np.float64)
            array.flags.writeable = False
            object.__setattr__(self, name, array)

    @property
    def moving(self) -> bool:
        """True when the object has a pose per frame."""
        return len(self.poses) > 1

    def polygon(self, frame: int) -> np.ndarray:
        """(k, 2) world-frame outline at ``frame`` (m)."""
        return place(self.outline, self.poses[min(frame, len(self.poses) - 1)])


class Difficulty(NamedTuple):
    """Measured difficulty quantities of a clip and the rule's verdicts (module docstring)."""

    straight_m: float
    """Straight-line start→target distance of the reference points (m)."""
    geodesic_m: float
    """Geodesic distance on the frame-0 ground-truth grid (m); inf when disconnected."""
    detour_ratio: float
    """geodesic_m / straight_m."""
    heading_cos: float
    """cos(θ_start − θ_target)."""
    along_m: float
    """Start offset along the target heading (m), target frame."""
    lateral_m: float
    """Start offset across the target heading (m), target frame."""
    clearance_m: float
    """Least distance from the target footprint to ground-truth objects (all frames) or the boundary (m)."""
    detour: bool
    """Criterion 1."""
    averse_heading: bool
    """Criterion 2."""
    front_of_reverse_bay: bool
    """Criterion 3."""
    tight: bool
    """Criterion 4."""

    @property
    def difficult(self) -> bool:
        """At least one criterion holds."""
        return self.detour or self.averse_heading or self.front_of_reverse_bay or self.tight

    @property
    def reasons(self) -> tuple[str, ...]:
        """Names of the criteria that hold."""
        return tuple(n for n in ("detour", "averse_heading", "front_of_reverse_bay", "tight") if getattr(self, n))


@dataclass(frozen=True, eq=False)
class Clip:
    """One recorded-style clip (module docstring). World frame, metres, radians; frames at ``frame_dt_s``."""

    name: str
    """``"<split>-<seed:07d>"``."""
    seed: int
    """Generator seed; its stream decides the split."""
    split: str
    """``"train"`` or ``"eval"``."""
    start: np.ndarray
    """(3,) initial ego reference-point pose."""
    target: np.ndarray
    """(3,) assigned parking pose: ``site.spots[target_spot].pose``."""
    target_spot: int
    """Index of the target in ``site.spots``."""
    objects: tuple[TrackedObject, ...]
    """Ground-truth objects, ids 0..n−1 in order."""
    frame_missed: np.ndarray
    """(n_frames,) bool: no perception message in this frame (never frame 0)."""
    det_offsets: np.ndarray
    """(n_frames + 1,) int64: frame i's detections are rows det_offsets[i]:det_offsets[i+1]."""
    det_object: np.ndarray
    """(N,) int32 object id of each detection row."""
    det_vertices_cm: np.ndarray
    """(N, 5, 2) int16 detection vertices, world frame, centimetres."""
    jitter_sd_m: float
    """Sd of this clip's vertex jitter (m)."""
    dropout_onset: float
    """Per-frame probability that a detected object drops out."""
    difficulty: Difficulty
    """Measured difficulty (see `clip_difficulty`)."""
    frame_dt_s: float = 0.1
    """Frame period (s)."""
    site: Site = field(default=None, repr=False)  # type: ignore[assignment]
    """The site the clip was recorded on (default: the shipped site)."""

    def __post_init__(self) -> None:
        for name, dtype in (("start", np.float64), ("target", np.float64), ("frame_missed", bool),
                            ("det_offsets", np.int64), ("det_object", np.int32), ("det_vertices_cm", np.int16)):
            array = np.array(getattr(self, name), dtype=dtype)
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        object.__setattr__(self, "objects", tuple(self.objects))
        if self.site is None:
            object.__setattr__(self, "site", load_site())
        if self.det_vertices_cm.shape[1:] != (5, 2) or len(self.det_offsets) != len(self.frame_missed) + 1:
            raise SceneError(f"Clip {self.name}: inconsistent detection arrays")

    @property
    def n_frames(self) -> int:
        """Number of frames."""
        return int(len(self.frame_missed))

    def ground_truth(self, frame: int) -> list[np.ndarray]:
        """World-frame outlines (k, 2) of every ground-truth object at ``frame``, in id order."""
        self._check_frame(frame)
        return [obj.polygon(frame) for obj in self.objects]

    def detections(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """The detections recorded in ``frame``: object ids (n,) and five-vertex polygons (n, 5, 2) in metres.

        Empty on a missed frame (see `detection_frame` for the frame a planner would use).
        """
        self._check_frame(frame)
        lo, hi = self.det_offsets[frame], self.det_offsets[frame + 1]
        return self.det_object[lo:hi].copy(), self.det_vertices_cm[lo:hi].astype(np.float64) / 100.0

    def detection_frame(self, frame: int) -> int:
        """The latest frame ≤ ``frame`` that is not missed: whose detections a planner holds at ``frame``."""
        self._check_frame(frame)
        while self.frame_missed[frame]:
            frame -= 1
        return frame

    def tracked_detections(self, frame: int, window: int,
                           vehicle: VehicleSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Detections filtered over the last ``window`` non-missed frames up to ``frame`` (a track per object id):
        every object detected in any of them, placed at the centroid of its latest detection, with the vertex-wise
        mean of its centred detections in the window as its shape. Averaging k detections divides the vertex
        jitter's sd by √k; an object that drops out is held at its last detection for the rest of the window.
        ``window=1`` is `detections` of `detection_frame` (the raw perception). A filtered outline that is not a
        simple polygon (a turning mover's averaged shape can fold) or would overlap the target footprint of
        ``vehicle`` (default `VehicleSpec()`) is replaced by the object's latest detection, which is neither (the
        clip's construction), so every frame stays a valid scene with a free target as in the raw clip. Returns ids
        (n,) in id order and polygons (n, 5, 2) in metres."""
        if int(window) < 1:
            raise ConfigError(f"Clip.tracked_detections: window must be >= 1 frame, got {window!r}")
        frames, f = [], self.detection_frame(frame)
        while f >= 0 and len(frames) < int(window):
            if not self.frame_missed[f]:
                frames.append(f)
            f -= 1
        latest: dict[int, np.ndarray] = {}
        shapes: dict[int, list[np.ndarray]] = {}
        for f in frames:  # newest first
            for object_id, polygon in zip(*self.detections(f)):
                latest.setdefault(int(object_id), polygon)
                shapes.setdefault(int(object_id), []).append(polygon - polygon.mean(axis=0))
        ids = np.array(sorted(latest), dtype=np.int32)
        polygons = np.array([latest[i].mean(axis=0) + np.mean(shapes[i], axis=0) for i in ids]).reshape(-1, 5, 2)
        if len(ids):
            target = ShapelyPolygon((VehicleSpec() if vehicle is None else vehicle).footprint(self.target))
            shapes_now = shapely.polygons(polygons)
            unusable = shapely.intersects(shapes_now, target) | ~shapely.is_valid(shapes_now)
            for k in np.flatnonzero(unusable):
                polygons[k] = latest[int(ids[k])]
        return ids, polygons

    def frame_scene(self, frame: int, *, ground_truth: bool = False, nearest: int | None = 10, pose=None,
                    vehicle: VehicleSpec | None = None, track_window: int = 1) -> Scene:
        """Frame ``frame`` as a validated `Scene`: site boundary, objects, the clip target.

        Parameters
        ----------
        frame
            Frame index, 0 ≤ frame < n_frames.
        ground_truth
            False (default): the detections held at this frame (`detection_frame`), as five-vertex polygons,
            the ``nearest`` ones to ``pose`` first (distance from the pose's reference point to the polygon, 0
            inside; ties by object id); the scene is validated against ``SITE_OBSERVATION.capacity()`` when
            ``nearest`` ≤ its 10 slots. True: every ground-truth object at this frame (``nearest`` is ignored;
            the closed loop and the validators need them all), validated without a capacity.
        nearest
            How many detections to keep; None keeps all (sorted by distance).
        pose
            Reference pose (x, y[, θ]) the distances are measured from; default the clip start.
        vehicle
            Vehicle whose target footprint must be free; default `VehicleSpec()`.
        track_window
            Detections filtered over this many frames (`tracked_detections`); 1 (default) is the raw frame.
        """
        self._check_frame(frame)
        tags = {"benchmark": "site", "split": self.split, "clip": self.name, "frame": int(frame)}
        if ground_truth:
            polygons = self.ground_truth(frame)
            tags["source"] = "ground_truth"
            capacity = None
        else:
            held = self.detection_frame(frame)
            ids, polygons_array = (self.detections(held) if track_window == 1
                                   else self.tracked_detections(frame, track_window, vehicle))
            reference = np.asarray(self.start if pose is None else pose, dtype=np.float64)[:2]
            order = np.lexsort((ids, polygon_distances(reference, polygons_array)))
            if nearest is not None:
                if int(nearest) < 0:
                    raise ConfigError(f"Clip.frame_scene: nearest must be >= 0 or None, got {nearest!r}")
                order = order[: int(nearest)]
            polygons = [polygons_array[j] for j in order]
            tags.update(source="detections", detection_frame=int(held))
            if track_window != 1:
                tags["track_window"] = int(track_window)
            fits = nearest is not None and int(nearest) <= SITE_OBSERVATION.max_obstacles
            capacity = SITE_OBSERVATION.capacity() if fits else None
        scene = self.site.scene(self.target, [PolygonObstacle(p) for p in polygons],
                                name=f"{self.name}/f{frame:03d}", tags=tags)
        scene.validate(source=f"clip {self.name} frame {frame}", vehicle=vehicle, capacity=capacity)
        return scene

    def _check_frame(self, frame: int) -> None:
        if not 0 <= int(frame) < self.n_frames:
            raise IndexError(f"clip {self.name}: frame {frame} out of range; expected 0 <= frame < {self.n_frames}")

    # ------------------------------------------------------------------ I/O

    def to_dict(self) -> dict:
        """JSON-safe dict (detections as integer centimetres) that `from_dict` turns back into this clip."""
        detections = []
        for i in range(self.n_frames):
            lo, hi = self.det_offsets[i], self.det_offsets[i + 1]
            rows = np.concatenate([self.det_object[lo:hi, None].astype(np.int64),
                                   self.det_vertices_cm[lo:hi].reshape(-1, 10).astype(np.int64)], axis=1)
            detections.append(rows.tolist())
        return {
            "name": self.name,
            "seed": int(self.seed),
            "split": self.split,
            "n_frames": self.n_frames,
            "frame_dt_s": float(self.frame_dt_s),
            "target_spot": int(self.target_spot),
            "target": self.target.tolist(),
            "start": self.start.tolist(),
            "jitter_sd_m": float(self.jitter_sd_m),
            "dropout_onset": float(self.dropout_onset),
            "difficulty": {key: (bool(v) if isinstance(v, (bool, np.bool_)) else _json_float(v))
                           for key, v in self.difficulty._asdict().items()},
            "objects": [{"id": o.id, "kind": o.kind, "outline": o.outline.tolist(), "poses": o.poses.tolist()}
                        for o in self.objects],
            "missed_frames": np.flatnonzero(self.frame_missed).tolist(),
            "detections": detections,
        }

    @classmethod
    def from_dict(cls, data: dict, *, site: Site | None = None, source: str = "<dict>") -> Clip:
        """Inverse of `to_dict`; `SceneError` naming ``source`` and the clip on malformed content."""
        try:
            n_frames = int(data["n_frames"])
            missed = np.zeros(n_frames, dtype=bool)
            missed[np.asarray(data["missed_frames"], dtype=np.int64)] = True
            counts = [len(rows) for rows in data["detections"]]
            if len(counts) != n_frames:
                raise ValueError(f"{len(counts)} detection frames for n_frames = {n_frames}")
            rows = [row for frame_rows in data["detections"] for row in frame_rows]
            table = np.asarray(rows, dtype=np.int64).reshape(len(rows), 11)
            difficulty = Difficulty(**{k: (float(v) if k in _DIFFICULTY_FLOATS else bool(v))
                                       for k, v in data["difficulty"].items()})
            objects = tuple(TrackedObject(int(o["id"]), str(o["kind"]), np.asarray(o["outline"], dtype=np.float64),
                                          np.asarray(o["poses"], dtype=np.float64)) for o in data["objects"])
            return cls(
                name=str(data["name"]), seed=int(data["seed"]), split=str(data["split"]),
                start=np.asarray(data["start"], dtype=np.float64), target=np.asarray(data["target"], dtype=np.float64),
                target_spot=int(data["target_spot"]), objects=objects, frame_missed=missed,
                det_offsets=np.concatenate([[0], np.cumsum(counts)]), det_object=table[:, 0],
                det_vertices_cm=table[:, 1:].reshape(-1, 5, 2), jitter_sd_m=float(data["jitter_sd_m"]),
                dropout_onset=float(data["dropout_onset"]), difficulty=difficulty,
                frame_dt_s=float(data["frame_dt_s"]), site=site,
            )
        except (KeyError, TypeError, ValueError, IndexError) as error:
            name = data.get("name", "?") if isinstance(data, dict) else "?"
            raise SceneError(f"{source}: clip {name}: malformed clip ({type(error).__name__}: {error})") from None


_DIFFICULTY_FLOATS = ("straight_m", "geodesic_m", "detour_ratio", "heading_cos", "along_m", "lateral_m", "clearance_m")


def _json_float(value: float) -> float | str:
    """A float for JSON; inf as the string "inf" (JSON has no infinity)."""
    return "inf" if math.isinf(value) else float(value)


# ---------------------------------------------------------------------- geometry helpers


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


def _rectangle(length: float, width: float) -> np.ndarray:
    """(4, 2) centred rectangle, counter-clockwise, rounded to the millimetre."""
    h, w = 0.5 * length, 0.5 * width
    return np.round(np.array([[-h, -w], [h, -w], [h, w], [-h, w]]), 3)


def _octagon(radius: float) -> np.ndarray:
    """(8, 2) regular octagon of circumradius ``radius``, counter-clockwise, rounded to the millimetre."""
    angles = 2.0 * np.pi * np.arange(8) / 8
    return np.round(radius * np.stack([np.cos(angles), np.sin(angles)], axis=1), 3)


def five_vertex_outline(outline: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The outline (k, 2) as exactly five vertices, same frame, drawing one number from ``rng``.

    k = 5: unchanged. k = 4 (rectangles): one vertex inserted on the longest edge at 30–70 % of its length (the
    outline is unchanged). k > 5 (round objects): the regular pentagon circumscribed about the circle centred at
    the vertex mean through the farthest vertex, rotated by a random angle (covers the object). k = 3: the
    longest edge split at 30–70 %, then the longest edge of the result at its midpoint.
    """
    k = len(outline)
    u = float(rng.random())
    if k == 5:
        return outline.copy()
    if k > 5:
        centre = outline.mean(axis=0)
        radius = float(np.max(np.linalg.norm(outline - centre, axis=1))) / math.cos(math.pi / 5)
        angles = 2.0 * np.pi * (u + np.arange(5)) / 5
        return centre + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    points = [np.asarray(p, dtype=np.float64) for p in outline]
    fraction = 0.3 + 0.4 * u
    while len(points) < 5:
        lengths = [np.linalg.norm(points[(i + 1) % len(points)] - points[i]) for i in range(len(points))]
        i = int(np.argmax(lengths))
        new = points[i] + fraction * (points[(i + 1) % len(points)] - points[i])
        points.insert(i + 1, new)
        fraction = 0.5
    return np.array(points)


def _geodesic_at(grid: GeodesicGrid, xy) -> float:
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


def _grid(site: Site, target, polygons: Sequence[np.ndarray], config: ClipConfig, vehicle: VehicleSpec) -> GeodesicGrid:
    """The footprint-inflated geodesic grid of the site with ``polygons`` as obstacles."""
    scene = site.scene(target, [PolygonObstacle(p) for p in polygons])
    return geodesic_grid(scene, cell_m=config.grid_m, vehicle=vehicle)


# ---------------------------------------------------------------------- difficulty


def measure_difficulty(start, target, spot_kind: str, geodesic_m: float, clearance_m: float,
                       rule: DifficultyRule | None = None) -> Difficulty:
    """Apply the difficulty rule (module docstring) to measured quantities; floats are rounded to 1e-4 first."""
    rule = DifficultyRule() if rule is None else rule
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    delta = start[:2] - target[:2]
    heading = np.array([math.cos(target[2]), math.sin(target[2])])
    straight = round(float(np.hypot(*delta)), 4)
    geodesic = geodesic_m if math.isinf(geodesic_m) else round(float(geodesic_m), 4)
    ratio = round(geodesic / straight, 4) if straight > 0 else math.inf
    cos_h = round(math.cos(wrap_angle(float(start[2] - target[2]))), 4)
    along = round(float(delta @ heading), 4)
    lateral = round(float(delta[0] * -heading[1] + delta[1] * heading[0]), 4)
    clearance = round(float(clearance_m), 4)
    return Difficulty(
        straight_m=straight, geodesic_m=geodesic, detour_ratio=ratio, heading_cos=cos_h, along_m=along,
        lateral_m=lateral, clearance_m=clearance,
        detour=bool(straight >= rule.detour_min_straight_m and ratio >= rule.detour_ratio),
        averse_heading=bool(cos_h < rule.averse_cos and straight <= rule.averse_radius_m),
        front_of_reverse_bay=bool(spot_kind == "reverse" and 0.0 < along <= rule.front_depth_m
                                  and abs(lateral) <= rule.front_halfwidth_m and cos_h < rule.front_aligned_cos),
        tight=bool(clearance < rule.tight_clearance_m),
    )


def target_clearance(site: Site, target, objects: Sequence[TrackedObject], n_frames: int,
                     vehicle: VehicleSpec | None = None) -> float:
    """Least distance (m) from the target footprint to the boundary or to any object outline in any frame."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    footprint = ShapelyPolygon(vehicle.footprint(target))
    best = footprint.distance(LinearRing(site.boundary))
    polygons = []
    for obj in objects:
        frames = range(n_frames) if obj.moving else range(1)
        polygons.extend(shapely.polygons(place(obj.outline, obj.poses[list(frames)])))
    if polygons:
        best = min(best, float(np.min(shapely.distance(footprint, np.array(polygons, dtype=object)))))
    return float(best)


def clip_difficulty(clip: Clip, rule: DifficultyRule | None = None, config: ClipConfig | None = None,
                    vehicle: VehicleSpec | None = None) -> Difficulty:
    """Recompute a clip's difficulty from its ground truth (frame-0 geodesic grid, all-frame clearance)."""
    config = ClipConfig() if config is None else config
    vehicle = VehicleSpec() if vehicle is None else vehicle
    grid = _grid(clip.site, clip.target, clip.ground_truth(0), config, vehicle)
    geodesic = _geodesic_at(grid, clip.start[:2])
    clearance = target_clearance(clip.site, clip.target, clip.objects, clip.n_frames, vehicle)
    return measure_difficulty(clip.start, clip.target, clip.site.spots[clip.target_spot].kind, geodesic, clearance,
                              rule)


# ---------------------------------------------------------------------- generation


def split_of_seed(seed: int) -> str:
    """The split whose seed stream holds ``seed`` (train: 0 ≤ seed < 1,000,000; eval: seed ≥ 1,000,000)."""
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ConfigError(f"clip seed: expected an integer >= 0, got {seed!r}")
    return "eval" if seed >= SEED_BASE["eval"] else "train"


class Candidate(NamedTuple):
    """The outcome of one seed: a clip (feasible) or None, and the rejection reason ("" when feasible)."""

    clip: Clip | None
    """The feasible clip, or None."""
    reason: str
    """"" or one of `REJECTION_REASONS` (all but ``not_difficult``)."""


class _Placer:
    """Static ground-truth placement with the clip's gap rules (shapely geometry, rounded poses)."""

    def __init__(self, site: Site, target_footprint: ShapelyPolygon, config: ClipConfig):
        self.region = ShapelyPolygon(site.boundary)
        self.ring = LinearRing(site.boundary)
        self.target = target_footprint
        self.config = config
        self.placed: list[ShapelyPolygon] = []
        self.start: ShapelyPolygon | None = None

    def fits(self, polygon: ShapelyPolygon, gap: float | None = None) -> bool:
        """The polygon is inside the site and keeps the gaps to the boundary, placed objects, target, start."""
        gap = self.config.object_gap_m if gap is None else gap
        if not self.region.contains_properly(polygon) or polygon.distance(self.ring) < gap:
            return False
        if polygon.distance(self.target) < self.config.target_gap_m:
            return False
        if self.start is not None and polygon.distance(self.start) < self.config.start_gap_m:
            return False
        return all(polygon.distance(other) >= gap for other in self.placed)

    def try_place(self, outline: np.ndarray, pose) -> np.ndarray | None:
        """Round ``pose`` (mm, 1e-4 rad); place and return it if the outline fits there, else None."""
        pose = np.array([round(float(pose[0]), 3), round(float(pose[1]), 3), round(float(wrap_angle(pose[2])), 4)])
        polygon = ShapelyPolygon(place(outline, pose))
        if not self.fits(polygon):
            return None
        self.placed.append(polygon)
        return pose


def _uniform(rng: np.random.Generator, bounds) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def _clutter_outline(kind: str, rng: np.random.Generator) -> np.ndarray:
    """A ground-truth outline for a clutter kind (cart, pallet, bin, pedestrian)."""
    if kind == "cart":
        return _rectangle(_uniform(rng, (0.9, 1.6)), _uniform(rng, (0.6, 0.9)))
    if kind == "pallet":
        return _rectangle(1.2, 1.0 if rng.random() < 0.5 else 0.8)
    if kind == "bin":
        return _octagon(_uniform(rng, (0.3, 0.45)))
    return _octagon(_uniform(rng, (0.25, 0.32)))


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


def generate_candidate(seed: int, *, site: Site | None = None, config: ClipConfig | None = None,
                       rule: DifficultyRule | None = None, vehicle: VehicleSpec | None = None) -> Candidate:
    """Generate the clip candidate of ``seed`` (module docstring), deterministic in the seed.

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
    static: list[tuple[str, np.ndarray, np.ndarray]] = []  # kind, outline, pose

    # parked vehicles in the other spots
    occupancy = _uniform(rng, config.occupancy_range)
    centre_shift = 0.5 * (vehicle.front_m - vehicle.rear_overhang_m)
    for index, spot in enumerate(site.spots):
        occupied = rng.random() < occupancy
        outline = _rectangle(_uniform(rng, config.vehicle_length_range_m), _uniform(rng, config.vehicle_width_range_m))
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
        h, left = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
        centre = spot.pose[:2] + centre_shift * h
        for lat, alo, dyaw in ((lateral, along, yaw), (0.0, 0.0, 0.0)):
            xy = centre + alo * h + lat * left
            pose = placer.try_place(outline, (xy[0], xy[1], th + dyaw))
            if pose is not None:
                static.append(("vehicle", outline, pose))
                break

    # clutter beside the target bay
    if rng.random() < config.near_target_probability:
        kind = ("bin", "pallet", "cart")[int(rng.integers(3))]
        outline = _clutter_outline(kind, rng)
        for _ in range(8):
            th = float(target[2])
            h, left = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
            centre = target[:2] + centre_shift * h
            half = float(np.max(np.abs(outline[:, 1])))
            side = 1.0 if rng.random() < 0.5 else -1.0
            offset = 0.5 * vehicle.width_m + _uniform(rng, config.near_target_gap_range_m) + half
            xy = centre + side * offset * left + rng.uniform(-0.4, 0.4) * vehicle.length_m * h
            pose = placer.try_place(outline, (xy[0], xy[1], th + rng.normal(0.0, 0.05)))
            if pose is not None:
                static.append((kind, outline, pose))
                break

    # clutter along kerbs and in the open; carts and pedestrians decide here whether they move
    movers: list[tuple[str, np.ndarray]] = []
    counts = {kind: int(rng.integers(lo, hi + 1)) for kind, (lo, hi) in (
        ("bin", config.n_bins_range), ("pallet", config.n_pallets_range), ("cart", config.n_carts_range),
        ("pedestrian", config.n_pedestrians_range))}
    for kind, count in counts.items():
        for _ in range(count):
            outline = _clutter_outline(kind, rng)
            moving = ((kind == "cart" and rng.random() < config.moving_cart_probability)
                      or (kind == "pedestrian" and rng.random() < config.walking_probability))
            if moving:
                movers.append((kind, outline))
                continue
            half = float(np.max(np.abs(outline[:, 1])))
            for _ in range(20):
                if kind != "pedestrian" and rng.random() < config.kerb_clutter_probability:
                    pose = _kerb_pose(rng, site, half)
                else:
                    pose = np.array([*_random_site_point(rng, site), rng.uniform(-math.pi, math.pi)])
                pose = placer.try_place(outline, pose)
                if pose is not None:
                    static.append((kind, outline, pose))
                    break

    # the start: footprint-free at frame 0
    start = None
    for _ in range(config.start_draws):
        mode = rng.random()
        heading = rng.uniform(-math.pi, math.pi)
        if mode < config.front_start_probability:
            th = float(target[2])
            h, left = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
            xy = (target[:2] + _uniform(rng, config.front_start_along_m) * h
                  + rng.uniform(-1.0, 1.0) * config.front_start_lateral_m * left)
            if rng.random() < config.front_start_cross_probability:
                heading = th + (0.5 * math.pi if rng.random() < 0.5 else -0.5 * math.pi) + rng.normal(0.0, 0.3)
        elif mode < config.front_start_probability + config.near_start_probability:
            r, phi = _uniform(rng, config.near_start_range_m), rng.uniform(-math.pi, math.pi)
            xy = target[:2] + r * np.array([math.cos(phi), math.sin(phi)])
        else:
            xy = _random_site_point(rng, site)
        pose = np.array([round(float(xy[0]), 3), round(float(xy[1]), 3), round(float(wrap_angle(heading)), 4)])
        footprint = ShapelyPolygon(vehicle.footprint(pose))
        if (placer.region.contains_properly(footprint) and footprint.distance(placer.ring) >= config.start_gap_m
                and footprint.distance(target_fp) >= config.start_target_gap_m
                and all(footprint.distance(p) >= config.start_gap_m for p in placer.placed)):
            start = pose
            placer.start = footprint
            break
    if start is None:
        return Candidate(None, "no_free_start")

    # movers: straight paths clear of static objects, the target and the start
    times = np.arange(n_frames) * config.frame_dt_s
    moving_objects: list[tuple[str, np.ndarray, np.ndarray]] = []
    for kind, outline in movers:
        radius = float(np.max(np.linalg.norm(outline, axis=1)))
        speed = _uniform(rng, config.cart_speed_range_mps if kind == "cart" else config.pedestrian_speed_range_mps)
        for _ in range(30):
            a = _random_site_point(rng, site)
            phi = rng.uniform(-math.pi, math.pi)
            length = _uniform(rng, config.path_length_range_m)
            direction = np.array([math.cos(phi), math.sin(phi)])
            b = a + length * direction
            swept = LineString([a, b]).buffer(radius)
            if (placer.region.contains_properly(swept) and swept.distance(placer.ring) >= config.object_gap_m
                    and swept.distance(target_fp) >= config.mover_target_gap_m
                    and swept.distance(placer.start) >= config.mover_start_gap_m
                    and all(swept.distance(p) >= config.object_gap_m for p in placer.placed)):
                s = speed * times
                if kind == "cart":
                    s = np.minimum(s, length)
                    yaw = np.full(n_frames, phi)
                else:
                    m = np.mod(s, 2.0 * length)
                    back = m > length
                    s = np.where(back, 2.0 * length - m, m)
                    yaw = np.where(back, phi + math.pi, phi)
                xy = a + s[:, None] * direction
                poses = np.stack([np.round(xy[:, 0], 3), np.round(xy[:, 1], 3),
                                  np.round(np.vectorize(wrap_angle)(yaw), 4)], axis=1)
                moving_objects.append((kind, outline, poses))
                break

    objects = tuple(TrackedObject(i, kind, outline, np.asarray(pose).reshape(-1, 3))
                    for i, (kind, outline, pose) in enumerate(static + moving_objects))

    # feasibility on the ground truth, frame 0 and last frame
    first = [o.polygon(0) for o in objects]
    grid = _grid(site, target, first, config, vehicle)
    geodesic = _geodesic_at(grid, start[:2])
    if math.isinf(geodesic):
        return Candidate(None, "start_disconnected")
    if moving_objects:
        last_grid = _grid(site, target, [o.polygon(n_frames - 1) for o in objects], config, vehicle)
        if math.isinf(_geodesic_at(last_grid, start[:2])):
            return Candidate(None, "disconnected_last_frame")
    clearance = target_clearance(site, target, objects, n_frames, vehicle)
    difficulty = measure_difficulty(start, target, site.spots[spot_index].kind, geodesic, clearance, rule)

    # detections
    jitter_sd = round(_uniform(rng, config.jitter_sd_range_m), 4)
    dropout_onset = round(_uniform(rng, config.dropout_onset_range), 4)
    missed = rng.random(n_frames) < _uniform(rng, config.missed_frame_range)
    missed[0] = False
    det_ids, det_frames, det_vertices = _detections(objects, n_frames, missed, jitter_sd, dropout_onset, target_fp,
                                           ShapelyPolygon(vehicle.footprint(start)), config, rng)
    counts_per_frame = np.bincount(det_frames, minlength=n_frames)
    clip = Clip(
        name=f"{split}-{seed:07d}", seed=int(seed), split=split, start=start, target=np.array(target),
        target_spot=spot_index, objects=objects, frame_missed=missed,
        det_offsets=np.concatenate([[0], np.cumsum(counts_per_frame)]), det_object=det_ids,
        det_vertices_cm=det_vertices, jitter_sd_m=jitter_sd, dropout_onset=dropout_onset, difficulty=difficulty,
        frame_dt_s=config.frame_dt_s, site=site,
    )
    return Candidate(clip, "")


def _detections(objects: tuple[TrackedObject, ...], n_frames: int, missed: np.ndarray, jitter_sd: float,
                dropout_onset: float, target_fp: ShapelyPolygon, start_fp: ShapelyPolygon, config: ClipConfig,
                rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Noisy five-vertex detections of every object in every frame, rows sorted by (frame, object id).

    Returns ``(object_ids (N,), frame_of_row (N,), vertices_cm (N, 5, 2) int16)``.
    """
    n_obj = len(objects)
    # drop-out chain per object: visible -> dropped with dropout_onset, dropped -> dropped with persistence
    u = rng.random((n_frames, n_obj))
    visible = np.ones((n_frames, n_obj), dtype=bool)
    state = u[0] >= dropout_onset
    visible[0] = state
    for i in range(1, n_frames):
        state = np.where(state, u[i] >= dropout_onset, u[i] >= config.dropout_persistence)
        visible[i] = state
    visible &= ~missed[:, None]
    base = np.empty((n_obj, n_frames, 5, 2))
    for j, obj in enumerate(objects):
        five = five_vertex_outline(obj.outline, rng)
        poses = obj.poses if obj.moving else np.repeat(obj.poses, n_frames, axis=0)
        base[j] = place(five, poses)
    noise = jitter_sd * np.clip(rng.standard_normal((n_obj, n_frames, 5, 2)), -config.jitter_truncation_sd,
                                config.jitter_truncation_sd)
    cm = np.zeros((n_obj, n_frames, 5, 2), dtype=np.int64)
    todo = np.ones((n_obj, n_frames), dtype=bool)
    protect_start = np.zeros((n_obj, n_frames), dtype=bool)
    protect_start[:, 0] = True
    for scale in (1.0, 0.5, 0.25, 0.0):
        trial = np.rint((base[todo] + scale * noise[todo]) * 100.0).astype(np.int64)
        polygons = shapely.polygons(trial / 100.0)
        ok = shapely.is_valid(polygons) & (shapely.area(polygons) > 0)
        ok &= ~np.any(np.all(trial == np.roll(trial, -1, axis=1), axis=2), axis=1)
        ok &= ~shapely.intersects(polygons, target_fp)
        ok &= ~(protect_start[todo] & shapely.intersects(polygons, start_fp))
        index = np.argwhere(todo)
        accepted = index[ok] if scale > 0.0 else index
        cm[accepted[:, 0], accepted[:, 1]] = trial[ok] if scale > 0.0 else trial
        todo[accepted[:, 0], accepted[:, 1]] = False
        if not todo.any():
            break
    if np.abs(cm).max(initial=0) > np.iinfo(np.int16).max:
        raise SceneError("clip detections: a coordinate exceeds the int16 centimetre range")
    frames, ids = np.nonzero(visible)  # row-major: sorted by frame, then object id
    return ids.astype(np.int32), frames, cm[ids, frames].astype(np.int16)


def generate_clip(seed: int, **kwargs) -> Clip:
    """The feasible clip of ``seed`` (keyword arguments as `generate_candidate`); `ClipRejected` if infeasible."""
    candidate = generate_candidate(seed, **kwargs)
    if candidate.clip is None:
        raise ClipRejected(f"generate_clip: seed {seed} gives no clip: {candidate.reason}", candidate.reason)
    return candidate.clip


# ---------------------------------------------------------------------- splits


@dataclass(frozen=True)
class SplitStatistics:
    """How a split was drawn from its seed stream."""

    split: str
    """``"train"`` or ``"eval"``."""
    examined: int
    """Candidates generated."""
    accepted: int
    """Clips kept."""
    rejected: dict
    """Rejection reason -> count."""
    seconds: float = 0.0
    """Wall time of the generation (s); 0 when read from a file."""


def generate_split(split: str, n: int | None = None, *, site: Site | None = None, config: ClipConfig | None = None,
                   rule: DifficultyRule | None = None) -> tuple[list[Clip], SplitStatistics]:
    """Walk ``split``'s seed stream until ``n`` clips (default `N_CLIPS`) are kept: feasible, and for eval
    also difficult. Returns the clips and the rejection statistics."""
    _check_split(split)
    n = N_CLIPS[split] if n is None else int(n)
    clips: list[Clip] = []
    rejected = {reason: 0 for reason in REJECTION_REASONS if split == "eval" or reason != "not_difficult"}
    seed = SEED_BASE[split]
    t0 = time.perf_counter()
    while len(clips) < n:
        if split == "train" and seed >= SEED_BASE["eval"]:
            raise ConfigError("generate_split: the train seed stream ran into the eval stream's seeds")
        candidate = generate_candidate(seed, site=site, config=config, rule=rule)
        seed += 1
        if candidate.clip is None:
            rejected[candidate.reason] += 1
        elif split == "eval" and not candidate.clip.difficulty.difficult:
            rejected["not_difficult"] += 1
        else:
            clips.append(candidate.clip)
    examined = seed - SEED_BASE[split]
    return clips, SplitStatistics(split, examined, len(clips), rejected, time.perf_counter() - t0)


def _check_split(split: str) -> None:
    if split not in SPLITS:
        raise ConfigError(f"clip split: unknown split {split!r}; expected one of {', '.join(repr(s) for s in SPLITS)}")


def eval_file_text(clips: Sequence[Clip], statistics: SplitStatistics) -> str:
    """The JSON text of the evaluation-clip file (compact, fixed key order, one clip per line)."""
    header = {
        "version": CLIPS_FORMAT_VERSION,
        "site": clips[0].site.name if clips else "",
        "split": "eval",
        "seed_base": SEED_BASE["eval"],
        "candidates": {"examined": statistics.examined, "accepted": statistics.accepted,
                       "rejected": dict(statistics.rejected)},
        "config": asdict(ClipConfig()),
        "rule": asdict(DifficultyRule()),
    }
    lines = [json.dumps(c.to_dict(), separators=(",", ":"), allow_nan=False) for c in clips]
    head = json.dumps(header, separators=(",", ":"))[:-1]
    return head + ',"clips":[\n' + ",\n".join(lines) + "\n]}\n"


def write_eval_file(path: Path, text: str) -> None:
    """Gzip ``text`` to ``path`` reproducibly (no file name, mtime 0)."""
    buffer = io.BytesIO()
    with gzip.GzipFile(filename="", mode="wb", fileobj=buffer, mtime=0, compresslevel=9) as stream:
        stream.write(text.encode("utf-8"))
    Path(path).write_bytes(buffer.getvalue())


def read_eval_file(path: Path | None = None) -> tuple[list[Clip], SplitStatistics]:
    """Read the evaluation-clip file (default the shipped one): clips and their candidate statistics."""
    path = EVAL_PATH if path is None else Path(path)
    source = str(path)
    try:
        data = json.loads(gzip.decompress(path.read_bytes()).decode("utf-8"))
    except FileNotFoundError:
        raise SceneError(f"{source}: evaluation clips not found; run `python -m np_sim.clips --regenerate`") from None
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as error:
        raise SceneError(f"{source}: not a gzipped JSON clip file ({error})") from None
    if not isinstance(data, dict) or data.get("version") != CLIPS_FORMAT_VERSION:
        raise SceneError(f"{source}: version: expected {CLIPS_FORMAT_VERSION}, got "
                         f"{data.get('version') if isinstance(data, dict) else type(data).__name__!r}")
    site = load_site()
    if data.get("site") != site.name:
        raise SceneError(f"{source}: site: expected {site.name!r}, got {data.get('site')!r}")
    clips = [Clip.from_dict(item, site=site, source=source) for item in data["clips"]]
    cand = data["candidates"]
    return clips, SplitStatistics("eval", int(cand["examined"]), int(cand["accepted"]), dict(cand["rejected"]))


@lru_cache(maxsize=None)
def _split_cached(split: str) -> tuple[tuple[Clip, ...], SplitStatistics]:
    if split == "eval":
        clips, stats = read_eval_file()
    else:
        clips, stats = generate_split("train")
    return tuple(clips), stats


def load_clips(split: str) -> list[Clip]:
    """The clips of ``split`` (SPEC §10): ``"train"`` — 1,000 clips generated from the train seed stream on the
    first call (about a minute), then cached in memory; ``"eval"`` — the 47 shipped difficult clips.

    Raises
    ------
    ConfigError
        For a split other than ``"train"`` or ``"eval"``.
    """
    _check_split(split)
    return list(_split_cached(split)[0])


def difficult_clips(split: str) -> list[Clip]:
    """The clips of ``split`` the difficulty rule marks difficult (`clip_difficulty`), in clip order: all 47 eval
    clips; 304 of the 1,000 training clips."""
    return [clip for clip in load_clips(split) if clip.difficulty.difficult]


def split_statistics(split: str) -> SplitStatistics:
    """Candidate statistics of ``split`` (loads or generates it, see `load_clips`)."""
    _check_split(split)
    return _split_cached(split)[1]


# ---------------------------------------------------------------------- training resets


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
        grid = _grid(site, target, list(polygons), ClipConfig(), vehicle)
        lo, hi = site.boundary.min(axis=0), site.boundary.max(axis=0)
        for _ in range(start_draws):
            start = np.array([*rng.uniform(lo, hi), rng.uniform(-math.pi, math.pi)])
            footprint = ShapelyPolygon(vehicle.footprint(start))
            if (not _start_fits(footprint, region, ring, shapes) or not footprint.disjoint(target_fp)
                    or math.isinf(_geodesic_at(grid, start[:2]))):
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
    again. Returns ``(scene, start_pose)``; RuntimeError after ``max_tries`` draws without a free start."""
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
        scene = clip.frame_scene(frame, pose=start, vehicle=vehicle)
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


# ---------------------------------------------------------------------- summary, figure, CLI


def summarize(clips: Sequence[Clip], statistics: SplitStatistics | None = None) -> dict[str, Any]:
    """Counts and rates of a set of clips (frames, detections, drop-outs, jitter, difficulty breakdown)."""
    frames = np.array([c.n_frames for c in clips])
    per_frame = np.concatenate([np.diff(c.det_offsets)[~c.frame_missed] for c in clips])
    objects = np.array([len(c.objects) for c in clips])
    possible = sum(len(c.objects) * int((~c.frame_missed).sum()) for c in clips)
    detected = sum(len(c.det_object) for c in clips)
    missed = sum(int(c.frame_missed.sum()) for c in clips)
    movers = sum(sum(o.moving for o in c.objects) for c in clips)
    kinds = {k: sum(sum(o.kind == k for o in c.objects) for c in clips) for k in OBJECT_KINDS}
    breakdown = {r: sum(r in c.difficulty.reasons for c in clips) for r in
                 ("detour", "averse_heading", "front_of_reverse_bay", "tight")}
    n_reasons = [len(c.difficulty.reasons) for c in clips]
    out = {
        "clips": len(clips),
        "frames_total": int(frames.sum()),
        "frames_per_clip": (int(frames.min()), float(frames.mean()), int(frames.max())),
        "objects_per_clip": (int(objects.min()), float(objects.mean()), int(objects.max())),
        "moving_objects_per_clip": movers / max(len(clips), 1),
        "object_kinds": kinds,
        "detections_per_frame": (float(per_frame.mean()), int(per_frame.max())),
        "dropout_rate": 1.0 - detected / max(possible, 1),
        "missed_frame_rate": missed / max(int(frames.sum()), 1),
        "jitter_sd_m": (min(c.jitter_sd_m for c in clips), max(c.jitter_sd_m for c in clips)),
        "difficult": sum(c.difficulty.difficult for c in clips),
        "difficulty_breakdown": breakdown,
        "difficulty_reasons_per_clip": {k: n_reasons.count(k) for k in sorted(set(n_reasons))},
    }
    if statistics is not None:
        out["candidates"] = {"examined": statistics.examined, "rejected": dict(statistics.rejected),
                             "rejected_fraction": 1.0 - statistics.accepted / max(statistics.examined, 1)}
    return out


def _summary_lines(name: str, s: dict[str, Any]) -> list[str]:
    lines = [
        f"{name}: {s['clips']} clips, {s['frames_total']} frames "
        f"(per clip min/mean/max {s['frames_per_clip'][0]}/{s['frames_per_clip'][1]:.1f}/{s['frames_per_clip'][2]})",
        f"  objects per clip min/mean/max {s['objects_per_clip'][0]}/{s['objects_per_clip'][1]:.1f}/"
        f"{s['objects_per_clip'][2]}, moving {s['moving_objects_per_clip']:.2f}/clip; kinds "
        + ", ".join(f"{k} {v}" for k, v in s["object_kinds"].items()),
        f"  detections per received frame mean {s['detections_per_frame'][0]:.1f}, max {s['detections_per_frame'][1]}"
        f"; drop-out rate {100 * s['dropout_rate']:.2f} %; missed frames {100 * s['missed_frame_rate']:.2f} %"
        f"; jitter sd {s['jitter_sd_m'][0]:.3f}–{s['jitter_sd_m'][1]:.3f} m",
        f"  difficult {s['difficult']}/{s['clips']}: "
        + ", ".join(f"{k} {v}" for k, v in s["difficulty_breakdown"].items())
        + " (criteria per clip: " + ", ".join(f"{k}: {v}" for k, v in s["difficulty_reasons_per_clip"].items()) + ")",
    ]
    if "candidates" in s:
        c = s["candidates"]
        lines.append(f"  candidates examined {c['examined']}, rejected {100 * c['rejected_fraction']:.1f} %: "
                     + ", ".join(f"{k} {v}" for k, v in c["rejected"].items()))
    return lines


def find_clip(name: str) -> Clip:
    """A clip by name: an eval clip from the shipped file, or ``train-<seed>`` generated from its seed."""
    for clip in load_clips("eval"):
        if clip.name == name:
            return clip
    if name.startswith("train-") and name[6:].isdigit():
        return generate_clip(int(name[6:]))
    raise ConfigError(f"find_clip: no clip named {name!r}; expected an eval clip name (e.g. "
                      f"{load_clips('eval')[0].name!r}) or 'train-<seed>'")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m np_sim.clips``."""
    parser = argparse.ArgumentParser(
        prog="python -m np_sim.clips",
        description="The delivery site and its clips (SPEC §4.4): print a summary, draw a clip, or regenerate "
                    "the shipped site and evaluation-clip files.",
        epilog="example: python -m np_sim.clips --summary --figure eval-1000003 --out clip.png",
    )
    parser.add_argument("--summary", action="store_true",
                        help="print site edge count, clip counts, frames, detections, drop-outs, jitter and the "
                             "difficulty breakdown (eval: all 47; train: the first --train-sample clips)")
    parser.add_argument("--train-sample", type=positive_int, default=50, metavar="N",
                        help="train clips the summary generates (default 50; 1000 = all, about a minute)")
    parser.add_argument("--figure", metavar="CLIP_NAME", help="draw this clip (eval name or train-<seed>)")
    parser.add_argument("--out", type=Path, default=None, metavar="PNG",
                        help="figure file (default <CLIP_NAME>.png)")
    parser.add_argument("--regenerate", action="store_true",
                        help="regenerate np_sim/data/site_v1.json and clips_eval_v1.json.gz from their seeds")
    return parser


@cli_boundary
def main(argv=None) -> dict:
    """Run the CLI (see `build_parser`); returns what it printed as a dict (for tests). A user's mistake (an
    unknown clip name, an unwritable figure path) prints one ``error:`` line and exits with status 2."""
    from np_sim.plotting import plot_clip  # matplotlib stays out of the library's import path

    args = build_parser().parse_args(argv)
    if not (args.summary or args.figure or args.regenerate):
        build_parser().error("nothing to do: give --summary, --figure CLIP_NAME or --regenerate")
    result: dict[str, Any] = {}
    if args.regenerate:
        t0 = time.perf_counter()
        site = generate_site(0)
        DATA_DIR.mkdir(parents=True, exist_ok=True)
        site.save(SITE_PATH)
        clips, stats = generate_split("eval", site=site)
        write_eval_file(EVAL_PATH, eval_file_text(clips, stats))
        _split_cached.cache_clear()
        seconds = time.perf_counter() - t0
        print(f"wrote {SITE_PATH} ({SITE_PATH.stat().st_size} bytes) and {EVAL_PATH} "
              f"({EVAL_PATH.stat().st_size} bytes) in {seconds:.1f} s")
        result["regenerate_s"] = seconds
    if args.summary:
        site = load_site()
        eval_clips, eval_stats = load_clips("eval"), split_statistics("eval")
        t0 = time.perf_counter()
        train_clips, train_stats = generate_split("train", args.train_sample)
        train_s = time.perf_counter() - t0
        result["site_edges"] = site.n_edges
        result["eval"] = summarize(eval_clips, eval_stats)
        result["train"] = summarize(train_clips, train_stats)
        print(f"site {site.name}: {site.n_edges} boundary edges (observation slots "
              f"{SITE_OBSERVATION.max_boundary_segments}), {len(site.spots)} spots ("
              + ", ".join(f"{k} {sum(s.kind == k for s in site.spots)}" for k in ("reverse", "forward", "parallel",
                                                                                   "angled")) + ")")
        print(f"splits: train {N_CLIPS['train']} clips (seeds from {SEED_BASE['train']}, generated on demand), "
              f"eval {len(eval_clips)} clips (seeds from {SEED_BASE['eval']}, shipped {EVAL_PATH.name})")
        for line in _summary_lines("eval", result["eval"]):
            print(line)
        for line in _summary_lines(f"train (first {len(train_clips)} of {N_CLIPS['train']}, "
                                   f"{1000 * train_s / max(train_stats.examined, 1):.0f} ms per candidate)",
                                   result["train"]):
            print(line)
    if args.figure:
        from matplotlib.figure import Figure

        clip = find_clip(args.figure)
        fig = Figure(figsize=(11, 8.5))
        plot_clip(fig.add_subplot(), clip)
        out = args.out if args.out is not None else Path(f"{clip.name}.png")
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(out, dpi=140, bbox_inches="tight")
        print(f"wrote {out}")
        result["figure"] = out
    return result


if __name__ == "__main__":
    main()
