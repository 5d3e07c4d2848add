"""NeuralParker rollouts, batched, and best-of-N: a cost-based choice among sampled ones (beyond the paper).

``PolicyRollouts`` runs ``n`` rollouts of a policy from one start in one batched environment (``BatchCore``, one
compiled step for those still running), with the env's own arcs, checks, heading gate, connector and arc budget, so
every rollout is a plan the env would accept. With ``std`` zero each arc is the compiled mean action ``μ(o)``: the
paper's planner (§III-A) is the batch of one. Otherwise each arc is drawn as ``clip(μ(o) + σ ⊙ ε, −1, 1)`` with
``σ`` the policy's learned standard deviation (or a multiple of it) and ``ε ~ N(0, I)`` from a generator seeded per
call, so the same query always gives the same plans; with ``first_arc='uniform'`` each rollout's first arc is
drawn uniformly over the action box ``[−1, 1]²`` instead (`FIRST_ARCS`).

A trained policy is a distribution: the rollouts it would sample during training reach the target from many
starts where the mean rollout collides or runs out of arcs, and among several successful rollouts some keep more
distance from the obstacles than others. ``choose`` keeps the plans the tracker can steer and among them takes the
lowest cost: an estimate of the drive time (as a length), a cost per reversal, a cost for clearance below a wanted
safety margin (the largest margin of a ladder under which the whole sampled path keeps the vehicle rectangle
inflated by it off every obstacle, `VehicleSpec.inflated`) and one for a terminal heading near the edge of the
parking tolerance. The weights were set on difficult training clips, never on the held-out ones.
"""

from __future__ import annotations

import functools
import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from np_sim.collision import path_valid
from np_sim.config import EnvConfig
from np_sim.env_core import BatchCore
from np_sim.frames import from_target_frame
from np_sim.kinematics import heading_gap
from np_sim.kernels import step as K
from np_sim.plan import HermiteSegment, Plan
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec

DEFAULT_MARGINS_M = (0.2, 0.1, 0.0)
"""Safety-margin ladder of ``choose`` (m), largest first; 0 is the plain footprint. It ends at
``ChoiceWeights.wanted_margin_m``: more clearance than that costs nothing, so checking it would be wasted."""


def hermite_of(core: BatchCore, row: int, scene: Scene) -> HermiteSegment | None:
    """The terminal Hermite segment the last step of env ``row`` connected, in the world frame, or None."""
    h = int(core.R[row, K.R_HERMITE])
    if h < 0:
        return None
    return HermiteSegment(points=from_target_frame(core.h_pts[row, h].T, scene.target),
                          forward=bool(core.R[row, K.R_H_FORWARD] > 0), length=float(core.R[row, K.R_H_LEN]),
                          delta_kappa=float(core.R[row, K.R_H_DK]))


def end_reason(core: BatchCore, row: int) -> str:
    """'' on success, else 'collision' or 'timeout' (the arc budget ran out) for env ``row``'s ended episode."""
    if core.R[row, K.R_SUCCESS] > 0:
        return ""
    return "collision" if core.R[row, K.R_COLLISION] > 0 else "timeout"


FIRST_ARCS = ("policy", "uniform")
"""How a ``PolicyRollouts`` batch draws each rollout's first arc: from the policy like every later arc, or
uniformly over the whole action box (a start the policy steers into a wall still gets every first arc tried)."""


class PolicyRollouts:
    """``n`` rollouts of a policy from one start, batched: mean actions when ``std`` is zero, sampled otherwise
    (module docstring)."""

    def __init__(self, actor, std: np.ndarray, config: EnvConfig, n: int = 1, seed: int = 0,
                 first_arc: str = "policy", nearest: bool = False):
        """``nearest``: a scene with more obstacles than the policy's slots is observed by the site's rule
        (`np_sim.nearest`), its checks still on the whole scene; otherwise it is a CapacityError."""
        if int(n) < 1:
            raise ValueError(f"PolicyRollouts: n must be >= 1 rollout, got {n!r}")
        if first_arc not in FIRST_ARCS:
            raise ValueError(f"PolicyRollouts: first_arc must be one of {FIRST_ARCS}, got {first_arc!r}")
        std = np.asarray(std, np.float64)
        if std.shape != (2,) or not np.all(np.isfinite(std)) or np.any(std < 0):
            raise ValueError(f"PolicyRollouts: std must be two finite numbers >= 0, got {std.tolist()}")
        self.actor, self.std, self.config, self.n, self.seed = actor, std, config, int(n), int(seed)
        self.first_arc, self.nearest = first_arc, bool(nearest)
        self._cores: weakref.WeakKeyDictionary[Scene, BatchCore] = weakref.WeakKeyDictionary()

    def core(self, scene: Scene) -> BatchCore:
        """The batched env core of ``scene`` these rollouts play in, built once per scene object."""
        core = self._cores.get(scene)
        if core is None:
            core = BatchCore([scene], self.n, self.config, None, nearest=self.nearest)
            self._cores[scene] = core
        return core

    def _actions(self, obs: np.ndarray, rng: np.random.Generator, first: bool) -> np.ndarray:
        """Normalised actions of the live rollouts' observations ``obs`` (module docstring)."""
        if first and self.first_arc == "uniform":
            return rng.uniform(-1.0, 1.0, (len(obs), 2))
        if not self.std.any():
            return self.actor.batch(obs)
        noise = rng.standard_normal((len(obs), 2)) * self.std
        return np.clip(self.actor.batch(obs) + noise, -1.0, 1.0)

    def __call__(self, scene: Scene, start, seed=None) -> list[Plan]:
        """The ``n`` rollouts from ``start`` as plans, successful or not (ConfigError on a start in collision);
        ``seed`` (anything ``np.random.default_rng`` takes) replaces the generator's seed for this call."""
        start = np.asarray(start, float)
        core = self.core(scene)
        rng = np.random.default_rng(self.seed if seed is None else seed)
        rows = np.arange(self.n)
        core.reset_envs(rows, rng, 0, start)
        scale = np.array([self.config.vehicle.kappa_max, self.config.episode.max_length_m])
        plays_rollout = getattr(self.actor, "plays_rollout", None)  # a `CompiledActor` plays it in one call
        if not self.std.any() and self.first_arc == "policy" and plays_rollout is not None and plays_rollout(core):
            mean_arcs = self.actor.mean_rollout(core) * scale  # the loop below's plan, in one compiled call
            reason = end_reason(core, 0)
            return [Plan(start=start, arcs=mean_arcs, hermite=hermite_of(core, 0, scene), success=not reason,
                         reason=reason)]
        arcs: list[list[np.ndarray]] = [[] for _ in rows]
        plans: list[Plan | None] = [None] * self.n
        alive = np.ones(self.n, bool)
        first = True
        while alive.any():
            live = np.flatnonzero(alive)
            actions = np.asarray(self._actions(core.obs[live], rng, first), np.float64)
            first = False
            # finished rollouts are not stepped; while all live, the step takes every env (no rows to check)
            core.step(actions, None if len(live) == self.n else live)
            for row, action in zip(live, actions):
                arcs[row].append(action * scale)
                if core.R[row, K.R_TERMINATED] > 0 or core.R[row, K.R_TRUNCATED] > 0:
                    reason = end_reason(core, row)
                    plans[row] = Plan(start=start, arcs=np.array(arcs[row]).reshape(-1, 2),
                                      hermite=hermite_of(core, row, scene), success=not reason, reason=reason)
                    alive[row] = False
        return plans


def clearance_level(scene: Scene, poses: np.ndarray, vehicle: VehicleSpec, margins: Sequence[float]) -> float:
    """The largest margin of ``margins`` under which the footprint inflated by it (`VehicleSpec.inflated`) stays
    inside the boundary and off every obstacle at every pose row (x, y, θ); −1 when none does."""
    for margin in sorted(margins, reverse=True):
        if path_valid(scene, poses, "footprint", vehicle.inflated(margin)):
            return float(margin)
    return -1.0


_POSE_LEVELS: "weakref.WeakKeyDictionary[Scene, dict]" = weakref.WeakKeyDictionary()


def pose_clearance_level(scene: Scene, pose, vehicle: VehicleSpec, margins: Sequence[float]) -> float:
    """``clearance_level`` of the one pose (x, y, θ), cached per scene object (scenes are immutable; a planner call
    asks it of its start and target several times)."""
    row = np.asarray(pose, float)[:3]
    key = (row.tobytes(), vehicle, tuple(margins))
    levels = _POSE_LEVELS.setdefault(scene, {})
    if key not in levels:
        levels[key] = clearance_level(scene, row[None, :], vehicle, margins)
    return levels[key]


def clearance_covers_sweep(vehicle: VehicleSpec, margin_m: float, ds_m: float, kappa_limit: float) -> bool:
    """Whether a path whose footprint grown by ``margin_m`` (`VehicleSpec.inflated`) is free at samples at most
    ``ds_m`` apart along it, with |path curvature| ≤ ``kappa_limit``, is free when swept continuously (the exact
    rule). Between two samples every body point travels at most ds·(1 + κ·r), r the farthest body point from the
    reference point, so the body at any pose between them lies within half of that of the body at the nearer sample,
    inside the grown rectangle (which contains the body's Minkowski sum with a disc of the margin)."""
    return margin_m >= 0.5 * ds_m * (1.0 + kappa_limit * _body_reach(vehicle))


@functools.lru_cache(maxsize=16)
def _body_reach(vehicle: VehicleSpec) -> float:
    """The farthest footprint corner's distance from the reference point (m)."""
    return float(np.max(np.hypot(*vehicle.footprint_local().T)))


@dataclass(frozen=True)
class ChoiceWeights:
    """How ``choose`` tells a steerable plan and trades drive time against clearance, reversals and the terminal
    heading (costs in metres of driving at the forward cruise speed)."""

    margins_m: tuple[float, ...] = DEFAULT_MARGINS_M
    """Safety-margin ladder (m): a plan's clearance level is the largest of these its inflated footprint keeps."""
    wanted_margin_m: float = 0.2
    """Clearance below this costs ``clearance_weight`` per metre missing."""
    clearance_weight: float = 50.0
    """Cost per metre of clearance below ``wanted_margin_m`` (m/m); a path with no clearance level at all (its
    plain footprint touches on the finer check) counts as one ladder step below 0."""
    reversal_weight: float = 2.0
    """Cost per reversal (m)."""
    forward_speed_mps: float = 2.0
    """Cruise speed forward (m/s) of the drive-time estimate (`drive_length`; the tracker's default profile)."""
    reverse_speed_mps: float = 1.5
    """Cruise speed in reverse (m/s) of the drive-time estimate."""
    lateral_accel_mps2: float = 1.0
    """Lateral acceleration bound v²·|c| (m/s²) of the drive-time estimate."""
    heading_slack_deg: float = 5.0
    """Terminal headings farther than this from the target's cost ``heading_penalty``."""
    heading_penalty: float = 5.0
    """Cost of a terminal heading outside the slack (m): the tracker parks within the env's own 10°, so a plan
    ending at that bound leaves no room for tracking error."""
    curvature_tolerance: float = 0.05
    """A plan is steerable when every sampled |steer curvature| is within (1 + this)·κ_max: the tracker's own
    check (`tracking.config.ExecutorConfig.curvature_tolerance`, same default, pinned by a test)."""
    sample_ds_m: float = 0.05
    """Spacing of the plan samples costed and checked (m): the tracker's reference spacing
    (`tracking.config.ExecutorConfig.reference_ds_m`), so the steering check sees what the tracker sees."""

    def __post_init__(self) -> None:
        if not self.margins_m or min(self.margins_m) < 0:
            raise ValueError(f"ChoiceWeights.margins_m: expected margins >= 0 m, got {self.margins_m!r}")
        for name in ("forward_speed_mps", "reverse_speed_mps", "lateral_accel_mps2"):
            if not getattr(self, name) > 0:
                raise ValueError(f"ChoiceWeights.{name}: expected > 0, got {getattr(self, name)!r}")

    @property
    def top_speed_ratio(self) -> float:
        """forward speed / the faster gear's speed: ``drive_length`` ≥ this × L (``choose``'s lower bound)."""
        return self.forward_speed_mps / max(self.forward_speed_mps, self.reverse_speed_mps)


def drive_length(rows: np.ndarray, weights: ChoiceWeights) -> float:
    """Drive time of sampled plan rows (``Plan.sample``: …, steer curvature c, gear, s) at the speed
    min(gear's cruise speed, √(a_lat / |c|)) at every sample, times the forward cruise speed: a length (m) that
    counts curves and reverse stretches as the slower driving they are (the clip runs have a time limit)."""
    ds = np.diff(rows[:, 5])
    cruise = np.where(rows[1:, 4] > 0, weights.forward_speed_mps, weights.reverse_speed_mps)
    curve = np.sqrt(weights.lateral_accel_mps2 / np.maximum(np.abs(rows[1:, 3]), 1e-12))
    return float(np.sum(ds / np.minimum(cruise, curve)) * weights.forward_speed_mps)


def curve_surcharge(weights: ChoiceWeights, kappa: float, length_m: float) -> float:
    """How much longer ``drive_length`` counts ``length_m`` driven forward at curvature ``kappa`` than driven straight
    (m): length · (v_f / min(v_f, √(a_lat / |κ|)) − 1), v_f the forward cruise speed."""
    curve = math.sqrt(weights.lateral_accel_mps2 / max(abs(kappa), 1e-12))
    return length_m * (weights.forward_speed_mps / min(weights.forward_speed_mps, curve) - 1.0)


def steerable(rows: np.ndarray, vehicle: VehicleSpec, weights: ChoiceWeights) -> bool:
    """Every sampled |steer curvature| of plan rows (``Plan.sample``) is within (1 + ``curvature_tolerance``)·κ_max:
    the tracker's own check of a plan it is given."""
    limit = (1.0 + weights.curvature_tolerance) * vehicle.kappa_max
    return bool(np.all(np.abs(rows[:, 3]) <= limit))


def plan_cost(plan: Plan, scene: Scene, vehicle: VehicleSpec, weights: ChoiceWeights) -> tuple[bool, float]:
    """(steering beyond κ_max, cost) of a successful plan; lower is better, steerable plans first.

    Steering: |steer curvature| of ``Plan.sample(weights.sample_ds_m)`` within (1 + ``curvature_tolerance``)·κ_max,
    the tracker's own check. Cost: ``drive_length`` + reversal, clearance and terminal-heading terms of
    ``weights``."""
    rows = plan.sample(weights.sample_ds_m)
    too_sharp = not steerable(rows, vehicle, weights)
    level = clearance_level(scene, rows[:, :3], vehicle, weights.margins_m)
    if level < 0:
        steps = sorted(weights.margins_m)
        level = -(steps[1] - steps[0]) if len(steps) > 1 else -weights.wanted_margin_m
    heading_error = heading_gap(rows[-1, 2], scene.target[2])
    reversals = plan.metrics()[1]
    cost = (drive_length(rows, weights) + weights.reversal_weight * reversals
            + weights.clearance_weight * max(0.0, weights.wanted_margin_m - level)
            + weights.heading_penalty * (heading_error > math.radians(weights.heading_slack_deg)))
    return too_sharp, cost


def cost_lower_bound(plan: Plan, weights: ChoiceWeights) -> float:
    """A lower bound of ``plan_cost`` without sampling the plan: the arcs' drive length exactly (constant curvature
    per arc), the Hermite segment's as ``top_speed_ratio`` × L_H, the reversal term; a hair below, so rounding
    never lifts it above the cost."""
    arcs = np.asarray(plan.arcs, float).reshape(-1, 2)
    cruise = np.where(arcs[:, 1] > 0, weights.forward_speed_mps, weights.reverse_speed_mps)
    curve = np.sqrt(weights.lateral_accel_mps2 / np.maximum(np.abs(arcs[:, 0]), 1e-12))
    drive = float(np.sum(np.abs(arcs[:, 1]) / np.minimum(cruise, curve))) * weights.forward_speed_mps
    if plan.hermite is not None:
        drive += weights.top_speed_ratio * plan.hermite.length
    return drive + weights.reversal_weight * plan.metrics()[1] - 1e-9


def choose(plans: Sequence[Plan], scene: Scene, vehicle: VehicleSpec, weights: ChoiceWeights | None = None) -> Plan:
    """The successful plan of ``plans`` with the lowest ``plan_cost``; ties keep the earlier plan. With no
    successful plan, the first plan (the mean rollout when it leads the list).

    Plans are costed in order of ``cost_lower_bound`` and the search stops once that bound exceeds the best
    steerable cost found (the clearance checks are the expensive part)."""
    if not plans:
        raise ValueError("choose: expected at least one plan, got none")
    weights = ChoiceWeights() if weights is None else weights
    bounds = [(cost_lower_bound(p, weights), i) for i, p in enumerate(plans) if p.success]
    best: tuple[tuple[bool, float], int] | None = None
    for bound, i in sorted(bounds):
        if best is not None and not best[0][0] and bound > best[0][1]:
            break
        candidate = (plan_cost(plans[i], scene, vehicle, weights), i)
        if best is None or candidate < best:
            best = candidate
    return plans[0] if best is None else plans[best[1]]
