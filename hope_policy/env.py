"""Gymnasium environments of the adapted HOPE baseline (paper §IV-B, App. B; spec §7).

## Description
HOPE's task on the project's benchmark scenes: the agent holds a steering angle δ and a speed v for HOPE's rollout
(T = NUM_STEP × STEP_LENGTH = 0.5 s). On the kinematic bicycle that is an arc of physical curvature tan δ / L and
length l = v T, executed with the project's arc kinematics (paper eq:arc) and checked at 30 reference points, with
hard collision and boundary termination in place of HOPE's collision-and-retreat. After a valid arc the fixed
nine-candidate Hermite terminator tries to finish (0.68 1/m cap on the terminator only). Near the target HOPE's
shortest-first Reeds–Shepp takeover (``hope_policy.takeover``) replaces the policy's actions with checked chunks.

## Action space
``Box(-1, 1, (2,), float32)``: δ = a_0 · 0.75 rad (positive = left), v = a_1 · 2.5 m/s (sign = gear); see
``hope_policy.spaces.action_to_arc``. Actions outside the box raise (the env never clips).

## Observation space
``Dict`` of ``lidar`` (120,) signed clearances d − b, ``target`` (5,) HOPE's target representation,
``action_mask`` (42,) when the mask is on, and the added ``vertices`` or ``bev`` input; see
``hope_policy.spaces``. Raw values: normalisation belongs to the agent.

## Rewards
HOPE's shaping (time cost, distance, box union) on continuing steps; +5 success, −5 collision or boundary,
−0.1 when the step budget runs out (``hope_policy.reward``).

## Starting state
A scene uniformly from ``scenes``, a start from the start sampler (default: the full-range uniform sampler of
``np_sim.starts``; the trainer may plug in ``np_sim.curriculum.CurriculumStartSampler``).
``reset(options={"scene_index": k, "start": [x, y, θ]})`` fixes both.

## Episode end
Terminated on collision or boundary failure, or on success (within 0.1 m and 10°, or a feasible Hermite
connection). Truncated after 200 actions.

## Info
``success``, ``collision`` (any hard failure), ``out_of_bounds`` (the failure left the boundary),
``rs_takeover`` (this step executed a takeover chunk), ``rs_found`` (a takeover path was accepted after this step),
``executed_action`` (the normalised action executed: the policy's or the chunk's), ``arc`` (its (κ, l)),
``hermite_index``, ``scene_index``, ``pose``, ``n_steps``; at episode end ``plan``: the episode as an
``np_sim.plan.Plan`` (executed arcs including takeover chunks, the Hermite segment, success and reason).

## Version history
* v0: first release.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from hope_policy import step as K
from hope_policy.action_mask import MASK_SECTOR, sector_maxima, swept_distances
from hope_policy.config import HopeEnvConfig
from hope_policy.reward import box_iou, reward_parameters
from hope_policy.spaces import N_ANCHORS, TARGET_SIZE, action_space, action_to_arc, observation_space
from hope_policy.takeover import MAX_CHUNKS
from np_sim.bev import render_bev_batch
from np_sim.config import EnvConfig
from np_sim.env_core import BatchCore, checked_actions, step_outcome
from np_sim.errors import ConfigError
from np_sim.frames import from_target_frame
from np_sim.kernels import step as NK
from np_sim.observation import static_slots
from np_sim.plan import HermiteSegment, Plan
from np_sim.scene import Scene
from np_sim.starts import StartSampler

__all__ = ["HopeParkingEnv", "HopeVectorEnv", "episode_plan"]


def kernel_config(config: HopeEnvConfig) -> np.ndarray:
    """The scalar settings of ``config`` as the float array ``P`` the step kernel reads."""
    P = np.zeros(K.P_SIZE)
    cn = config.connector
    P[K.P_KAPPA_MAX], P[K.P_MAX_LEN] = config.kappa_max, config.max_length_m
    P[K.P_SAMPLES], P[K.P_MAX_STEPS] = config.samples_per_arc, config.max_steps
    P[K.P_POS_TOL], P[K.P_HEAD_TOL] = config.position_tolerance_m, np.radians(config.heading_tolerance_deg)
    P[K.P_CONN_KAPPA_MAX] = cn.kappa_max
    P[K.P_SEL_DK], P[K.P_SEL_LEN], P[K.P_SEL_CONST] = (cn.selection_kappa_weight, cn.selection_length_weight,
                                                       cn.selection_constant)
    P[K.P_FOOTPRINT] = config.collision == "footprint"
    P[K.P_ENSEMBLE], P[K.P_GATE] = cn.mode == "ensemble", cn.heading_gate
    P[K.P_LIDAR_RANGE] = config.observation.lidar_range_m
    P[K.P_RS_ON], P[K.P_RS_DIST] = config.rs_takeover, config.rs_max_dist_m
    P[K.P_RS_SPACING], P[K.P_RS_RATIO] = config.rs_spacing_m, config.rs_length_ratio
    P[K.P_MASK_ON], P[K.P_MASK_RATE] = config.action_mask, config.mask_upsample
    P[K.P_MASK_WIDTH] = config.mask_filter_width
    return P


def _benchmark_config(config: HopeEnvConfig) -> EnvConfig:
    """The benchmark env's config for the parts it shares with the HOPE env: vehicle, connector, convention,
    LiDAR geometry (its own observation streams are off: the HOPE env writes its own)."""
    ob = dataclasses.replace(config.observation, use_obstacles=False, use_boundary=False, use_lidar=False)
    return EnvConfig(vehicle=config.vehicle, observation=ob, connector=config.connector, collision=config.collision)


def episode_plan(start, arcs, hermite_points=None, hermite_forward: bool = True, hermite_length: float = 0.0,
                 hermite_delta_kappa: float = 0.0, success: bool = False, reason: str = "") -> Plan:
    """An episode as an ``np_sim.plan.Plan``: the executed (κ, l) arcs (policy arcs and takeover chunks in order)
    and, when the Hermite terminator finished it, its world-frame samples (N, 2) and direction."""
    hermite = None
    if hermite_points is not None:
        hermite = HermiteSegment(np.asarray(hermite_points, float), bool(hermite_forward), float(hermite_length),
                                 float(hermite_delta_kappa))
    return Plan(start=np.asarray(start, float).copy(), arcs=np.asarray(arcs, float).reshape(-1, 2).copy(),
                hermite=hermite, success=bool(success), reason=reason)


class HopeCore:
    """State of ``num_envs`` adapted-HOPE episodes over a list of scenes, stepped by one compiled call. Scenes,
    starts, start checks, LiDAR geometry and Hermite scratch come from the benchmark env's ``BatchCore``."""

    def __init__(self, scenes: Scene | Sequence[Scene], num_envs: int, config: HopeEnvConfig,
                 start_sampler: StartSampler | None):
        if not isinstance(config, HopeEnvConfig):
            raise ConfigError(f"HOPE environment: expected a HopeEnvConfig, got {type(config).__name__}")
        self.config = config
        self.base = BatchCore(scenes, num_envs, _benchmark_config(config), start_sampler)
        self.scenes, self.num_envs, self.geo = self.base.scenes, self.base.num_envs, self.base.geo
        self.targets = self.base.arrays.targets
        self.space = observation_space(config)
        self.P, self.W = kernel_config(config), reward_parameters(config.reward)
        dist_star = swept_distances(config)
        self.mask_tables = (dist_star, sector_maxima(dist_star, MASK_SECTOR))
        n, n_beams = self.num_envs, config.observation.n_beams
        self.S = np.zeros((n, K.S_SIZE))
        self.R = np.zeros((n, K.R_SIZE))
        self.queue = np.zeros((n, MAX_CHUNKS, 2))
        self.lidar = np.zeros((n, n_beams), np.float32)
        self.target = np.zeros((n, TARGET_SIZE), np.float32)
        self.mask = np.ones((n, N_ANCHORS), np.float32)
        self.starts = np.zeros((n, 3))
        self.arc_log = np.zeros((n, config.max_steps, 2))
        self.pose_log = np.zeros((n, config.max_steps + 1, 3))
        self.vertices = None
        if config.added_input == "vertices":
            ob = dataclasses.replace(config.observation, use_obstacles=True, use_boundary=True)
            self.vertices = np.stack([static_slots(s, ob) for s in self.scenes]).astype(np.float32)

    def reset_envs(self, env_ids: np.ndarray, rng: np.random.Generator, scene_index=None, start=None) -> None:
        """New episodes in ``env_ids`` (scene and start as ``np_sim.env_core.BatchCore.reset_envs``)."""
        env_ids = np.asarray(env_ids, np.int64)
        self.base.reset_envs(env_ids, rng, scene_index, start)
        poses = self.base.S[env_ids, NK.S_X:NK.S_TH + 1]
        scenes = self.base.S[env_ids, NK.S_SCENE].astype(np.int64)
        targets = self.targets[scenes]
        self.S[env_ids] = 0.0
        self.S[env_ids, K.S_X:K.S_TH + 1] = poses
        self.S[env_ids, K.S_SCENE] = scenes
        self.S[env_ids, K.S_START_DIST] = np.hypot(*(poses[:, :2] - targets[:, :2]).T)
        local = self.base.local
        self.S[env_ids, K.S_BEST_IOU] = [box_iou(*p, t, local) for p, t in zip(poses, targets)]
        self.starts[env_ids] = poses
        self.pose_log[env_ids, 0] = poses
        K.observe_batch(self.geo, self.targets, self.S, self.P, env_ids, self.base.b_ranges, self.base.off_c,
                        self.base.off_s, self.mask_tables, self.lidar, self.target, self.mask)

    def step(self, actions: np.ndarray) -> None:
        """Advance every env by its normalised action row; fills the observation arrays and ``R``."""
        a = checked_actions(actions, self.num_envs)
        b = self.base
        arcs = np.ascontiguousarray(action_to_arc(a, self.config))
        K.step_batch(self.geo, self.targets, self.S, self.P, self.W, arcs, b.local, self.queue, b.b_ranges, b.off_c,
                     b.off_s, self.mask_tables, b.offsets, b.headings, b.scales0, b.scales1, b.basis, b.dbasis,
                     b.h_pts, b.h_kbar_max, b.h_dk, b.h_len, b.h_cost, self.lidar, self.target, self.mask, self.R)
        rows, steps = np.arange(self.num_envs), self.S[:, K.S_STEPS].astype(np.int64)
        self.arc_log[rows, steps - 1] = self.R[:, K.R_KAPPA:K.R_LENGTH + 1]
        self.pose_log[rows, steps] = self.S[:, K.S_X:K.S_TH + 1]

    def observation(self, rows=slice(None)) -> dict[str, np.ndarray]:
        """Copies of the observation arrays (rows ``rows``) as the observation-space dict."""
        obs = {"lidar": self.lidar[rows].copy(), "target": self.target[rows].copy()}
        if self.config.action_mask:
            obs["action_mask"] = self.mask[rows].copy()
        if self.vertices is not None:
            obs["vertices"] = self.vertices[self.S[rows, K.S_SCENE].astype(np.int64)].copy()
        if self.config.added_input == "bev":
            obs["bev"] = self.bev(rows)
        return obs

    def bev(self, rows=slice(None)) -> np.ndarray:
        """BEV rasters (``np_sim.bev``) of the envs ``rows`` at their current poses, with the trajectory tail: up to
        ``bev.tail_poses − 1`` earlier step-end poses of the episode, oldest first (none when ``bev_tail`` is off)."""
        ids = np.arange(self.num_envs)[rows]
        one = np.ndim(ids) == 0
        ids = np.atleast_1d(ids)
        steps = self.S[ids, K.S_STEPS].astype(np.int64)
        span = self.config.bev.tail_poses - 1 if self.config.bev_tail else 0
        n_tail = np.minimum(steps, span)
        window = np.arange(max(span, 1))[None, :] + (steps - n_tail)[:, None]
        tails = self.pose_log[ids[:, None], np.minimum(window, self.config.max_steps)]
        images = render_bev_batch(self.base.arrays, self.S[ids, K.S_SCENE].astype(np.int64),
                                  self.S[ids, K.S_X:K.S_TH + 1], tails, n_tail, self.config.bev, self.config.vehicle)
        return images[0] if one else images

    def executed_actions(self) -> np.ndarray:
        """(N, 2) normalised actions of the arcs executed by the last step (the policy's or a takeover chunk's)."""
        kappa, length = self.R[:, K.R_KAPPA], self.R[:, K.R_LENGTH]
        steer_curvature = -np.sign(length) * kappa
        steer = np.arctan(steer_curvature * self.config.vehicle.wheelbase_m) / self.config.max_steer_rad
        return np.stack([steer, length / self.config.max_length_m], 1)

    def step_info(self) -> dict[str, np.ndarray]:
        """Per-env info arrays of the last step."""
        R, S = self.R, self.S
        return {
            "success": R[:, K.R_SUCCESS] > 0, "collision": R[:, K.R_COLLISION] > 0,
            "out_of_bounds": R[:, K.R_OUT_OF_BOUNDS] > 0, "rs_takeover": R[:, K.R_RS_STEP] > 0,
            "rs_found": R[:, K.R_RS_FOUND] > 0, "executed_action": self.executed_actions(),
            "arc": R[:, K.R_KAPPA:K.R_LENGTH + 1].copy(), "hermite_index": R[:, K.R_HERMITE].astype(np.int64),
            "scene_index": S[:, K.S_SCENE].astype(np.int64), "pose": S[:, K.S_X:K.S_TH + 1].copy(),
            "n_steps": S[:, K.S_STEPS].astype(np.int64),
        }

    def plan(self, i: int) -> Plan:
        """Env i's episode so far as an ``np_sim.plan.Plan`` (call after its last step, before a reset)."""
        R, n = self.R[i], int(self.S[i, K.S_STEPS])
        h = int(R[K.R_HERMITE])
        points = None
        if h >= 0:
            target = self.targets[int(self.S[i, K.S_SCENE])]
            points = from_target_frame(self.base.h_pts[i, h].T, target)
        reason = ("" if R[K.R_SUCCESS] else "boundary" if R[K.R_OUT_OF_BOUNDS] else "collision" if R[K.R_COLLISION]
                  else "timeout" if R[K.R_TRUNCATED] else "running")
        return episode_plan(self.starts[i], self.arc_log[i, :n], points, R[K.R_H_FORWARD] > 0, R[K.R_H_LEN],
                            R[K.R_H_DK], bool(R[K.R_SUCCESS]), reason)


class HopeParkingEnv(gym.Env):
    """One adapted-HOPE episode at a time (the batched core with one env); see the module docstring."""

    metadata = {"render_modes": []}

    def __init__(self, scenes: Scene | Sequence[Scene], config: HopeEnvConfig | None = None,
                 start_sampler: StartSampler | None = None):
        self.config = HopeEnvConfig() if config is None else config
        self.core = HopeCore(scenes, 1, self.config, start_sampler)
        self.action_space = action_space()
        self.observation_space = self.core.space

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        self.core.reset_envs(np.array([0]), self.np_random, options.get("scene_index"), options.get("start"))
        return self.core.observation(0), {"scene_index": int(self.core.S[0, K.S_SCENE])}

    def step(self, action):
        core = self.core
        core.step(np.asarray(action, np.float64).reshape(1, 2))
        R = core.R[0]
        info = {k: (v[0].copy() if isinstance(v[0], np.ndarray) else v[0].item()) for k, v in core.step_info().items()}
        terminated, truncated = bool(R[K.R_TERMINATED]), bool(R[K.R_TRUNCATED])
        if terminated or truncated:
            info["plan"] = core.plan(0)
        return core.observation(0), float(R[K.R_REWARD]), terminated, truncated, info


class HopeVectorEnv(VectorEnv):
    """N adapted-HOPE episodes over a list of scenes, stepped in one compiled call (same-step autoreset).

    When an episode ends, ``step`` returns the first observation of the next episode in its row and puts the last
    observation in ``info["final_obs"]`` (rows valid where ``info["_final_obs"]``) and the ended episode's
    ``np_sim.plan.Plan`` in ``info["plan"]`` (an object array, ``None`` in other rows); the other info entries are
    the step's arrays at those rows.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, scenes: Sequence[Scene], num_envs: int, config: HopeEnvConfig | None = None,
                 seed: int | None = 0, start_sampler: StartSampler | None = None):
        self.config = HopeEnvConfig() if config is None else config
        self.core = HopeCore(scenes, num_envs, self.config, start_sampler)
        self.num_envs = self.core.num_envs
        self.single_action_space = action_space()
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.single_observation_space = self.core.space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._rng = np.random.default_rng(seed)
        self._all = np.arange(self.num_envs)

    def set_start_sampler(self, sampler: StartSampler) -> None:
        """Replace the start sampler (e.g. when the curriculum fraction changes)."""
        self.core.base.sampler = sampler

    def state_dict(self) -> dict[str, Any]:
        """Episode state of every env (poses, counters, takeover queues, episode logs, current observations) and
        the start generator's state, for exact resumption of training."""
        core = self.core
        names = ("S", "R", "queue", "starts", "arc_log", "pose_log", "lidar", "target", "mask")
        return {**{name: getattr(core, name).copy() for name in names}, "rng": self._rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Inverse of ``state_dict``."""
        for name, value in state.items():
            if name != "rng":
                getattr(self.core, name)[:] = value
        self._rng.bit_generator.state = state["rng"]

    def pending_takeover(self) -> tuple[np.ndarray, np.ndarray]:
        """(queued, actions): which envs will execute a takeover chunk at the next step, whatever the action, and
        that chunk as a normalised action (rows where ``queued``; zeros elsewhere)."""
        S, cfg = self.core.S, self.config
        queued = S[:, K.S_RS_POS] < S[:, K.S_RS_LEN]
        chunk = self.core.queue[self._all, np.minimum(S[:, K.S_RS_POS].astype(np.int64), MAX_CHUNKS - 1)]
        steer = np.arctan(-np.sign(chunk[:, 1]) * chunk[:, 0] * cfg.vehicle.wheelbase_m) / cfg.max_steer_rad
        actions = np.where(queued[:, None], np.stack([steer, chunk[:, 1] / cfg.max_length_m], 1), 0.0)
        return queued, actions

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        options = options or {}
        self.core.reset_envs(self._all, self._rng, options.get("scene_index"), options.get("start"))
        return self.core.observation(), {"scene_index": self.core.S[:, K.S_SCENE].astype(np.int64)}

    def step(self, actions):
        core = self.core
        core.step(actions)
        reward, terminated, truncated = step_outcome(core.R)
        info = core.step_info()
        done = terminated | truncated
        if done.any():
            ids = np.flatnonzero(done)
            final = core.observation()
            info["final_obs"] = {k: np.where(done.reshape((-1,) + (1,) * (v.ndim - 1)), v, 0) for k, v in final.items()}
            info["_final_obs"] = done
            plans = np.full(self.num_envs, None, dtype=object)
            for i in ids:
                plans[i] = core.plan(int(i))
            info["plan"], info["_plan"] = plans, done
            core.reset_envs(ids, self._rng)
        return core.observation(), reward, terminated, truncated, info
