"""The clip data model (spec §4.4, §8 "Closed loop on a clip"; paper §V-F, App. C).

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
it holds the latest received detections, as a planner would. A perception model of the closed loop (a filter
over several frames: `tracking.perception`) hands its own detections to `Clip.frame_scene`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from np_sim.clips.difficulty import DIFFICULTY_FLOATS, Difficulty
from np_sim.clips.geometry import polygon_distances
from np_sim.errors import ConfigError, SceneError
from np_sim.frames import place
from np_sim.scene import PolygonObstacle, Scene
from np_sim.site import SITE_OBSERVATION, Site, load_site
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True, eq=False)
class TrackedObject:
    """One ground-truth object: its outline in its own frame and its pose per frame."""

    id: int
    """Object id, unique in the clip; detections refer to it."""
    kind: str
    """One of `np_sim.clips.config.OBJECT_KINDS`."""
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

    def frame_scene(self, frame: int, *, ground_truth: bool = False, nearest: int | None = 10, pose=None,
                    vehicle: VehicleSpec | None = None,
                    detections: tuple[np.ndarray, np.ndarray] | None = None) -> Scene:
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
        detections
            Object ids (n,) and five-vertex polygons (n, 5, 2) in metres to use instead of the recorded ones held
            at this frame (a perception filter's output, `tracking.perception`); not with ``ground_truth``.
        """
        self._check_frame(frame)
        tags = {"benchmark": "site", "split": self.split, "clip": self.name, "frame": int(frame)}
        if ground_truth:
            if detections is not None:
                raise ConfigError("Clip.frame_scene: give detections or ground_truth=True, not both")
            polygons = self.ground_truth(frame)
            tags["source"] = "ground_truth"
            capacity = None
        else:
            held = self.detection_frame(frame)
            ids, polygons_array = self.detections(held) if detections is None else detections
            reference = np.asarray(self.start if pose is None else pose, dtype=np.float64)[:2]
            order = np.lexsort((ids, polygon_distances(reference, polygons_array)))
            if nearest is not None:
                if int(nearest) < 0:
                    raise ConfigError(f"Clip.frame_scene: nearest must be >= 0 or None, got {nearest!r}")
                order = order[: int(nearest)]
            polygons = [polygons_array[j] for j in order]
            tags.update(source="detections", detection_frame=int(held))
            fits = nearest is not None and int(nearest) <= SITE_OBSERVATION.max_obstacles
            capacity = SITE_OBSERVATION.capacity() if fits else None
        scene = self.site.scene(self.target, [PolygonObstacle(p) for p in polygons],
                                name=f"{self.name}/f{frame:03d}", tags=tags)
        scene.validate(source=f"clip {self.name} frame {frame}", vehicle=vehicle, capacity=capacity)
        return scene

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
            difficulty = Difficulty(**{k: (float(v) if k in DIFFICULTY_FLOATS else bool(v))
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


def _json_float(value: float) -> float | str:
    """A float for JSON; inf as the string "inf" (JSON has no infinity)."""
    return "inf" if math.isinf(value) else float(value)
