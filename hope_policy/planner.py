"""The adapted HOPE as a planner (paper §IV-B, App. ``app:hope-adaptation``; spec §7).

``HopePlanner.from_checkpoint(path).plan(scene, start) -> Plan`` plays the trained policy in the environment it was
trained in (``HopeParkingEnv`` with the checkpoint's ``HopeEnvConfig``): observations turned into the network's
inputs as in training (`hope_policy.inputs`: a BEV raster encoded by the frozen autoencoder the config names) and
normalised with the statistics stored in the checkpoint, the Reeds–Shepp takeover and the fixed Hermite terminator
in the loop exactly as in training, until success, a hard failure or the step budget. A success is claimed only
when the plan passes the rule it is scored by (`np_sim.validate.validation_failure`); otherwise it becomes a failure
'validation: …'.

Actions (``action``): 'sampled' (the default) is HOPE's own evaluation protocol and the paper's wording ("samples
an executed action from 42 anchors using the policy density multiplied by LiDAR-derived safety weights"): with the
action mask an anchor drawn by HOPE's masked choice (`hope_policy.action_mask.apply_mask`), without it
``clip(μ + σ ε, −1, 1)``, as HOPE's ``choose_action`` plays both at evaluation. The draws come from a generator
seeded by (``seed``, the start pose's bits), so a plan depends only on its scene, start and seed, not on the order
of the calls. 'mean' is a deterministic variant: the mean action, or the most probable masked anchor.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
import torch

from hope_policy.action_mask import apply_mask
from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.config import HOPE_ACTIONS
from hope_policy.env import HopeParkingEnv
from hope_policy.inputs import PolicyInputs
from hope_policy.network import HopeActorCritic
from hope_policy.normalization import ObservationNormaliser
from hope_policy.spaces import observation_space
from hope_policy.train import HopeTrainConfig
from np_policy.checkpoint import CheckpointError, load_weights
from np_policy.planner import query_seed
from np_sim.errors import ConfigError
from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.validate import validation_failure


class HopePlanner:
    """A trained adapted-HOPE policy with its observation statistics, as a planner."""

    name = "hope"
    convention = "reference_point"

    def __init__(self, model: HopeActorCritic, normaliser: ObservationNormaliser, config: HopeTrainConfig,
                 inputs: PolicyInputs | None = None, action: str = "sampled", seed: int = 0):
        if action not in HOPE_ACTIONS:
            raise ConfigError(f"HopePlanner.action: expected one of {HOPE_ACTIONS}, got {action!r}")
        if not (isinstance(seed, int) and seed >= 0):
            raise ConfigError(f"HopePlanner.seed: expected an integer >= 0, got {seed!r}")
        if config.env.collision != self.convention:
            raise ConfigError(f"HopePlanner: expected an env with {self.convention!r} collision checks, got "
                              f"{config.env.collision!r}")
        self.model = model.eval()
        self.normaliser = normaliser
        self.config = config
        self.inputs = PolicyInputs(config.env, config.bev_encoder_file) if inputs is None else inputs
        self.action_mode = action
        self.seed = seed

    @classmethod
    def from_checkpoint(cls, path: str | Path, action: str = "sampled", seed: int = 0) -> "HopePlanner":
        """Rebuild the network, the normaliser and the env config stored in an adapted-HOPE checkpoint
        (``final.pt`` or a snapshot), playing ``action`` with ``seed`` (module docstring); CheckpointError naming
        the file when it is not one or does not fit."""
        payload = load_hope_checkpoint(path)
        try:
            config = HopeTrainConfig.from_dict(payload["config"])
        except ConfigError as exc:
            raise CheckpointError(f"{path}: its stored config is not a valid HopeTrainConfig: {exc}") from exc
        space = observation_space(config.env)
        inputs = PolicyInputs(config.env, config.bev_encoder_file)
        model = HopeActorCritic(inputs.modalities(space))
        load_weights(model, payload["model"], path)
        normaliser = ObservationNormaliser.for_space(space, config.env)
        try:
            normaliser.load_state_dict(payload["obs_norm"])
        except (KeyError, ValueError) as exc:
            raise CheckpointError(f"{path}: its observation statistics do not fit its config: {exc}") from exc
        return cls(model, normaliser, config, inputs, action, seed)

    def action(self, obs: dict[str, np.ndarray], rng: np.random.Generator | None = None) -> np.ndarray:
        """The action (2,) for one raw observation: drawn with ``rng`` as HOPE evaluates (the masked anchor choice,
        or the clipped Gaussian sample without the mask), or with ``rng`` None the mean or most probable anchor."""
        batch = self.normaliser(self.inputs({key: np.asarray(value)[None] for key, value in obs.items()}))
        with torch.no_grad():
            dist = self.model.distribution({key: torch.tensor(value) for key, value in batch.items()})
        mean, std = dist.mean.numpy(), dist.stddev.numpy()
        if "action_mask" in obs:
            action = apply_mask(mean, std, np.asarray(obs["action_mask"])[None], rng)
        elif rng is None:
            action = mean
        else:
            action = np.clip(mean + std * rng.standard_normal(mean.shape), -1.0, 1.0)
        return action[0].astype(np.float32)

    def episode_rng(self, start) -> np.random.Generator | None:
        """The generator of one plan's draws (None for the 'mean' action): seeded by the planner's seed and the
        start pose's bits (`np_policy.planner.query_seed`, as NeuralParker's sampled queries), so the same start
        draws the same actions whatever was planned before."""
        return None if self.action_mode == "mean" else np.random.default_rng(query_seed(self.seed, start))

    def plan(self, scene: Scene, start) -> Plan:
        """Roll the policy out from ``start`` (module docstring); the episode as a ``Plan``."""
        t0 = time.perf_counter()
        env = HopeParkingEnv(scene, self.config.env)
        obs, _ = env.reset(options={"scene_index": 0, "start": np.asarray(start, float)})
        rng = self.episode_rng(start)
        while True:
            obs, _, terminated, truncated, info = env.step(self.action(obs, rng))
            if terminated or truncated:
                break
        plan = info["plan"]
        if plan.success:
            env_config = self.config.env
            reason = validation_failure(scene, plan, self.convention, env_config.vehicle, env_config.samples_per_arc)
            if reason:
                plan = dataclasses.replace(plan, success=False, reason=reason)
        return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0)
