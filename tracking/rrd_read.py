"""Read a closed-loop recording (`tracking.rerun_log`, `tracking.clip_log`) back into plain data: `read_run`.

The recording is read with the Rerun SDK's own reader (`rerun.chunk.RrdReader`, its first recording store). Rows
of an entity are taken in the order they were logged (their row ids), times are ``sim_time`` in seconds.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader

_ROW_ID = "rerun.controls.RowId"


@dataclass(frozen=True)
class PlanSegment:
    """One gear's stretch of a plan as the tracker followed it."""

    gear: int
    """+1 forward, −1 reverse."""
    poses: np.ndarray
    """(n, 3) reference-point poses x, y, θ (m, rad)."""


@dataclass(frozen=True)
class RecordedPlan:
    """A plan the tracker started to follow at ``time_s`` (the first plan when the drive starts, each replan)."""

    time_s: float
    segments: tuple[PlanSegment, ...]

    @property
    def poses(self) -> np.ndarray:
        """(n, 3) every pose of the plan, the segments one after the other."""
        return np.vstack([s.poses for s in self.segments])


@dataclass(frozen=True)
class RecordedCall:
    """A planner call of a clip run and the detections it planned with."""

    time_s: float
    frame: int
    success: bool
    rejected: str
    """Why the tracker refused a successful plan ('' when it did not)."""
    plan_time_s: float
    detections: tuple[np.ndarray, ...]
    """Closed detection outlines ((k, 2) each, m)."""
    labels: tuple[str, ...]
    """The detected object of each outline, '<kind> <id>'."""

    @property
    def usable(self) -> bool:
        """A successful plan the tracker followed."""
        return self.success and not self.rejected


@dataclass(frozen=True)
class RecordedContact:
    """A chassis contact as it began."""

    time_s: float
    geom: str
    """The touched geom (``obstacle_<i>[_<k>]``, ``wall_<edge>_<k>`` or ``mover_<id>``)."""
    position: np.ndarray
    """(2,) world contact point (m)."""


@dataclass(frozen=True)
class Outcome:
    """The run's outcome as logged at its end."""

    success: bool
    reason: str
    final_pose: np.ndarray
    final_error: np.ndarray
    """(position error (m), absolute heading error (rad)) to the target."""
    cross_track_rms_m: float
    cross_track_max_m: float
    """The executor's largest lateral error while driving (it skips the steps standing or aligning the wheels)."""
    sim_time_s: float
    plans_used: int
    text: str


@dataclass
class RecordedRun:
    """One closed-loop run read from its ``.rrd`` (`read_run`)."""

    name: str
    """The recording's name (``<clip>_<planner>`` in a clip run)."""
    clip: str
    """The clip's name ('' for a run without a clip)."""
    boundary: np.ndarray
    """(k, 2) closed site boundary (m)."""
    obstacles: dict[str, np.ndarray]
    """Static obstacle label (``obstacle_<i>``) -> closed ground-truth outline."""
    target: np.ndarray
    """Closed target footprint."""
    plans: list[RecordedPlan]
    calls: list[RecordedCall]
    """Empty for a run without a clip (only clip runs log their calls)."""
    footprint_times: np.ndarray
    footprints: np.ndarray
    """(n, 5, 2) closed outlines of the simulated body at ``footprint_times`` (every ``log_every`` steps)."""
    reference_points: np.ndarray
    """(n, 2) the reference point (rear-axle centre) at ``footprint_times`` (m)."""
    mover_times: np.ndarray
    movers: list[dict[str, np.ndarray]]
    """Per entry of ``mover_times``: mover name -> closed ground-truth outline."""
    contacts: list[RecordedContact]
    controller: dict[str, tuple[np.ndarray, np.ndarray]]
    """Controller scalar name (``cross_track_m``...) -> (times, values) at every control step."""
    executed: np.ndarray
    """(n, 2) executed reference-point path."""
    outcome: Outcome | None
    """None when the run was cut off before its end was logged."""

    def plan_at(self, t: float) -> RecordedPlan | None:
        """The plan followed at sim time ``t`` (the newest one started at or before it), None before the first."""
        started = [p for p in self.plans if p.time_s <= t + 1e-9]
        return started[-1] if started else None

    def call_of(self, plan: RecordedPlan) -> RecordedCall:
        """The planner call that gave ``plan``: the usable call at its time."""
        for call in self.calls:
            if call.usable and abs(call.time_s - plan.time_s) < 1e-6:
                return call
        raise LookupError(f"{self.name}: no usable planner call at t = {plan.time_s:.2f} s, the plan's start")

    def body_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(closed body outline, reference point) logged nearest in time to ``t``."""
        if not len(self.footprint_times):
            raise LookupError(f"{self.name}: the recording logged no vehicle footprint")
        k = int(np.argmin(np.abs(self.footprint_times - t)))
        return self.footprints[k], self.reference_points[k]

    def movers_at(self, t: float) -> dict[str, np.ndarray]:
        """The movers' logged outlines nearest in time to ``t`` (empty without movers)."""
        if not len(self.mover_times):
            return {}
        return self.movers[int(np.argmin(np.abs(self.mover_times - t)))]


def _entity_rows(path: Path) -> dict[str, list[dict]]:
    """Entity path -> its rows in logging order, each {'t': sim time (s) or None (static), component: value}."""
    reader = RrdReader(str(path))
    entries = reader.recordings()
    if not entries:
        raise ValueError(f"read_run: {path} holds no recording")
    rows: dict[str, list[tuple[bytes, dict]]] = {}
    for chunk in reader.store(store=entries[0]).stream().to_chunks():
        batch = chunk.to_record_batch()
        names = batch.schema.names
        times = (batch.column("sim_time").cast(pa.int64()).to_numpy(zero_copy_only=False) / 1e9
                 if "sim_time" in names else [None] * batch.num_rows)
        ids = batch.column(_ROW_ID).to_pylist()
        columns = {n: batch.column(n).to_pylist() for n in names if ":" in n}
        for k in range(batch.num_rows):
            row = {n: values[k] for n, values in columns.items() if values[k] is not None}
            rows.setdefault(chunk.entity_path, []).append((ids[k], {"t": times[k], **row}))
    return {entity: [row for _, row in sorted(found, key=lambda r: r[0])] for entity, found in rows.items()}


def _one(row: dict, component: str, default=None):
    """The single value of a one-element component of ``row``."""
    values = row.get(component)
    return default if not values else values[0]


def _plans(rows: list[dict], path: Path) -> list[RecordedPlan]:
    plans = []
    for row in rows:
        if "PlanPoses:gear" not in row:
            raise ValueError(f"read_run: {path} was written before recordings carried the plans' headings and gears "
                             "(and the planner calls); drive the run again to record it")
        strips = [np.asarray(s, float) for s in row["LineStrips2D:strips"]]
        gears, headings = row["PlanPoses:gear"], np.asarray(row["PlanPoses:heading_rad"], float)
        bounds = np.cumsum([0] + [len(s) for s in strips])
        segments = tuple(PlanSegment(int(g), np.column_stack([s, headings[a:b]]))
                         for g, s, a, b in zip(gears, strips, bounds[:-1], bounds[1:]))
        plans.append(RecordedPlan(float(row["t"]), segments))
    return plans


def _calls(calls: list[dict], detections: list[dict]) -> list[RecordedCall]:
    """The calls, each with the detections logged with it (one row each per call, in the same order)."""
    if len(calls) != len(detections):
        raise ValueError(f"read_run: {len(calls)} planner calls but {len(detections)} detection rows")
    out = []
    for call, seen in zip(calls, detections):
        out.append(RecordedCall(
            time_s=float(call["t"]), frame=int(_one(call, "PlannerCall:frame")),
            success=bool(_one(call, "PlannerCall:success")), rejected=_one(call, "PlannerCall:rejected", ""),
            plan_time_s=float(_one(call, "PlannerCall:plan_time_s")),
            detections=tuple(np.asarray(s, float) for s in seen.get("LineStrips2D:strips", [])),
            labels=tuple(seen.get("LineStrips2D:labels", []))))
    return out


def _outcome(rows: list[dict]) -> Outcome | None:
    if not rows:
        return None
    row = rows[-1]
    return Outcome(success=bool(_one(row, "Outcome:success")), reason=_one(row, "Outcome:reason", ""),
                   final_pose=np.asarray(row["Outcome:final_pose"], float),
                   final_error=np.asarray(row["Outcome:final_error"], float),
                   cross_track_rms_m=float(_one(row, "Outcome:cross_track_rms_m")),
                   cross_track_max_m=float(_one(row, "Outcome:cross_track_max_m")),
                   sim_time_s=float(_one(row, "Outcome:sim_time_s")),
                   plans_used=int(_one(row, "Outcome:plans_used")), text=_one(row, "TextLog:text", ""))


def _timed_strips(rows: list[dict]) -> tuple[np.ndarray, list[list[np.ndarray]], list[list[str]]]:
    """(times, per row its outlines, per row its labels) of a line-strip entity."""
    times = np.array([r["t"] for r in rows], float)
    strips = [[np.asarray(s, float) for s in r.get("LineStrips2D:strips", [])] for r in rows]
    return times, strips, [list(r.get("LineStrips2D:labels", [])) for r in rows]


def _scalars(rows: dict[str, list[dict]]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    out = {}
    for entity, found in rows.items():
        if entity.startswith("/controller/"):
            out[entity.removeprefix("/controller/")] = (np.array([r["t"] for r in found], float),
                                                        np.array([r["Scalars:scalars"][0] for r in found], float))
    return out


def _static_strips(rows: dict[str, list[dict]], entity: str) -> tuple[list[np.ndarray], list[str]]:
    """The outlines and labels of a static line-strip entity (none when it was not logged)."""
    found = rows.get(entity)
    if not found:
        return [], []
    last = found[-1]
    return [np.asarray(s, float) for s in last["LineStrips2D:strips"]], list(last.get("LineStrips2D:labels", []))


def read_run(path: str | Path) -> RecordedRun:
    """The closed-loop run recorded in the ``.rrd`` at ``path`` (`tracking.rerun_log` describes what is logged):
    the scene, the plans followed (poses and gears), the planner calls with their detections (clip runs), the
    simulated body's outline over time, the movers, the contacts, the controller scalars and the outcome."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"read_run: {path} not found; expected a closed-loop .rrd recording")
    rows = _entity_rows(path)
    boundary, _ = _static_strips(rows, "/world/scene/boundary")
    obstacles, labels = _static_strips(rows, "/world/scene/obstacles")
    target, _ = _static_strips(rows, "/world/scene/target")
    executed, _ = _static_strips(rows, "/world/executed")
    foot_t, foot, _ = _timed_strips(rows.get("/world/vehicle/footprint", []))
    mover_t, mover_rings, mover_names = _timed_strips(rows.get("/world/scene/movers", []))
    info = [r for r in rows.get("/__properties", []) if "RecordingInfo:name" in r]
    clip = rows.get("/run/clip", [])
    return RecordedRun(
        name=info[-1]["RecordingInfo:name"][0] if info else "",
        clip=_one(clip[-1], "TextDocument:text", "") if clip else "",
        boundary=boundary[0] if boundary else np.zeros((0, 2)), obstacles=dict(zip(labels, obstacles)),
        target=target[0] if target else np.zeros((0, 2)),
        plans=_plans(rows.get("/world/plan", []), path),
        calls=_calls(rows.get("/run/calls", []), rows.get("/world/detections", [])),
        footprint_times=foot_t, footprints=np.array([f[0] for f in foot]).reshape(-1, 5, 2),
        reference_points=np.array([r["Points2D:positions"][0] for r in rows.get("/world/vehicle/reference_point", [])],
                                  float).reshape(-1, 2),
        mover_times=mover_t, movers=[dict(zip(n, r)) for n, r in zip(mover_names, mover_rings)],
        contacts=[RecordedContact(float(r["t"]), r["Points2D:labels"][0], np.asarray(r["Points2D:positions"][0]))
                  for r in rows.get("/world/contacts", [])],
        controller=_scalars(rows), executed=executed[0] if executed else np.zeros((0, 2)),
        outcome=_outcome(rows.get("/run/outcome", [])))
