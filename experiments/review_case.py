"""What one recorded failure shows (`experiments.failure_review`): at the first contact, the plan being followed,
its clearance to the touched object's true outline and, where it meets that outline, to the planner's detection of
it, whether the planner saw the object, the tracking error, and a one-phrase kind.

Clearances are those of the *planned body*: the body the simulator drove (a ``body_length`` disturbance makes it
longer than the planned `VehicleSpec`) placed at every pose of the plan; 0 where it overlaps. A moving object's
true outline is the one at the contact time. A plan passing within `SLACK_M` of an object counts as touching it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from np_sim.frames import place
from np_sim.vehicle import VehicleSpec
from tracking.rrd_read import RecordedRun

SLACK_M = 0.05
"""A plan that passes an object closer than this is taken as touching it: no tracker follows a plan closer (the
undisturbed runs' median largest cross-track error is 0.02–0.08 m per planner in the robustness study's
records.csv)."""

KINDS = {
    "left the plan": f"the plan's own body clears the touched object's true outline by at least {SLACK_M} m: the "
                     "vehicle left the plan (a lateral error, an overshoot or a turned body)",
    "unseen": "the plan passes the object within the slack, and the call that made the plan had no detection of it",
    "detection off": "where the plan passes within the slack of the object's true outline, it clears the object's "
                     "detection by at least the slack",
    "planned through": "where the plan passes within the slack of the object's true outline, it passes within the "
                       "slack of its detection (or of the map's boundary) too",
}
"""The kinds of a contact failure, in the order they are decided; a run without a contact is labelled by its
reason ('timeout', 'not parked', ...)."""


def planned_bodies(poses: np.ndarray, body: VehicleSpec) -> np.ndarray:
    """The outlines (shapely polygons) of ``body`` at each reference-point pose of ``poses`` (n, 3)."""
    return shapely.polygons(place(body.footprint_local(), np.asarray(poses, float).reshape(-1, 3)))


def clearance(poses: np.ndarray, body: VehicleSpec, outline) -> float:
    """Least distance (m) from ``body`` at any pose of ``poses`` to ``outline`` (a shapely geometry); 0 where they
    overlap."""
    return float(shapely.distance(planned_bodies(poses, body), outline).min())


def true_outline(run: RecordedRun, geom: str, t: float):
    """The ground-truth shape of the touched ``geom`` at sim time ``t``: the site boundary's ring for a wall, a
    static obstacle's outline, or a mover's outline at (the logged time nearest to) ``t``."""
    if geom.startswith("wall_"):
        return shapely.LinearRing(run.boundary)
    if geom.startswith("mover_"):
        movers = run.movers_at(t)
        if geom not in movers:
            raise LookupError(f"{run.name}: no outline of {geom} logged near t = {t:.2f} s")
        return shapely.Polygon(movers[geom])
    label = "_".join(geom.split("_")[:2])  # obstacle_<i>[_<part>]
    if label not in run.obstacles:
        raise LookupError(f"{run.name}: the touched {geom} is no logged obstacle")
    return shapely.Polygon(run.obstacles[label])


def contact_kind(plan_clearance_m: float, seen: str, detection_clearance_m: float) -> str:
    """The kind of a contact (`KINDS`) from the plan's clearance to the true outline, whether the planner saw the
    object ('yes', 'no' or 'map' for the boundary) and the plan's clearance to the detection (m; `SLACK_M`)."""
    if plan_clearance_m >= SLACK_M:
        return "left the plan"
    if seen == "no":
        return "unseen"
    if seen == "yes" and detection_clearance_m >= SLACK_M:
        return "detection off"
    return "planned through"


@dataclass(frozen=True)
class ContactReview:
    """The first contact of a recorded run and the plan followed then."""

    time_s: float
    geom: str
    calls_before: int
    """Planner calls up to the contact."""
    failed_calls_since_plan: int
    """Planner calls after the one that made the followed plan, up to the contact: all failed (a usable one
    would have replaced the plan), while the vehicle drove on along the plan."""
    cross_track_m: float
    """|cross-track error| of the last control step at or before the contact."""
    cross_track_worst_m: float
    """Largest |cross-track error| up to the contact."""
    off_plan_m: float
    """Distance of the reference point (at the logged time nearest the contact) to the followed plan's path."""
    plan_time_s: float
    """When the followed plan was made."""
    plan_clearance_m: float
    """With the body the simulator drove."""
    plan_clearance_nominal_m: float
    """With the body the planner planned for (differs under a ``body_length`` disturbance)."""
    seen: str
    detection_clearance_m: float
    """The plan's least clearance to the planner's detection of the object at the poses where the plan passes within
    `SLACK_M` of its true outline (at every pose where it passes no closer): whether the plan met the object where
    it also met the detection. nan when the planner had no detection of it ('no'); the boundary's clearance for a
    wall."""
    kind: str


def _cross_track(run: RecordedRun, t: float) -> tuple[float, float]:
    """(|error| at the last step at or before ``t``, largest |error| up to ``t``) of the recorded cross-track
    error."""
    times, values = run.controller["cross_track_m"]
    upto = np.abs(values[times <= t + 1e-9])
    return (float(upto[-1]), float(upto.max())) if len(upto) else (math.nan, math.nan)


def review_contact(run: RecordedRun, body: VehicleSpec, touched_object: str,
                   planned: VehicleSpec | None = None) -> ContactReview:
    """The first contact of ``run`` (which has one) reviewed with the driven ``body`` (and the ``planned`` one the
    planner planned for, default ``body``); ``touched_object`` is the touched object as the detections name it
    ('<kind> <id>', or 'boundary' for a wall)."""
    contact = run.contacts[0]
    t = contact.time_s
    plan = run.plan_at(t)
    if plan is None:
        raise LookupError(f"{run.name}: contact at t = {t:.2f} s before any plan was followed")
    call = run.call_of(plan)
    outline = true_outline(run, contact.geom, t)
    placed = planned_bodies(plan.poses, body)
    to_truth = shapely.distance(placed, outline)
    plan_clearance = float(to_truth.min())
    if touched_object == "boundary":
        seen, detection_clearance = "map", plan_clearance
    elif touched_object in call.labels:
        detection = shapely.Polygon(call.detections[call.labels.index(touched_object)])
        near = to_truth < SLACK_M  # where the plan meets the object; the whole plan where it never does
        to_detection = shapely.distance(placed[near] if near.any() else placed, detection)
        seen, detection_clearance = "yes", float(to_detection.min())
    else:
        seen, detection_clearance = "no", math.nan
    then, worst = _cross_track(run, t)
    reference = run.body_at(t)[1]
    off_plan = float(np.hypot(*(plan.poses[:, :2] - reference).T).min())
    return ContactReview(time_s=t, geom=contact.geom, calls_before=sum(c.time_s <= t + 1e-9 for c in run.calls),
                         failed_calls_since_plan=sum(plan.time_s + 1e-9 < c.time_s <= t + 1e-9 for c in run.calls),
                         cross_track_m=then, cross_track_worst_m=worst, off_plan_m=off_plan, plan_time_s=plan.time_s,
                         plan_clearance_m=plan_clearance,
                         plan_clearance_nominal_m=clearance(plan.poses, planned or body, outline),
                         seen=seen, detection_clearance_m=detection_clearance,
                         kind=contact_kind(plan_clearance, seen, detection_clearance))
