"""The review sheet of one factor (`experiments.failure_review`): a panel per level × planner around the first
contact of its recorded failure (or where the run ended without one)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments.registry import label
from experiments.review_case import ContactReview, planned_bodies, true_outline
from np_sim.vehicle import VehicleSpec
from tracking.rrd_read import RecordedRun

WINDOW_M = 7.0
"""Half-width of a panel around the contact (m)."""
_GEAR = {1: "tab:green", -1: "tab:red"}


@dataclass(frozen=True)
class Panel:
    """One recorded failure as the sheet draws it."""

    level: str
    planner: str
    run: RecordedRun
    review: ContactReview | None
    """None for a run without a contact."""
    body: VehicleSpec
    """The body the simulator drove."""
    caption: str


def _ring(ax, ring, **style) -> None:
    ring = np.asarray(ring, float)
    ax.plot(np.append(ring[:, 0], ring[0, 0]), np.append(ring[:, 1], ring[0, 1]), **style)


def _draw(ax, panel: Panel) -> None:
    """The scene around the contact (the run's end without one): true outlines (blue, movers pink, the touched
    one violet), the detections the followed plan was made with (cyan, dashed), the plan per gear, the planned body at
    the plan's pose nearest the vehicle (orange, dotted), the body at the contact (orange) and the contact point."""
    run, review = panel.run, panel.review
    if not len(run.footprint_times):  # the drive never started (no usable first plan): the scene at the target
        t, body, reference = 0.0, None, run.target[:-1].mean(axis=0)
    else:
        t = review.time_s if review else run.footprint_times[-1]
        body, reference = run.body_at(t)
    centre = run.contacts[0].position if review else reference
    _ring(ax, run.boundary, color="0.4", lw=1.2)
    for ring in run.obstacles.values():
        _ring(ax, ring, color="tab:blue", lw=0.9)
    for ring in run.movers_at(t).values():
        _ring(ax, ring, color="tab:pink", lw=0.9)
    plan = run.plan_at(t)
    if plan is not None:
        for ring in run.call_of(plan).detections:
            _ring(ax, ring, color="tab:cyan", lw=0.9, ls="--")
        for segment in plan.segments:
            ax.plot(segment.poses[:, 0], segment.poses[:, 1], color=_GEAR[segment.gear], lw=1.4)
        nearest = plan.poses[int(np.argmin(np.hypot(*(plan.poses[:, :2] - reference).T)))]
        _ring(ax, planned_bodies(nearest, panel.body)[0].exterior.coords, color="tab:orange", lw=1.0, ls=":")
    if body is not None:
        _ring(ax, body, color="tab:orange", lw=1.6)
    if review:
        touched = true_outline(run, review.geom, t)
        _ring(ax, np.asarray(touched.exterior.coords if hasattr(touched, "exterior") else touched.coords),
              color="darkviolet", lw=1.6)
        ax.plot(*centre, "x", color="red", ms=8, mew=2)
    ax.set_xlim(centre[0] - WINDOW_M, centre[0] + WINDOW_M)
    ax.set_ylim(centre[1] - WINDOW_M, centre[1] + WINDOW_M)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=6)
    ax.set_title(panel.caption, fontsize=7)


def review_sheet(factor: str, levels: list[str], planners: list[str], panels: list[Panel], path: Path) -> Path:
    """Draw ``factor``'s sheet, a row per level and a column per planner (an empty panel where that level and
    planner have no recording), to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    size = (max(3.4 * len(planners), 7.0), 3.9 * len(levels) + 0.8)
    fig, axes = plt.subplots(len(levels), len(planners), figsize=size, squeeze=False)
    by_cell = {(p.level, p.planner): p for p in panels}
    for i, level in enumerate(levels):
        for j, planner in enumerate(planners):
            ax = axes[i, j]
            if (level, planner) in by_cell:
                _draw(ax, by_cell[level, planner])
            else:
                ax.set_axis_off()
                ax.set_title(f"{level} · {label(planner)}\nno failure recorded", fontsize=7)
    keys = [("0.4", "-", "site boundary"), ("tab:blue", "-", "true outline"), ("tab:pink", "-", "mover (true)"),
            ("darkviolet", "-", "touched object (true)"),
            ("tab:cyan", "--", "detection of the plan's call"), ("tab:green", "-", "plan, forward"),
            ("tab:red", "-", "plan, reverse"), ("tab:orange", ":", "planned body nearest"),
            ("tab:orange", "-", "body at contact")]
    handles = [Line2D([], [], color=c, ls=ls, label=name) for c, ls, name in keys]
    handles.append(Line2D([], [], color="red", marker="x", ls="", label="first contact"))
    fig.legend(handles=handles, loc="lower center", ncol=(len(handles) + 1) // 2, fontsize=7, frameon=False)
    fig.suptitle(f"{factor}: the recorded failure per level and planner (world frame, m)", fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 0.98), h_pad=1.5)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
