"""The adapted HOPE as a planner (paper §IV-B, App. ``app:hope-adaptation``; spec §7).

``HopePlanner.from_checkpoint(path).plan(scene, start) -> Plan`` plays the trained policy deterministically in the
environment it was trained in (``HopeParkingEnv`` with the checkpoint's ``HopeEnvConfig``): observations turned into
the network's inputs as in training (`hope_policy.inputs`: a BEV raster encoded by the frozen autoencoder the
config names) and normalised with the statistics stored in the checkpoint, the policy's mean action, or with the
action mask the most probable masked anchor (`hope_policy.action_mask.apply_mask` without a generator), the
Reeds–Shepp takeover and the fixed Hermite terminator in the loop exactly as in training, until success, a hard
failure or the step budget. A success is claimed only when the plan passes the rule it is scored by
(`np_sim.validate.validation_failure`); otherwise it becomes a failure 'validation: …'.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
import torch

from hope_policy.action_mask import apply_mask
from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.env import HopeParkingEnv
from hope_policy.inputs import PolicyInputs
from hope_policy.network import HopeActorCritic
from hope_policy.normalization import ObservationNormaliser
from hope_policy.spaces import observation_space
from hope_policy.train import HopeTrainConfig
from np_policy.checkpoint import CheckpointError, load_weights
from np_sim.errors import ConfigError
from np_sim.plan import Plan
from np_sim.scene import Scene
from np_sim.validate import validation_failure


class HopePlanner:
    """A trained adapted-HOPE policy with its observation statistics, as a planner."""

    name = "hope"
    convention = "reference_point"

    def __init__(self, model: HopeActorCritic, normaliser: ObservationNormaliser, config: HopeTrainConfig,
                 inputs: PolicyInputs | None = None):
        if config.env.collision != self.convention:
            raise ConfigError(f"HopePlanner: expected an env with {self.convention!r} collision checks, got "
                              f"{config.env.collision!r}")
        self.model = model.eval()
        self.normaliser = normaliser
        self.config = config
        self.inputs = PolicyInputs(config.env, config.bev_encoder_file) if inputs is None else inputs

    @classmethod
    def from_checkpoint(cls, path: str | Path) -> "HopePlanner":
        """Rebuild the network, the normaliser and the env config stored in an adapted-HOPE checkpoint
        (``final.pt`` or a snapshot); CheckpointError naming the file when it is not one or does not fit."""
        payload = load_hope_checkpoint(path)
        try:
            config = HopeTrainConfig.from_dict(payload["config"])
        except ConfigError as exc:
            raise CheckpointError(f"{path}: its stored config is not a valid HopeTrainConfig: {exc}") from exc
        space = observation_space(config.env)
        inputs = PolicyInputs(config.env, config.bev_encoder_file)
        model = HopeActorCritic(inputs.modalities(space))
        load_weights(model, payload["model"], path)
        normaliser = ObservationNormaliser({key: box.shape for key, box in space.spaces.items()})
        try:
            normaliser.load_state_dict(payload["obs_norm"])
        except (KeyError, ValueError) as exc:
            raise CheckpointError(f"{path}: its observation statistics do not fit its config: {exc}") from exc
        return cls(model, normaliser, config, inputs)

    def action(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The deterministic action (2,) for one raw observation: the mean, or the most probable masked anchor."""
        batch = self.normaliser(self.inputs({key: np.asarray(value)[None] for key, value in obs.items()}))
        with torch.no_grad():
            dist = self.model.distribution({key: torch.tensor(value) for key, value in batch.items()})
        mean = dist.mean.numpy()
        if "action_mask" in obs:
            mean = apply_mask(mean, dist.stddev.numpy(), np.asarray(obs["action_mask"])[None])
        return mean[0].astype(np.float32)

    def plan(self, scene: Scene, start) -> Plan:
        """Roll the deterministic policy out from ``start`` (module docstring); the episode as a ``Plan``."""
        t0 = time.perf_counter()
        env = HopeParkingEnv(scene, self.config.env)
        obs, _ = env.reset(options={"scene_index": 0, "start": np.asarray(start, float)})
        while True:
            obs, _, terminated, truncated, info = env.step(self.action(obs))
            if terminated or truncated:
                break
        plan = info["plan"]
        if plan.success:
            env_config = self.config.env
            reason = validation_failure(scene, plan, self.convention, env_config.vehicle, env_config.samples_per_arc)
            if reason:
                plan = dataclasses.replace(plan, success=False, reason=reason)
        return dataclasses.replace(plan, plan_time_s=time.perf_counter() - t0)
