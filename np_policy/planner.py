"""The NeuralParker planner: deterministic policy rollout with the terminal connector in the loop (SPEC §7).

``NeuralParkerPlanner.from_checkpoint(path).plan(scene, start) -> Plan`` plays the mean action in the same
environment the policy was trained in (``ParkingEnv`` with the checkpoint's ``EnvConfig``), so arcs, collision
checks, the heading gate and the Hermite selection follow exactly the env's rules. The mean action is evaluated by
``CompiledActor`` (the same weights in one numba function, about 20× faster than torch at batch 1).
"""

from __future__ import annotations

import dataclasses
import time
import weakref
from pathlib import Path

import numpy as np

from np_policy.checkpoint import load_checkpoint
from np_policy.inference import CompiledActor
from np_policy.network import ActorCritic
from np_policy.train import TrainConfig
from np_sim.env import ParkingEnv
from np_sim.frames import from_target_frame
from np_sim.kernels.step import R_H_FORWARD
from np_sim.plan import HermiteSegment, Plan
from np_sim.scene import Scene


class NeuralParkerPlanner:
    """A trained policy as a planner."""

    def __init__(self, model: ActorCritic, config: TrainConfig):
        self.model = model.eval()
        self.actor = CompiledActor(self.model)
        self.config = config
        self._envs: weakref.WeakKeyDictionary[Scene, ParkingEnv] = weakref.WeakKeyDictionary()

    def _env(self, scene: Scene) -> ParkingEnv:
        """One env per scene, rebuilt when the env config changes (packing a scene costs about a millisecond)."""
        env = self._envs.get(scene)
        if env is None or env.config != self.config.env:
            env = ParkingEnv(scene, self.config.env)
            self._envs[scene] = env
        return env

    @classmethod
    def from_checkpoint(cls, path: str | Path, connector: str | None = None) -> "NeuralParkerPlanner":
        """Rebuild the network and env config stored in a checkpoint (CheckpointError on a bad file).

        ``connector`` ('fixed' or 'ensemble') replaces the checkpoint's terminal connector (paper §III-E: the
        81-candidate ensemble used at evaluation only); None keeps it."""
        payload = load_checkpoint(path)
        config = TrainConfig.from_dict(payload["config"])
        if connector is not None:
            env = config.env
            env = dataclasses.replace(env, connector=dataclasses.replace(env.connector, mode=connector))
            config = dataclasses.replace(config, env=env)
        model = ActorCritic(config.env.observation, config.network)
        model.load_state_dict(payload["model"])
        return cls(model, config)

    def plan(self, scene: Scene, start) -> Plan:
        """Roll out the mean action from ``start`` until success, collision or the arc budget (paper §III-A)."""
        t0 = time.perf_counter()
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
        hermite = None
        h = info["hermite_index"]
        if h >= 0:
            core = env.core
            hermite = HermiteSegment(points=from_target_frame(core.h_pts[0, h].T, scene.target),
                                     forward=bool(core.R[0, R_H_FORWARD] > 0), length=float(info["hermite_length"]),
                                     delta_kappa=float(info["hermite_delta_kappa"]))
        reason = "" if info["success"] else ("collision" if info["collision"] else "timeout")
        return Plan(start=np.asarray(start, float), arcs=np.array(arcs).reshape(-1, 2), hermite=hermite,
                    success=bool(info["success"]), reason=reason, plan_time_s=time.perf_counter() - t0)
