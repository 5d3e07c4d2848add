"""The difficulty rule of the clips (spec §4.4 asks for "high search effort or a required target-averse first
manoeuvre"; this is the measurable stand-in, `DifficultyRule`). A clip is *difficult* when at least one holds:

1. ``detour`` — geodesic detour: straight-line start→target distance d ≥ 5 m (below that the 1.5 m grid
   quantises too coarsely) and geodesic distance on the frame-0 grid / d ≥ 1.5;
2. ``averse_heading`` — the start faces away from the target's heading: cos(θ_start − θ_target) < −0.5 with the
   target within 8 m (the vehicle must turn round in a small space, first moving away);
3. ``front_of_reverse_bay`` — the target is a ``reverse`` bay and the start stands in front of it: in the
   target's frame, 0 < along-heading offset ≤ 9 m and |lateral offset| ≤ 2 m, and the start is not already
   lined up to reverse straight in (cos(θ_start − θ_target) < 0.5), so the vehicle must first pull away;
4. ``tight`` — tight final clearance: the least distance from the target footprint to any ground-truth object
   (over all frames) or to the boundary is < 0.5 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np
import shapely
from shapely.geometry import LinearRing
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips.config import ClipConfig
from np_sim.clips.geometry import clip_grid, geodesic_at
from np_sim.frames import place
from np_sim.kinematics import wrap_angle
from np_sim.site import Site
from np_sim.vehicle import VehicleSpec

if TYPE_CHECKING:
    from np_sim.clips.model import Clip, TrackedObject

CRITERIA = ("detour", "averse_heading", "front_of_reverse_bay", "tight")
"""Names of the four criteria, in the rule's order."""


@dataclass(frozen=True)
class DifficultyRule:
    """Thresholds of the difficulty rule (this module's docstring)."""

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


class Difficulty(NamedTuple):
    """Measured difficulty quantities of a clip and the rule's verdicts (this module's docstring)."""

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
        return tuple(n for n in CRITERIA if getattr(self, n))


DIFFICULTY_FLOATS = ("straight_m", "geodesic_m", "detour_ratio", "heading_cos", "along_m", "lateral_m", "clearance_m")
"""The measured (float) fields of `Difficulty`; the others are the criteria's verdicts."""


def measure_difficulty(start, target, spot_kind: str, geodesic_m: float, clearance_m: float,
                       rule: DifficultyRule | None = None) -> Difficulty:
    """Apply the difficulty rule (this module's docstring) to measured quantities; floats are rounded to 1e-4
    first."""
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
    grid = clip_grid(clip.site, clip.target, clip.ground_truth(0), config, vehicle)
    geodesic = geodesic_at(grid, clip.start[:2])
    clearance = target_clearance(clip.site, clip.target, clip.objects, clip.n_frames, vehicle)
    return measure_difficulty(clip.start, clip.target, clip.site.spots[clip.target_spot].kind, geodesic, clearance,
                              rule)
