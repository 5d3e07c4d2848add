"""Plan → reference path: gear segments of dense samples with physical steering curvature and a speed profile.

A plan's samples (``Plan.sample``: x, y, θ, steer_curvature c = −sgn(l)·κ, gear, s; spec §2) are cut at every cusp
(gear change) into segments; each segment gets a speed profile that starts at rest (or at the given start speed)
and ends at rest, bounded by the gear's cruise speed, the lateral acceleration v²·|c| ≤ a_lat, the steering rate
(a steering change Δδ over a window W of path is driven in at least Δδ / rate seconds, so v ≤ rate·W / Δδ) and the
acceleration bound (forward–backward pass v_{i+1}² ≤ v_i² + 2·a·Δs).

The steering feed-forward is the plan's steering angle δ = atan(c·L) averaged over the same window W
(`window_average`), turned back into a curvature: a steering step becomes a ramp of δ centred on it that the
rate-limited steering can follow at the profile speed, instead of a step it cannot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from np_sim.plan import Plan
from tracking.config import SpeedProfileConfig


@dataclass(frozen=True, eq=False)
class Segment:
    """One gear's stretch of the reference, sampled densely; s runs from 0 at the segment start."""

    gear: int
    """+1 forward, −1 reverse."""
    xy: np.ndarray
    """(N, 2) reference-point positions (m)."""
    theta: np.ndarray
    """(N,) headings (rad)."""
    steer_curvature: np.ndarray
    """(N,) physical steering curvature c (1/m, positive = left)."""
    s: np.ndarray
    """(N,) distance along the segment (m), from 0."""
    speed: np.ndarray
    """(N,) target speed magnitude (m/s), 0 at both ends."""
    steer_feedforward: np.ndarray
    """(N,) steering curvature feed-forward tan(δ̄)/L, δ̄ the window average of atan(c·L) (1/m)."""

    @property
    def length(self) -> float:
        """Segment length (m)."""
        return float(self.s[-1])

    def duration_s(self) -> float:
        """Time to drive the profile: Σ 2·Δs / (v_i + v_{i+1}) (s)."""
        v_sum = self.speed[:-1] + self.speed[1:]
        ds = np.diff(self.s)
        return float(np.sum(np.where(v_sum > 0, 2.0 * ds / np.maximum(v_sum, 1e-9), 0.0)))


def split_segments(samples: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """(gear, rows) per gear stretch of ``Plan.sample`` rows; a cusp row ends one stretch and starts the next
    (with the next stretch's steering curvature); rows of zero gear (zero-length arcs) are dropped."""
    rows = samples[samples[:, 4] != 0.0]
    if len(rows) < 2:
        return []
    cuts = np.flatnonzero(rows[1:, 4] != rows[:-1, 4]) + 1  # first row of each new gear
    out = []
    starts = np.concatenate([[0], cuts - 1])  # the cusp row (end of the previous stretch) starts the next one
    ends = np.concatenate([cuts, [len(rows)]])
    for a, b in zip(starts, ends):
        seg = rows[a:b].copy()
        seg[0, 3] = seg[1, 3] if len(seg) > 1 else seg[0, 3]
        seg[0, 4] = seg[-1, 4]
        seg[:, 5] -= seg[0, 5]
        if len(seg) >= 2 and seg[-1, 5] > 0:
            out.append((int(seg[-1, 4]), seg))
    return out


def window_average(s: np.ndarray, piece_values: np.ndarray, window_m: float) -> np.ndarray:
    """Mean of a piecewise-constant function over [s_i − W/2, s_i + W/2] ∩ [0, s_end] at every sample.

    ``piece_values[i]`` (i ≥ 1) holds on the piece (s_{i−1}, s_i]; with the exact cumulative integral F (linear
    between samples) the mean is (F(b) − F(a)) / (b − a)."""
    F = np.concatenate([[0.0], np.cumsum(piece_values[1:] * np.diff(s))])
    a = np.maximum(s - 0.5 * window_m, s[0])
    b = np.minimum(s + 0.5 * window_m, s[-1])
    return (np.interp(b, s, F) - np.interp(a, s, F)) / np.maximum(b - a, 1e-12)


def speed_profile(s: np.ndarray, steer_curvature: np.ndarray, gear: int, config: SpeedProfileConfig,
                  steer_rate_rps: float, wheelbase_m: float, start_speed_mps: float = 0.0) -> np.ndarray:
    """Target speed magnitude at each sample: the pointwise bounds of the module docstring, then the
    acceleration-bounded forward (from ``start_speed_mps``) and backward (to rest) passes."""
    cruise = config.forward_speed_mps if gear > 0 else config.reverse_speed_mps
    c = np.abs(steer_curvature)
    bound = np.minimum(cruise, np.sqrt(config.lateral_accel_mps2 / np.maximum(c, 1e-9)))
    delta = np.arctan(steer_curvature * wheelbase_m)
    half = 0.5 * config.steer_window_m
    lo = np.searchsorted(s, s - half, side="left")
    hi = np.searchsorted(s, s + half, side="right")
    span = np.array([np.ptp(delta[a:b]) for a, b in zip(lo, hi)])  # steering excursion within each window
    bound = np.minimum(bound, steer_rate_rps * config.steer_window_m / np.maximum(span, 1e-9))
    v = bound.copy()
    v[0] = min(v[0], max(start_speed_mps, 0.0))
    ds = np.diff(s)
    two_a = 2.0 * config.accel_mps2
    for i in range(1, len(v)):
        v[i] = min(v[i], math.sqrt(v[i - 1] ** 2 + two_a * ds[i - 1]))
    v[-1] = 0.0
    for i in range(len(v) - 2, -1, -1):
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + two_a * ds[i]))
    return v


def reference_segments(plan: Plan, ds_m: float, config: SpeedProfileConfig, steer_rate_rps: float,
                       wheelbase_m: float, start_speed_mps: float = 0.0) -> list[Segment]:
    """The plan's gear segments with speed profiles; only the first may start moving (``start_speed_mps``)."""
    out = []
    for k, (gear, rows) in enumerate(split_segments(plan.sample(ds_m))):
        v0 = start_speed_mps if k == 0 else 0.0
        speed = speed_profile(rows[:, 5], rows[:, 3], gear, config, steer_rate_rps, wheelbase_m, v0)
        out.append(Segment(gear=gear, xy=rows[:, :2].copy(), theta=np.unwrap(rows[:, 2]),
                           steer_curvature=rows[:, 3].copy(), s=rows[:, 5].copy(), speed=speed,
                           steer_feedforward=np.tan(window_average(rows[:, 5], np.arctan(rows[:, 3] * wheelbase_m),
                                                                   config.steer_window_m)) / wheelbase_m))
    return out
