"""The outcome of one closed-loop run."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

REASONS = ("", "contact", "timeout", "not_parked", "plan_failed", "empty_plan", "steering_limit",
           "start_in_collision")
"""Failure reasons ('' = success): body contact, time limit, stopped outside the parking tolerance, the planner
failed, the plan has no motion, the plan steers beyond κ_max, the start footprint overlaps an obstacle or wall."""


@dataclass(frozen=True)
class Contact:
    """A chassis contact with an obstacle or wall, recorded when it begins."""

    time_s: float
    """Sim time (s)."""
    geom: str
    """Name of the touched geom (``obstacle_<i>[_<k>]`` or ``wall_<edge>_<k>``)."""
    position: tuple[float, float]
    """World contact point (m)."""


@dataclass
class ExecutionRecord:
    """Result of `tracking.executor.execute` (spec §8, §10)."""

    success: bool
    """No body contact and parked within the executor's tolerance of the scene target."""
    reason: str
    """'' on success, else one of `REASONS`."""
    detail: str = ""
    """Human-readable explanation of the reason."""
    controller: str = ""
    """Lateral controller name."""
    contacts: list[Contact] = field(default_factory=list)
    """Body contacts in time order."""
    final_pose: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    """Executed final reference-point pose [x, y, θ]."""
    final_error: tuple[float, float] = (math.nan, math.nan)
    """(position error (m), absolute heading error (rad)) of the final pose to the scene target."""
    cross_track_rms_m: float = math.nan
    """RMS over control steps of the lateral error to the tracked segment (m)."""
    cross_track_max_m: float = math.nan
    """Largest absolute lateral error (m)."""
    heading_error_rms_rad: float = math.nan
    """RMS over control steps of the heading error (rad)."""
    path_length_m: float = 0.0
    """Executed reference-point path length (m)."""
    reversals: int = 0
    """Executed changes of driving direction."""
    sim_time_s: float = 0.0
    """Simulated time (s)."""
    wall_time_s: float = 0.0
    """Wall-clock time of the closed loop (s)."""
    plans_used: int = 0
    """Plans followed (1 without replanning)."""
    replans_failed: int = 0
    """Replanning calls that returned a failed or untrackable plan (a replanner returning None is not counted)."""
    frames_rendered: int = 0
    """Off-screen frames rendered."""

    @property
    def realtime_factor(self) -> float:
        """Simulated time per wall-clock time."""
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else math.nan

    def to_row(self) -> dict:
        """Flat CSV/JSON row (degrees for the heading error)."""
        return {"success": int(self.success), "reason": self.reason, "detail": self.detail,
                "controller": self.controller, "contacts": len(self.contacts),
                "first_contact_geom": self.contacts[0].geom if self.contacts else "",
                "final_position_error_m": self.final_error[0],
                "final_heading_error_deg": math.degrees(self.final_error[1]),
                "cross_track_rms_m": self.cross_track_rms_m, "cross_track_max_m": self.cross_track_max_m,
                "heading_error_rms_deg": math.degrees(self.heading_error_rms_rad),
                "path_length_m": self.path_length_m, "reversals": self.reversals, "sim_time_s": self.sim_time_s,
                "wall_time_s": self.wall_time_s, "realtime_factor": self.realtime_factor,
                "plans_used": self.plans_used, "replans_failed": self.replans_failed}
