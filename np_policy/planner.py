"""The NeuralParker planner: policy rollouts with the terminal connector in the loop (spec §7).

``NeuralParkerPlanner.from_checkpoint(path, config).plan(scene, start) -> Plan`` plays the policy in the same
environment it was trained in (the checkpoint's ``EnvConfig``), so arcs, collision checks, the heading gate and
the Hermite selection follow exactly the env's rules. ``config`` is a `np_policy.config.NeuralParkerConfig`, by
name from ``PRESETS``: 'paper' (the default) plays the mean action once, the paper's planner; 'footprint_best_of_n'
adds seeded sampled rollouts and rescue rounds and returns the best by `np_policy.sampling.choose`; the anytime presets
answer first with the mean rollout when it keeps 0.2 m of clearance, and 'footprint_search' (beyond the paper, a
learned-first hybrid) then with a Hybrid A* plan for the body grown by 0.2 m before any sampling. Every rollout,
mean or sampled, is one batch of `np_policy.sampling.PolicyRollouts` (the mean rollout: a batch of one with zero
noise), its actions from ``CompiledActor`` (the same weights in one numba function, about 20× faster than torch
at batch 1). Every successful rollout is validated before it is claimed or chosen
(`np_sim.validate.validation_failure`): the env's own rule, which it passes by construction, and under the
footprint convention the exact swept footprint, which a rollout checked at 30 samples per arc can break between
samples; such a rollout becomes a failure 'validation: …' (a mean rollout the anytime test accepts is not validated
again: that test implies the rule, `clearance_covers_sweep`). ``action='sample'`` plays one rollout of sampled actions
instead of the mean (seeded per query, `query_seed`): how a policy trained with Tianshou acts at test time by
default, for comparisons with figures measured that way.

A scene with more obstacles than the policy's slots (a real lot) is observed by the site's rule unless
``config.over_capacity`` is 'refuse': the nearest obstacles fill the slots, re-selected after every arc, while the
rollout's arc and connector checks and the validation of the plan see the whole scene (`np_sim.nearest`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from np_policy.checkpoint import check_vehicle, load_checkpoint, load_weights
from np_policy.config import PAPER, NeuralParkerConfig, TrainConfig, check_benchmark_layout, checkpoint_config
from np_policy.guarded import GuardedRollout
from np_policy.inference import CompiledActor
from np_policy.network import ActorCritic
from np_policy.sampling import (PolicyRollouts, choose, clearance_covers_sweep, clearance_level, curve_surcharge,
                                pose_clearance_level, steerable)
from np_sim.collision import path_valid
from np_sim.config import EnvConfig
from np_sim.errors import ConfigError, StartInCollisionError
from np_sim.kinematics import heading_gap
from np_sim.plan import Plan
from np_sim.planners import HybridAStar, HybridAStarConfig
from np_sim.scene import Scene
from np_sim.validate import validation_failure
from np_sim.vehicle import VehicleSpec


def query_seed(seed: int, start) -> np.random.SeedSequence:
    """The noise seed of one ``action='sample'`` query: the planner's ``seed`` and the start pose's bits, so the
    same query gives the same plan and different starts draw independent noise."""
    return np.random.SeedSequence([int(seed), *np.asarray(start, np.float64).reshape(3).view(np.uint64).tolist()])


@dataclass(frozen=True, eq=False)
class Policy:
    """A trained NeuralParker policy: its network and the `TrainConfig` it was trained under (the env rules)."""

    model: ActorCritic
    """The actor–critic network (`np_policy.network`)."""
    train: TrainConfig
    """The run's config, as stored in the checkpoint."""

    @classmethod
    def load(cls, path: str | Path, benchmark: str | None = None, vehicle: VehicleSpec | None = None) -> "Policy":
        """Rebuild the network and config stored in a checkpoint (CheckpointError on a bad file). ``benchmark``
        ('factorial', 'topology', 'examples', 'site'), when given, names the scenes it will plan: a checkpoint of
        another observation layout is refused here, with both layouts named (`check_benchmark_layout`).
        ``vehicle``, when given, is the vehicle it will plan for: a checkpoint trained for another one is refused,
        with both vehicles named (`np_policy.checkpoint.check_vehicle`)."""
        payload = load_checkpoint(path)
        config = checkpoint_config(path, payload)
        if benchmark is not None:
            check_benchmark_layout(path, config, benchmark)
        if vehicle is not None:
            check_vehicle(path, config.env.vehicle, vehicle)
        model = ActorCritic(config.env.observation, config.network)
        load_weights(model, payload["model"], path)
        return cls(model, config)


def rollout_env(env: EnvConfig, max_arcs: int | None) -> EnvConfig:
    """The env of the sampled and rescue rollouts: ``env`` with its arc budget cut to ``max_arcs`` (None keeps
    it; `NeuralParkerConfig.rollout_max_arcs`). A rollout ends as a timeout at the budget and nothing else in the
    env depends on it, so every rollout that ends within ``max_arcs`` arcs is the same plan as under ``env``."""
    if max_arcs is None:
        return env
    if max_arcs > env.episode.max_arcs:
        raise ConfigError(f"NeuralParkerConfig.rollout_max_arcs: expected at most the policy env's arc budget "
                          f"(episode.max_arcs = {env.episode.max_arcs}), got {max_arcs}")
    return dataclasses.replace(env, episode=dataclasses.replace(env.episode, max_arcs=max_arcs))


def planning_env(policy: Policy, config: NeuralParkerConfig) -> EnvConfig:
    """The env the rollouts play: the policy's, its connector replaced by ``config.connector`` and, with
    ``config.margin_m``, its footprint grown by that much (the choice's costs still see the real body)."""
    env = policy.train.env
    if config.connector is not None:
        env = dataclasses.replace(env, connector=env.connector.variant(config.connector))
    if config.margin_m:
        env = dataclasses.replace(env, vehicle=env.vehicle.inflated(config.margin_m))
    return env


def _unless_start_collides(rollout) -> Plan | None:
    """``rollout()``'s plan, or None where the body it rolls out starts in collision (a grown body can where the
    real one does not)."""
    try:
        return rollout()
    except StartInCollisionError:
        return None


SEARCH_TIME_BUDGET_S = 3600.0
"""Wall-time budget of the anytime search (``search_fallback``): never reached, its node budget stops it first."""


def search_fallback(body: VehicleSpec, config: NeuralParkerConfig, margin_m: float) -> HybridAStar:
    """The anytime search of ``config.search_margin_m``: footprint convention, ``body`` grown by ``margin_m``, the
    node budget ``config.search_max_expanded``, the steering cost ``config.search_steer_cost_m``."""
    steer_cost = config.search_steer_cost_m
    if steer_cost is None:
        steer_cost = curve_surcharge(config.weights, body.kappa_max, HybridAStarConfig.step_m)
    search = HybridAStarConfig(vehicle=body.inflated(margin_m), max_expanded=config.search_max_expanded,
                               steer_cost_m=steer_cost, time_budget_s=SEARCH_TIME_BUDGET_S)
    return HybridAStar(search, convention="footprint")


class NeuralParkerPlanner:
    """A trained policy as a planner (module docstring); follows `np_sim.planners.protocol.Planner`."""

    name = "neuralparker"
    """Registry key of the planner kind."""

    def __init__(self, policy: Policy, config: NeuralParkerConfig = PAPER):
        if not isinstance(config, NeuralParkerConfig):
            raise TypeError(f"NeuralParkerPlanner: config must be a NeuralParkerConfig, got {type(config).__name__}")
        self.policy, self.config = policy, config
        self.model = policy.model.eval()
        self.actor = CompiledActor(self.model)
        self.body = policy.train.env.vehicle
        self.env_config = planning_env(policy, config)
        self.convention = self.env_config.collision
        std = self.model.log_std.detach().exp().numpy()
        nearest = config.over_capacity == "nearest"
        capped = rollout_env(self.env_config, config.rollout_max_arcs)
        self.mean = PolicyRollouts(self.actor, np.zeros(2), capped if config.mean_capped else self.env_config,
                                   nearest=nearest)
        grown = (rollout_env(dataclasses.replace(self.env_config,
                                                 vehicle=self.env_config.vehicle.inflated(config.mean_margin_m)),
                             config.rollout_max_arcs) if config.mean_margin_m else None)
        self.grown_mean = PolicyRollouts(self.actor, np.zeros(2), grown, nearest=nearest) if grown else None
        self.sampled = (PolicyRollouts(self.actor, std, capped, config.samples, config.seed, nearest=nearest)
                        if config.samples else None)
        self.guarded = (GuardedRollout(self.actor, std, grown if grown is not None else capped, config.guard_sigmas,
                                       nearest, config.weights.heading_slack_deg) if config.guard_sigmas else None)
        self.searches: dict[float, HybridAStar] = {}
        """The anytime searches by footprint margin (``search_at``)."""
        self.single = (PolicyRollouts(self.actor, std, self.env_config, 1, config.seed, nearest=nearest)
                       if config.action == "sample" else None)
        self.rescue = [PolicyRollouts(self.actor, std * scale, capped, n, config.seed + 1 + k, first_arc, nearest)
                       for k, (n, scale, first_arc) in enumerate(config.rescue)]
        # Twice the steerable bound: the Hermite segment's curvature is known only at its samples.
        self.kappa_limit = 2.0 * (1.0 + config.weights.curvature_tolerance) * self.body.kappa_max

    @classmethod
    def from_checkpoint(cls, path: str | Path, config: NeuralParkerConfig | str = PAPER,
                        benchmark: str | None = None, vehicle: VehicleSpec | None = None) -> "NeuralParkerPlanner":
        """The planner of the policy stored in ``path`` (`Policy.load`, with its ``benchmark`` and ``vehicle``
        checks), playing it as ``config`` says: a `NeuralParkerConfig` or the name of one of ``PRESETS``."""
        if isinstance(config, str):
            config = NeuralParkerConfig.preset(config)
        return cls(Policy.load(path, benchmark, vehicle), config)

    def plan(self, scene: Scene, start) -> Plan:
        """Roll out the mean action from ``start`` until success, collision or the arc budget (paper §III-A); with
        ``samples``, the best of that and the sampled rollouts (``np_policy.sampling.choose``), then the rescue
        rounds while the best fails or keeps too little clearance (``_rescue_wanted_m``), unless ``accept_mean_m``
        accepts the mean rollout first (with ``mean_margin_m``, the grown-body mean rollout before the plain one;
        with ``guard_sigmas``, the guarded rollout between them; with ``search_margin_m``, the grown-body search
        after them); with ``action='sample'``, one rollout of sampled actions. ``Plan.stage`` names the stage that
        gave the plan: 'mean' (either mean rollout), 'guarded', 'search', 'sampled' or 'rescue'."""
        t0 = time.perf_counter()
        if self.single is not None:
            plan = self.claimed(scene, self.single(scene, start, seed=query_seed(self.config.seed, start))[0])
            return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0, stage="sampled")
        anytime = self.config.accept_mean_m is not None
        grown, answered = self.grown_answer(scene, start)
        if answered:
            return dataclasses.replace(grown, plan_time_s=time.perf_counter() - t0, stage="mean")
        guarded, answered = self.guarded_answer(scene, start)
        if answered:
            return dataclasses.replace(guarded, plan_time_s=time.perf_counter() - t0, stage="guarded")
        plan, stage, searched = self._mean_rollout(scene, start), "mean", None
        if anytime:
            plan, answered = self._anytime_answer(scene, plan)
            if answered:
                return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0, stage=stage)
            searched, answered = self.search_answer(scene, start)
            if answered:
                return dataclasses.replace(searched, plan_time_s=time.perf_counter() - t0, stage="search")
        elif self.sampled is None:
            plan = self.claimed(scene, plan)
        if self.sampled is not None:
            earlier = (p for p in (grown, guarded, searched) if p is not None)
            candidates = [plan, *earlier, *self.sampled(scene, start)]
            plan, stage = self._choose_claimed(scene, candidates, anytime), "sampled"
        for k, rounds in enumerate(self.rescue):
            if plan.success and not self._too_close(scene, plan, self._rescue_wanted_m(k)):
                break
            plan, stage = self._choose_claimed(scene, [plan, *rounds(scene, start)], first_checked=True), "rescue"
        return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0, stage=stage)

    def accepted(self, scene: Scene, plan: Plan) -> bool:
        """The validated ``plan`` succeeds, is steerable and keeps ``accept_mean_m`` of clearance (the anytime test;
        at most the ``limited_clearance``); with ``accept_aligned``, it also ends within the choice's heading slack
        of the target's heading."""
        if not plan.success:
            return False
        margin = self.limited_clearance(scene, plan.start, self.config.accept_mean_m)
        weights = self.config.weights
        rows = plan.sample(weights.sample_ds_m)
        if self.config.accept_aligned and heading_gap(rows[-1, 2], scene.target[2]) > math.radians(
                weights.heading_slack_deg):
            return False
        return (steerable(rows, self.body, weights)
                and path_valid(scene, rows[:, :3], "footprint", self.body.inflated(margin)))

    def grown_mean_rollout(self, scene: Scene, start) -> Plan | None:
        """The mean rollout played with the footprint grown by ``mean_margin_m`` (not validated), or None without
        one or where the grown body's start is in collision."""
        return _unless_start_collides(lambda: self.grown_mean(scene, start)[0]) if self.grown_mean else None

    def grown_answer(self, scene: Scene, start) -> tuple[Plan | None, bool]:
        """(the grown-body mean rollout, validated with the real body, or None; whether the anytime test accepts
        it)."""
        return self._anytime_answer_of(scene, self.grown_mean_rollout(scene, start))

    def guarded_answer(self, scene: Scene, start) -> tuple[Plan | None, bool]:
        """(the guarded rollout (`np_policy.guarded`), validated with the real body, or None without one or where
        its body's start is in collision; whether the anytime test accepts it)."""
        plan = _unless_start_collides(lambda: self.guarded(scene, start)) if self.guarded else None
        return self._anytime_answer_of(scene, plan)

    def search_answer(self, scene: Scene, start) -> tuple[Plan | None, bool]:
        """(the grown-body Hybrid A* plan (``search_margin_m``, at most the ``limited_clearance``), validated with
        the real body, or None without a search; whether the anytime test accepts it)."""
        if self.config.search_margin_m is None:
            return None, False
        margin = self.limited_clearance(scene, start, self.config.search_margin_m)
        return self._anytime_answer(scene, self.search_at(margin).plan(scene, start))

    def search_at(self, margin_m: float) -> HybridAStar:
        """The anytime search for the footprint grown by ``margin_m`` (`search_fallback`), built once per margin."""
        if margin_m not in self.searches:
            self.searches[margin_m] = search_fallback(self.body, self.config, margin_m)
        return self.searches[margin_m]

    def limited_clearance(self, scene: Scene, start, wanted_m: float) -> float:
        """``wanted_m``, capped with ``start_limited_clearance`` at the clearance level of the ``start`` pose and with
        ``target_limited_clearance`` at the target's (the ``weights.margins_m`` ladder, 0 below its lowest rung): no
        path from that start, or to that target, keeps more."""
        ends = [start] * self.config.start_limited_clearance + [scene.target] * self.config.target_limited_clearance
        for pose in ends:
            if wanted_m <= 0.0:
                break
            level = pose_clearance_level(scene, pose, self.body, self.config.weights.margins_m)
            wanted_m = min(wanted_m, max(0.0, level))
        return wanted_m

    def accept_implies_valid(self, scene: Scene, plan: Plan) -> bool:
        """Whether the anytime test (``accepted``) of ``plan`` implies the claim check (``claimed``), so that an
        accepted plan is not validated a second time (`np_policy.sampling.clearance_covers_sweep`)."""
        if self.config.accept_mean_m is None or self.convention != "footprint":
            return False
        margin = self.limited_clearance(scene, plan.start, self.config.accept_mean_m)
        return clearance_covers_sweep(self.body, margin, self.config.weights.sample_ds_m, self.kappa_limit)

    def _anytime_answer_of(self, scene: Scene, plan: Plan | None) -> tuple[Plan | None, bool]:
        """``_anytime_answer`` of ``plan``, or (None, False) without one."""
        return (None, False) if plan is None else self._anytime_answer(scene, plan)

    def _anytime_answer(self, scene: Scene, plan: Plan) -> tuple[Plan, bool]:
        """(``plan`` validated, whether the anytime test accepts it); an accepted plan is not validated a second
        time where the test implies the rule (``accept_implies_valid``)."""
        if self.accept_implies_valid(scene, plan):
            if self.accepted(scene, plan):
                return plan, True
            return self.claimed(scene, plan), False
        plan = self.claimed(scene, plan)
        return plan, self.accepted(scene, plan)

    def _mean_rollout(self, scene: Scene, start) -> Plan:
        """The paper's planner: the mean action rolled out once (the batch of one with zero noise)."""
        return self.mean(scene, start)[0]

    def _choose_claimed(self, scene: Scene, plans: Sequence[Plan], first_checked: bool = False) -> Plan:
        """``choose`` among the plans whose success passes ``claimed``: the chosen plan is validated, and when it
        fails it is replaced by its failure and the choice is made again. The same answer as validating every plan
        first, at the cost of validating only the candidates the choice reaches (the exact footprint rule costs
        milliseconds per rollout). ``first_checked``: ``plans[0]`` has been validated already."""
        plans = list(plans)
        while True:
            plan = choose(plans, scene, self.body, self.config.weights)
            if not plan.success or (first_checked and plan is plans[0]):
                return plan
            checked = self.claimed(scene, plan)
            if checked.success:
                return plan
            plans[next(i for i, p in enumerate(plans) if p is plan)] = checked

    def claimed(self, scene: Scene, plan: Plan) -> Plan:
        """``plan``, or a failure with reason 'validation: …' when a success breaks the rule it is scored by (the
        env's own: the paper's or the sampled footprint) or, under the footprint convention, the exact swept rule
        (`np_sim.validate.validation_failure`, with the real body)."""
        if not plan.success:
            return plan
        env = self.env_config
        reason = validation_failure(scene, plan, env.collision, self.body, env.episode.samples_per_arc)
        return dataclasses.replace(plan, success=False, reason=reason) if reason else plan

    def _rescue_wanted_m(self, k: int) -> float:
        """The clearance (m) a successful plan must keep for rescue round ``k`` to be skipped:
        ``rescue_clearance_m`` before the first round, ``rescue_stop_m`` (when set) before the later ones."""
        stop = self.config.rescue_stop_m
        return self.config.rescue_clearance_m if k == 0 or stop is None else stop

    def _too_close(self, scene: Scene, plan: Plan, clearance_m: float) -> bool:
        """The plan's clearance level (the ``weights.margins_m`` ladder) is below ``clearance_m``
        (``limited_clearance``); never for 0."""
        clearance_m = self.limited_clearance(scene, plan.start, clearance_m)
        if clearance_m <= 0.0:
            return False
        weights = self.config.weights
        poses = plan.sample(weights.sample_ds_m)[:, :3]
        return clearance_level(scene, poses, self.body, weights.margins_m) < clearance_m
