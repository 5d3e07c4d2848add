"""Trajectory stitching for replanning from a moving vehicle (beyond the paper).

A planner asked for a new plan from the vehicle's current pose while it drives does not know the vehicle's
speed: a new plan that starts in the other gear makes the vehicle brake across a metre or more of its old path
before it can start, off the new plan's start (at 1.5 m/s and 1 m/s² the stop takes 1.1 m). Stitching, as
on-road stacks do (Apollo's trajectory stitcher), plans instead from a pose on the followed plan that the vehicle
can still stop at — the braking distance plus one replanning period ahead — and drives the followed plan up to
that pose, then the new plan: a ``StitchedPlan``. The vehicle keeps its speed through the stitch when the new plan
starts in the same gear and stops there otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from np_sim.plan import Plan


def stitch_distance(speed_mps: float, decel_mps2: float, period_s: float, margin_m: float) -> float:
    """Distance ahead of the vehicle (m) of the pose a replan starts from: braking distance v²/(2a) at the
    profile's deceleration, one replanning period of driving v·T, and a margin."""
    v = abs(float(speed_mps))
    return v * v / (2.0 * decel_mps2) + v * period_s + margin_m


@dataclass(frozen=True, eq=False)
class StitchedPlan(Plan):
    """The followed plan's stretch ``prefix_s`` = (s_from, s_to) (its own travelled distance) followed by
    ``suffix``, a planner's plan from the followed plan's pose at s_to.

    ``start`` is the prefix's pose at s_from; ``success``, ``reason`` and ``plan_time_s`` are the suffix's;
    ``arcs`` and ``hermite`` stay empty: the geometry is the prefix's samples then the suffix's (``sample``)."""

    prefix: Plan | None = None
    """The plan followed when the replan happened (itself possibly stitched)."""
    prefix_s: tuple[float, float] = (0.0, 0.0)
    """Stretch (s_from, s_to) of ``prefix`` driven before the suffix (m along the prefix)."""
    suffix: Plan | None = None
    """The new plan, from the prefix's pose at s_to."""

    @classmethod
    def join(cls, prefix: Plan, s_from: float, s_to: float, suffix: Plan) -> "StitchedPlan":
        """``prefix`` from s_from to s_to, then ``suffix``; a stitched prefix whose own prefix is already behind
        s_from is unwrapped, so replanning many times does not nest plans ever deeper."""
        while isinstance(prefix, StitchedPlan):
            inner_from, inner_to = prefix.prefix_s
            prefix_length = inner_to - inner_from
            if s_from < prefix_length - 1e-9:
                break
            prefix, s_from, s_to = prefix.suffix, s_from - prefix_length, s_to - prefix_length
        if not 0.0 <= s_from <= s_to:
            raise ValueError(f"StitchedPlan.join: expected 0 <= s_from <= s_to, got {s_from!r}, {s_to!r}")
        start = _row_at(prefix.sample(0.05), s_from)[:3]
        return cls(start=start, success=suffix.success, reason=suffix.reason,
                   plan_time_s=suffix.plan_time_s, expanded_nodes=suffix.expanded_nodes, prefix=prefix,
                   prefix_s=(float(s_from), float(s_to)), suffix=suffix)

    def sample(self, ds: float = 0.1) -> np.ndarray:
        """(M, 6) rows x, y, θ, steer_curvature, gear, s: the prefix's samples from s_from to s_to (both ends
        included, interpolated), then the suffix's after its start; s from 0."""
        if not ds > 0:
            raise ValueError(f"Plan.sample: ds must be > 0, got {ds}")
        s_from, s_to = self.prefix_s
        head = _rows_between(self.prefix.sample(ds), s_from, s_to)
        head[:, 5] -= s_from
        tail = self.suffix.sample(ds)[1:].copy()
        tail[:, 5] += head[-1, 5]
        return np.vstack([head, tail])

    def metrics(self) -> tuple[float, int, float]:
        """(L, reversals, Δκ) of the stitched path: L and reversals from the samples; Δκ is not defined across a
        stitch (nan)."""
        rows = self.sample(0.05)
        gears = rows[1:, 4][rows[1:, 4] != 0]
        return float(rows[-1, 5]), int(np.count_nonzero(gears[1:] != gears[:-1])), float("nan")


def _rows_between(rows: np.ndarray, s_from: float, s_to: float) -> np.ndarray:
    """Rows with s in [s_from, s_to], the two ends interpolated (pose, s; steering and gear of the row ahead)."""
    s = rows[:, 5]
    inside = rows[(s > s_from + 1e-9) & (s < s_to - 1e-9)]
    ends = [_row_at(rows, s_from), _row_at(rows, s_to)] if s_to > s_from else [_row_at(rows, s_from)]
    return np.vstack([ends[0][None], inside, *([ends[1][None]] if len(ends) > 1 else [])])


def _row_at(rows: np.ndarray, s_at: float) -> np.ndarray:
    s = rows[:, 5]
    k = int(np.clip(np.searchsorted(s, s_at), 1, len(rows) - 1))
    a, b = rows[k - 1], rows[k]
    w = 0.0 if b[5] <= a[5] else float(np.clip((s_at - a[5]) / (b[5] - a[5]), 0.0, 1.0))
    out = b.copy()
    out[:2] = a[:2] + w * (b[:2] - a[:2])
    out[2] = math.remainder(a[2] + w * math.remainder(b[2] - a[2], 2 * math.pi), 2 * math.pi)
    out[5] = s_at
    return out
