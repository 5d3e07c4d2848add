"""The NeuralParker planner: deterministic policy rollout with the terminal connector in the loop (SPEC §7).

``NeuralParkerPlanner.from_checkpoint(path).plan(scene, start) -> Plan`` plays the mean action in the same
environment the policy was trained in (``ParkingEnv`` with the checkpoint's ``EnvConfig``), so arcs, collision
checks, the heading gate and the Hermite selection follow exactly the env's rules. The mean action is evaluated by
``CompiledActor`` (the same weights in one numba function, about 20× faster than torch at batch 1). Every
successful rollout is validated before it is claimed or chosen (`np_sim.validate.validation_failure`): the env's
own rule, which it passes by construction, and under the footprint convention the exact swept footprint, which a
rollout checked at 30 samples per arc can break between samples; such a rollout becomes a failure 'validation: …'.

``samples=N`` (beyond the paper, ``np_policy.sampling``) adds N seeded stochastic rollouts of the same policy to
the mean rollout and returns the successful one the tracker can steer with the lowest drive-time, reversal,
clearance and terminal-heading cost; ``samples=0`` (the default) is the paper's planner. ``rescue`` adds wider
rounds that run only when none of those succeeds: each ``(n, scale)`` samples ``n`` rollouts with the policy's
standard deviation times ``scale``, in order, until one round has a successful plan (with
``rescue_clearance_m``, a plan keeping at least that clearance). A round ``(n, scale, 'uniform')`` draws each
rollout's first arc uniformly over the action box instead (`np_policy.sampling.FIRST_ARCS`): the escape from a
start where the policy's own first arcs all collide. ``action='sample'`` plays
one rollout of sampled actions instead of the mean (seeded per query, `query_seed`): how a policy trained with
Tianshou acts at test time by default, for comparisons with figures measured that way.
"""

from __future__ import annotations

import dataclasses
import time
import weakref
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from np_policy.checkpoint import load_checkpoint, load_weights
from np_policy.inference import CompiledActor
from np_policy.network import ActorCritic
from np_policy.sampling import (FIRST_ARCS, ChoiceWeights, SampledRollouts, choose, clearance_level, end_reason,
                                hermite_of)
from np_policy.train import TrainConfig, check_benchmark_layout, checkpoint_config
from np_sim.env import ParkingEnv
from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.validate import validation_failure


ACTIONS = ("mean", "sample")
"""How the planner acts: the policy's mean action (the paper's planner, SPEC §7) or one sampled action per arc
(each arc ``clip(μ(o) + σ·ε, −1, 1)``: what a Tianshou PPO policy plays at test time unless it is built with
``deterministic_eval=True``)."""


RescueRound = tuple[int, float] | tuple[int, float, str]
"""One rescue round: (rollouts, standard-deviation scale[, first arc: 'policy' (default) or 'uniform'])."""


def rescue_round(spec: Sequence) -> tuple[int, float, str]:
    """A rescue round as (n, scale, first_arc), the first arc 'policy' when left out; ValueError naming what is
    wrong otherwise."""
    spec = tuple(spec)
    if len(spec) not in (2, 3):
        raise ValueError(f"NeuralParkerPlanner: a rescue round is (n, scale[, first_arc]), got {spec!r}")
    n, scale, first_arc = (*spec, "policy")[:3]
    if int(n) != n or int(n) < 1 or not scale > 0:
        raise ValueError(f"NeuralParkerPlanner: rescue rounds must be (n >= 1, scale > 0), got {spec!r}")
    if first_arc not in FIRST_ARCS:
        raise ValueError(f"NeuralParkerPlanner: a rescue round's first arc must be one of {FIRST_ARCS}, got {spec!r}")
    return int(n), float(scale), first_arc


def query_seed(seed: int, start) -> np.random.SeedSequence:
    """The noise seed of one ``action='sample'`` query: the planner's ``seed`` and the start pose's bits, so the
    same query gives the same plan and different starts draw independent noise."""
    return np.random.SeedSequence([int(seed), *np.asarray(start, np.float64).reshape(3).view(np.uint64).tolist()])


class NeuralParkerPlanner:
    """A trained policy as a planner."""

    def __init__(self, model: ActorCritic, config: TrainConfig, samples: int = 0,
                 weights: ChoiceWeights | None = None, seed: int = 0, rescue: Sequence[RescueRound] = (),
                 margin_m: float = 0.0, action: str = "mean", rescue_clearance_m: float = 0.0):
        if int(samples) < 0:
            raise ValueError(f"NeuralParkerPlanner: samples must be >= 0, got {samples!r}")
        if action not in ACTIONS:
            raise ValueError(f"NeuralParkerPlanner: action must be one of {ACTIONS}, got {action!r}")
        if action == "sample" and (samples or rescue):
            raise ValueError("NeuralParkerPlanner: action='sample' plays one sampled rollout; it does not combine "
                             f"with samples ({samples}) or rescue rounds ({list(rescue)})")
        if not rescue_clearance_m >= 0:
            raise ValueError(f"NeuralParkerPlanner: rescue_clearance_m must be >= 0 m, got {rescue_clearance_m!r}")
        rescue = [rescue_round(spec) for spec in rescue]
        self.model = model.eval()
        self.actor = CompiledActor(self.model)
        self.body = config.env.vehicle
        if margin_m:  # the rollouts' collision checks use the grown footprint; costs still see the real body
            config = dataclasses.replace(config, env=dataclasses.replace(config.env,
                                                                         vehicle=self.body.inflated(margin_m)))
        self.config = config
        self.weights = ChoiceWeights() if weights is None else weights
        std = self.model.log_std.detach().exp().numpy()
        self.sampled = SampledRollouts(self.actor, std, config.env, samples, seed) if samples else None
        self.seed = int(seed)
        self.single = SampledRollouts(self.actor, std, config.env, 1, seed) if action == "sample" else None
        self.rescue = [SampledRollouts(self.actor, std * scale, config.env, n, seed + 1 + k, first_arc)
                       for k, (n, scale, first_arc) in enumerate(rescue)]
        self.rescue_clearance_m = float(rescue_clearance_m)
        self._envs: weakref.WeakKeyDictionary[Scene, ParkingEnv] = weakref.WeakKeyDictionary()

    def _env(self, scene: Scene) -> ParkingEnv:
        """One env per scene, rebuilt when the env config changes (packing a scene costs about a millisecond)."""
        env = self._envs.get(scene)
        if env is None or env.config != self.config.env:
            env = ParkingEnv(scene, self.config.env)
            self._envs[scene] = env
        return env

    @classmethod
    def from_checkpoint(cls, path: str | Path, connector: str | None = None, samples: int = 0,
                        weights: ChoiceWeights | None = None, seed: int = 0,
                        rescue: Sequence[RescueRound] = (), margin_m: float = 0.0,
                        action: str = "mean", rescue_clearance_m: float = 0.0,
                        benchmark: str | None = None) -> "NeuralParkerPlanner":
        """Rebuild the network and env config stored in a checkpoint (CheckpointError on a bad file).

        ``connector`` ('fixed', 'ensemble' or 'centred', `np_sim.config.ConnectorConfig.variant`) replaces the
        checkpoint's terminal connector (paper §III-E: the 81-candidate ensemble used at evaluation only); None
        keeps it. ``samples``, ``weights``, ``seed``, ``rescue``: best-of-N sampled rollouts and the wider rounds
        after a failure (module docstring; 0 and () = the paper's planner). ``margin_m``: the rollouts' collision
        checks use the footprint grown by this on every side (`VehicleSpec.inflated`); the choice's costs see the
        real body. ``action``: 'mean' (the deterministic planner, default) or 'sample' (one rollout of sampled
        actions, `plan`). ``rescue_clearance_m``: the rescue rounds also run while the chosen plan's clearance
        level (`np_policy.sampling.clearance_level` on ``weights.margins_m``) is below this (m); 0 = only after
        a failure. ``benchmark`` ('factorial', 'topology', 'examples', 'site'), when given, names the scenes it
        will plan: a checkpoint of another observation layout is refused here, with both layouts named
        (`np_policy.train.check_benchmark_layout`)."""
        payload = load_checkpoint(path)
        config = checkpoint_config(path, payload)
        if benchmark is not None:
            check_benchmark_layout(path, config, benchmark)
        if connector is not None:
            env = config.env
            env = dataclasses.replace(env, connector=env.connector.variant(connector))
            config = dataclasses.replace(config, env=env)
        model = ActorCritic(config.env.observation, config.network)
        load_weights(model, payload["model"], path)
        return cls(model, config, samples=samples, weights=weights, seed=seed, rescue=rescue, margin_m=margin_m,
                   action=action, rescue_clearance_m=rescue_clearance_m)

    def plan(self, scene: Scene, start) -> Plan:
        """Roll out the mean action from ``start`` until success, collision or the arc budget (paper §III-A); with
        ``samples``, the best of that and the sampled rollouts (``np_policy.sampling.choose``); with
        ``action='sample'``, one rollout of sampled actions."""
        t0 = time.perf_counter()
        if self.single is not None:
            plan = self._claimed(scene, self.single(scene, start, seed=query_seed(self.seed, start))[0])
            return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0)
        plan = self._mean_rollout(scene, start)
        if self.sampled is None:
            plan = self._claimed(scene, plan)
        else:
            plan = self._choose_claimed(scene, [plan, *self.sampled(scene, start)])
        for rounds in self.rescue:
            if plan.success and not self._too_close(scene, plan):
                break
            plan = self._choose_claimed(scene, [plan, *rounds(scene, start)], first_checked=True)
        return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0)

    def _choose_claimed(self, scene: Scene, plans: Sequence[Plan], first_checked: bool = False) -> Plan:
        """``choose`` among the plans whose success passes ``_claimed``: the chosen plan is validated, and when it
        fails it is replaced by its failure and the choice is made again. The same answer as validating every plan
        first, at the cost of validating only the candidates the choice reaches (the exact footprint rule costs
        milliseconds per rollout). ``first_checked``: ``plans[0]`` has been validated already."""
        plans = list(plans)
        while True:
            plan = choose(plans, scene, self.body, self.weights)
            if not plan.success or (first_checked and plan is plans[0]):
                return plan
            claimed = self._claimed(scene, plan)
            if claimed.success:
                return plan
            plans[next(i for i, p in enumerate(plans) if p is plan)] = claimed

    def _claimed(self, scene: Scene, plan: Plan) -> Plan:
        """``plan``, or a failure with reason 'validation: …' when a success breaks the rule it is scored by (the
        env's own: the paper's or the sampled footprint) or, under the footprint convention, the exact swept rule
        (`np_sim.validate.validation_failure`, with the real body)."""
        if not plan.success:
            return plan
        env = self.config.env
        reason = validation_failure(scene, plan, env.collision, self.body, env.episode.samples_per_arc)
        return dataclasses.replace(plan, success=False, reason=reason) if reason else plan

    def _too_close(self, scene: Scene, plan: Plan) -> bool:
        """The plan keeps less clearance than ``rescue_clearance_m`` (module docstring)."""
        if self.rescue_clearance_m <= 0.0:
            return False
        poses = plan.sample(self.weights.sample_ds_m)[:, :3]
        return clearance_level(scene, poses, self.body, self.weights.margins_m) < self.rescue_clearance_m

    def _mean_rollout(self, scene: Scene, start) -> Plan:
        env = self._env(scene)
        obs, _ = env.reset(options={"start": np.asarray(start, float)})
        kappa_max, l_max = self.config.env.vehicle.kappa_max, self.config.env.episode.max_length_m
        arcs = []
        while True:
            a = self.actor(obs)
            obs, _, terminated, truncated, info = env.step(a)
            arcs.append((float(a[0]) * kappa_max, float(a[1]) * l_max))
            if terminated or truncated:
                break
        reason = end_reason(env.core, 0)
        return Plan(start=np.asarray(start, float), arcs=np.array(arcs).reshape(-1, 2),
                    hermite=hermite_of(env.core, 0, scene), success=not reason, reason=reason)
