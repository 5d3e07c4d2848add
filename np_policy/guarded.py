"""The guarded mean rollout: the policy's mean action with a one-arc lookahead (beyond the paper).

The footprint planner answers a call at the cost of one rollout only when the policy's mean rollout is accepted
(`np_policy.planner`, the anytime test). Where it is not, the mean rollout usually fails at one arc: the mean
action runs the body into an obstacle, or it passes a pose from which a slightly different arc would have parked.
``GuardedRollout`` keeps the mean rollout but, before committing each arc, steps the mean action and a fixed star of
offsets around it from the same state, in one batched step (``BatchCore.copy_env``): the rows
``GUARD_DIRECTIONS`` × each multiple in ``sigmas`` of the policy's standard deviation (in that order, the mean
first). The arc taken is the first row, in that order, that parks (the connector reached the target) with its
terminal heading within ``heading_slack_deg`` of the target's; else the first that neither collides nor parks: the
mean action wherever it is free; else the first that parks at all. A park at the edge of the parking tolerance
(the connector's 80° and 100° candidates end 10° off) is passed over while the rollout can go on: the tracker
arrives a little beyond such an end and replans, which in the closed loop cycled until the clip's time ran out
(training clip train-0000407). The rollout ends in success, as a timeout at the env's arc budget, or in collision
when every row collides. Nothing is random: the
same query gives the same plan, and a query whose mean rollout never collides nor passes a parkable pose gives the
mean rollout itself. Played in the env whose body is grown by the anytime margin, a collision is a loss of that
clearance, so the guard keeps it.

Measured on difficult training clips only (docs/best_of_n.md, 2026-12-06): with the body grown by 0.2 m and
offsets at 1, 2 and 3 σ, the anytime test accepts it on 72 of the 94 validation clips' first frames where the
grown-body mean rollout is accepted on 50, and in the closed loop on 188 clips it answers a fifth of the calls and
a fifth of the rescue calls go; but 165 runs park against the preset's 170 (one gained, six lost), so the
``footprint_anytime`` preset does not use it (``guard_sigmas`` turns it on).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from np_policy.sampling import ChoiceWeights, PolicyRollouts, end_reason, hermite_of
from np_sim.config import EnvConfig
from np_sim.kernels import step as K
from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.validate import end_pose_error

GUARD_DIRECTIONS = ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0),
                    (-1.0, -1.0))
"""Offset directions of the guard, per multiple of σ, in the order they are preferred: curvature up and down,
length up and down, then the four diagonals (the action is (curvature, signed length), normalised)."""


def guard_offsets(sigmas: Sequence[float]) -> np.ndarray:
    """The guard's rows in units of the policy's standard deviation: (0, 0) first, then ``GUARD_DIRECTIONS`` times
    each of ``sigmas`` in order; shape (1 + 8 · len(sigmas), 2)."""
    rows = [(0.0, 0.0)] + [(a * s, b * s) for s in sigmas for a, b in GUARD_DIRECTIONS]
    return np.array(rows, np.float64)


def guard_choice(R: np.ndarray, aligned: np.ndarray) -> int | None:
    """Index of the row the guard takes from one batched step's result rows ``R`` (module docstring): the first
    success whose terminal heading is ``aligned`` (a flag per row), else the first row that neither collided nor
    parked, else the first success; None when every row collided."""
    success = R[:, K.R_SUCCESS] > 0
    for rows in (np.flatnonzero(success & aligned), np.flatnonzero(~success & (R[:, K.R_COLLISION] == 0)),
                 np.flatnonzero(success)):
        if len(rows):
            return int(rows[0])
    return None


class GuardedRollout(PolicyRollouts):
    """The mean rollout with a one-arc lookahead over a fixed star of offsets (module docstring)."""

    def __init__(self, actor, std: np.ndarray, config: EnvConfig, sigmas: Sequence[float], nearest: bool = False,
                 heading_slack_deg: float = ChoiceWeights.heading_slack_deg):
        offsets = guard_offsets(sigmas)
        super().__init__(actor, std, config, len(offsets), 0, "policy", nearest)
        self.offsets = offsets * self.std
        self.heading_slack = math.radians(heading_slack_deg)

    def _plans(self, core, scene: Scene, start: np.ndarray, arcs: list[np.ndarray], actions: np.ndarray,
               scale: np.ndarray) -> list[Plan | None]:
        """The plan each row of the last step would end with when it parked (None for the others)."""
        return [Plan(start=start, arcs=np.array([*arcs, actions[row] * scale]), hermite=hermite_of(core, row, scene),
                     success=True, reason="") if core.R[row, K.R_SUCCESS] > 0 else None for row in range(self.n)]

    def _aligned(self, plans: list[Plan | None], scene: Scene) -> np.ndarray:
        """Per row: it parked with its terminal heading within ``heading_slack_deg`` of the target's."""
        return np.array([p is not None and end_pose_error(scene, p)[1] <= self.heading_slack for p in plans])

    def __call__(self, scene: Scene, start, seed=None) -> Plan:
        """The guarded rollout from ``start`` as one plan, successful or not (StartInCollisionError on a start in
        collision); ``seed`` is accepted for the rollouts' interface and unused (nothing is drawn)."""
        start = np.asarray(start, float)
        core = self.core(scene)
        rows = np.arange(self.n)
        core.reset_envs(rows, np.random.default_rng(0), 0, start)
        scale = np.array([self.config.vehicle.kappa_max, self.config.episode.max_length_m])
        arcs: list[np.ndarray] = []
        mean = np.asarray(self.actor.batch(core.obs[:1]), np.float64)[0]
        while True:
            actions = np.clip(mean + self.offsets, -1.0, 1.0)
            core.step(actions)
            parked = self._plans(core, scene, start, arcs, actions, scale)
            taken = guard_choice(core.R, self._aligned(parked, scene))
            if taken is None:
                return Plan(start=start, arcs=np.array([*arcs, actions[0] * scale]), hermite=None, success=False,
                            reason="collision")
            if parked[taken] is not None:
                return parked[taken]
            arcs.append(actions[taken] * scale)
            if core.R[taken, K.R_TRUNCATED] > 0:
                return Plan(start=start, arcs=np.array(arcs), hermite=None, success=False,
                            reason=end_reason(core, taken))
            core.copy_env(taken, rows)
            mean = np.asarray(self.actor.batch(core.obs[taken:taken + 1]), np.float64)[0]
