"""Gymnasium environments of the NeuralParker arc-planning task (paper §III, spec §5).

## Description
The agent plans a parking manoeuvre as a sequence of curvature–length arcs. Each arc is executed with the
kinematics of paper eq:arc and checked at 30 reference points (or the full footprint, by config); after a valid
arc that does not end at the target, the in-loop Hermite terminal connector (81-candidate ensemble or fixed
nine) tries to finish the manoeuvre when the reached heading faces the target (sin θ̃ > 0).

## Action space
``Box(-1, 1, (2,), float32)``, mapped linearly: κ = a_0 · 0.68 (1/m; positive = heading decreases, spec §2),
l = a_1 · 10 (m; sign = gear). Actions outside the box raise (the env never clips).

## Observation space
``Box(-inf, inf, (484,), float32)`` by default (flat), or a ``Dict`` of the parts when
``ObservationConfig.flat`` is False; layout in ``np_sim.observation``: ego (4), LiDAR clearances (120),
obstacle slots (20 × 16), boundary slots (10 × 4); unused slots hold −1e4.

## Rewards
eq:step-reward each arc; on success eq:terminal-reward (with the Hermite score p_H, floored at −500 for the
ensemble); on collision or boundary failure −2501; timeout adds nothing.

## Starting state
A scene drawn uniformly from ``scenes`` and a start from the start sampler (default: uniform, footprint-free in
the scene's start region). ``reset(options={"scene_index": k, "start": [x, y, θ]})`` fixes both.

## Episode end
Terminated on collision/boundary failure or success (direct: within 0.1 m and 10°; or a feasible Hermite
connection). Truncated after 200 arcs.

## Info
``success``, ``collision``, ``hermite_index`` (−1 when none), ``hermite_length``, ``hermite_delta_kappa``,
``scene_index``, ``pose``, ``n_arcs`` and the episode's eq:metrics so far: ``path_length``, ``reversals``,
``delta_kappa``.

## Version history
* v0: first release.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from np_sim.config import EnvConfig
from np_sim.env_core import BatchCore, step_outcome
from np_sim.kernels import step as K
from np_sim.observation import section_shapes, split_observation
from np_sim.scene import Scene
from np_sim.starts import StartSampler

__all__ = ["EnvConfig", "ParkingEnv", "ParkingVectorEnv"]


def _observation_space(config: EnvConfig, size: int) -> spaces.Space:
    if config.observation.flat:
        return spaces.Box(-np.inf, np.inf, (size,), np.float32)
    return spaces.Dict({k: spaces.Box(-np.inf, np.inf, s, np.float32)
                        for k, s in section_shapes(config.observation).items()})


def _action_space() -> spaces.Box:
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


class ParkingEnv(gym.Env):
    """One NeuralParker planning episode at a time (the batched core with one env); see the module docstring."""

    metadata = {"render_modes": []}

    def __init__(self, scenes: Scene | Sequence[Scene], config: EnvConfig | None = None,
                 start_sampler: StartSampler | None = None):
        self.config = EnvConfig() if config is None else config
        self.core = BatchCore(scenes, 1, self.config, start_sampler)
        self.action_space = _action_space()
        self.observation_space = _observation_space(self.config, self.core.obs_size)

    def _obs(self):
        row = self.core.obs[0].copy()
        return row if self.config.observation.flat else split_observation(row, self.config.observation)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        self.core.reset_envs(np.array([0]), self.np_random, options.get("scene_index"), options.get("start"))
        return self._obs(), {"scene_index": int(self.core.S[0, K.S_SCENE])}

    def step(self, action):
        self.core.step(np.asarray(action, np.float64).reshape(1, 2))
        R = self.core.R[0]
        info = {k: (v[0].copy() if isinstance(v[0], np.ndarray) else v[0].item())
                for k, v in self.core.step_info().items()}
        return self._obs(), float(R[K.R_REWARD]), bool(R[K.R_TERMINATED]), bool(R[K.R_TRUNCATED]), info


class ParkingVectorEnv(VectorEnv):
    """N NeuralParker episodes over a list of scenes, stepped in one compiled call (same-step autoreset).

    When an episode ends, ``step`` returns the first observation of the next episode in its row and puts the
    last observation in ``info["final_obs"]`` (rows valid where ``info["_final_obs"]``); the ended episode's
    info entries are the step's info arrays (``success``, ``path_length``, …) at those rows.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, scenes: Sequence[Scene], num_envs: int, config: EnvConfig | None = None, seed: int | None = 0,
                 start_sampler: StartSampler | None = None):
        self.config = EnvConfig() if config is None else config
        self.core = BatchCore(scenes, num_envs, self.config, start_sampler)
        self.num_envs = self.core.num_envs
        self.single_action_space = _action_space()
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.single_observation_space = _observation_space(self.config, self.core.obs_size)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._rng = np.random.default_rng(seed)
        self._all = np.arange(self.num_envs)

    def state_dict(self) -> dict[str, Any]:
        """Episode state of every env and the start generator's state (for exact resumption of training)."""
        return {"S": self.core.S.copy(), "rng": self._rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any], obs: np.ndarray) -> None:
        """Inverse of ``state_dict``; ``obs`` are the current observations saved alongside."""
        self.core.S[:] = state["S"]
        self.core.obs[:] = obs
        self._rng.bit_generator.state = state["rng"]

    def set_start_sampler(self, sampler: StartSampler) -> None:
        """Replace the start sampler (e.g. when the curriculum fraction changes)."""
        self.core.sampler = sampler

    def _obs(self, flat: np.ndarray):
        return flat if self.config.observation.flat else split_observation(flat, self.config.observation)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        options = options or {}
        self.core.reset_envs(self._all, self._rng, options.get("scene_index"), options.get("start"))
        return self._obs(self.core.obs.copy()), {"scene_index": self.core.S[:, K.S_SCENE].astype(np.int64)}

    def step(self, actions):
        core = self.core
        core.step(actions)
        reward, terminated, truncated = step_outcome(core.R)
        info = core.step_info()
        done = terminated | truncated
        if done.any():
            ids = np.flatnonzero(done)
            final = np.zeros_like(core.obs)
            final[ids] = core.obs[ids]
            info["final_obs"] = self._obs(final)
            info["_final_obs"] = done
            core.reset_envs(ids, self._rng)
        return self._obs(core.obs.copy()), reward, terminated, truncated, info
