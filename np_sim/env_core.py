"""The batched environment state and its compiled step, shared by ``ParkingEnv`` (one env) and
``ParkingVectorEnv`` (N envs): the dynamics, checks, reward and termination exist once, over ``(num_envs, ...)``
arrays (STYLE §5)."""

from __future__ import annotations

import functools
import math
import weakref
from collections.abc import Sequence

import numpy as np

from np_sim.bev import render_bev_batch
from np_sim.config import EnvConfig, ObservationConfig
from np_sim.errors import ConfigError, StartInCollisionError
from np_sim.kernels import step as K
from np_sim.kernels.collision import pose_valid
from np_sim.kernels.geometry import beam_offsets
from np_sim.kernels.hermite import hermite_basis
from np_sim.lidar import footprint_ranges
from np_sim.nearest import exceeds_slots, nearest_objects
from np_sim.observation import bev_encoder, observation_sections, observation_size, static_slots
from np_sim.scene import Scene
from np_sim.scene_arrays import pack_scenes, packed_scene
from np_sim.starts import StartSampler, UniformStartSampler


def kernel_parameters(config: EnvConfig) -> np.ndarray:
    """The scalar settings of ``config`` as the float array ``P`` the step kernel reads."""
    P = np.zeros(K.P_SIZE)
    ep, rw, cn, ob = config.episode, config.reward, config.connector, config.observation
    P[K.P_KAPPA_MAX] = config.vehicle.kappa_max
    P[K.P_LENGTH_MAX] = ep.max_length_m
    P[K.P_POS_TOL] = ep.position_tolerance_m
    P[K.P_HEAD_TOL] = math.radians(ep.heading_tolerance_deg)
    P[K.P_CONN_KAPPA_MAX] = cn.kappa_max
    P[K.P_SEL_DK] = cn.selection_kappa_weight
    P[K.P_SEL_LEN] = cn.selection_length_weight
    P[K.P_SEL_CONST] = cn.selection_constant
    P[K.P_R_DK] = rw.kappa_change_weight
    P[K.P_R_LEN] = rw.length_weight
    P[K.P_R_STEP] = rw.step_penalty
    P[K.P_R_REV] = rw.reversal_penalty
    P[K.P_R_SHORT_W] = rw.short_arc_weight
    P[K.P_R_SHORT_M] = rw.short_arc_m
    P[K.P_R_BONUS] = rw.success_bonus
    P[K.P_R_SUCC_REV] = rw.success_reversal_weight
    P[K.P_R_SUCC_DK] = rw.success_kappa_weight
    P[K.P_R_H_W] = rw.hermite_weight
    P[K.P_R_H_DK] = rw.hermite_kappa_weight
    P[K.P_R_H_LEN] = rw.hermite_length_weight
    P[K.P_R_H_CONST] = rw.hermite_constant
    P[K.P_R_H_FLOOR] = rw.hermite_floor
    P[K.P_R_FAIL] = rw.failure_penalty
    P[K.P_LIDAR_RANGE] = ob.lidar_range_m
    P[K.P_SAMPLES] = ep.samples_per_arc
    P[K.P_MAX_ARCS] = ep.max_arcs
    P[K.P_N_BEAMS] = ob.n_beams
    P[K.P_FOOTPRINT] = 1.0 if config.collision == "footprint" else 0.0
    P[K.P_USE_LIDAR] = 1.0 if ob.use_lidar else 0.0
    P[K.P_ENSEMBLE] = 1.0 if cn.mode == "ensemble" else 0.0
    P[K.P_GATE] = 1.0 if cn.heading_gate else 0.0
    return P


def checked_actions(actions, num_envs: int) -> np.ndarray:
    """``actions`` as a float64 (num_envs, 2) array in [-1, 1]^2; ValueError naming the first bad row otherwise
    (the envs never clip)."""
    a = np.asarray(actions, dtype=np.float64)
    if a.shape != (num_envs, 2):
        raise ValueError(f"step: expected actions of shape ({num_envs}, 2), got {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(np.abs(a) > 1.0):
        bad = np.argwhere(~np.isfinite(a) | (np.abs(a) > 1.0))[0]
        raise action_space_error(int(bad[0]), a[bad[0]])
    return a


def action_space_error(row: int, action: np.ndarray) -> ValueError:
    """The error of a step given ``action`` (row ``row``) outside the action space [-1, 1]^2 or not finite."""
    return ValueError(f"step: action[{row}] = {np.asarray(action).tolist()} lies outside the action space "
                      "[-1, 1]^2 (the env never clips; clip or squash in the policy)")


def checked_rows(rows, num_envs: int) -> np.ndarray:
    """``rows`` as a 1-D int64 array of distinct env indices in [0, ``num_envs``); ValueError otherwise (one env
    stepped twice in a parallel loop would race)."""
    r = np.asarray(rows)
    if r.ndim != 1 or (len(r) and not np.issubdtype(r.dtype, np.integer)):
        raise ValueError(f"step: expected rows as a 1-D array of env indices, got shape {r.shape} and dtype {r.dtype}")
    r = np.ascontiguousarray(r, np.int64)
    if len(r) and (r.min() < 0 or r.max() >= num_envs):
        raise ValueError(f"step: rows must lie in [0, {num_envs}), got {int(r.min())}..{int(r.max())}")
    if len(np.unique(r)) != len(r):
        raise ValueError("step: rows must be distinct (each env is stepped at most once per call)")
    return r


def step_outcome(R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(reward as float32, terminated, truncated) of a batched step's result rows ``R``, whose first columns are
    ``K.R_REWARD``, ``K.R_TERMINATED`` and ``K.R_TRUNCATED`` (the benchmark env's and the adapted HOPE's kernels)."""
    return R[:, K.R_REWARD].astype(np.float32), R[:, K.R_TERMINATED] > 0, R[:, K.R_TRUNCATED] > 0


@functools.lru_cache(maxsize=64)
def config_arrays(config: EnvConfig) -> tuple:
    """What ``BatchCore`` reads from ``config`` alone, built once per config and shared by its cores (never
    written): obstacle columns, observation size, ``P``, footprint, LiDAR body ranges and beam offsets, connector
    candidates and Hermite basis. A planner builds a core per perceived scene, so this is per-call work saved."""
    ob, cn = config.observation, config.connector
    return (observation_sections(ob).get("obstacles"), observation_size(ob), kernel_parameters(config),
            config.vehicle.footprint_local(), footprint_ranges(config.vehicle, ob.n_beams), *beam_offsets(ob.n_beams),
            *cn.arrays(), *hermite_basis(cn.n_samples))


_STATIC_ROWS: "weakref.WeakKeyDictionary[Scene, dict]" = weakref.WeakKeyDictionary()


def scene_static_row(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """`np_sim.observation.static_slots` of ``scene``, cached per scene and observation config (callers copy it)."""
    rows = _STATIC_ROWS.setdefault(scene, {})
    if config not in rows:
        rows[config] = static_slots(scene, config)
    return rows[config]


class BatchCore:
    """State of ``num_envs`` episodes over a list of scenes, stepped by one compiled call."""

    def __init__(self, scenes: Sequence[Scene], num_envs: int, config: EnvConfig, start_sampler: StartSampler | None,
                 nearest: bool = False):
        """``nearest``: a scene with more obstacles than the observation's slots is observed by the site's rule
        (`np_sim.nearest`: the nearest ones, re-selected after every arc; every check stays on the whole scene)
        instead of raising CapacityError."""
        if isinstance(scenes, Scene):
            scenes = [scenes]
        self.scenes = list(scenes)
        if not self.scenes:
            raise ConfigError("environment: expected at least one scene, got none")
        if int(num_envs) < 1:
            raise ConfigError(f"environment: num_envs must be >= 1, got {num_envs}")
        self.num_envs = int(num_envs)
        self.config = config
        self.arrays = packed_scene(self.scenes[0]) if len(self.scenes) == 1 else pack_scenes(self.scenes)
        self.geo = self.arrays.geometry
        selectors = [nearest_objects(s, config.observation) if nearest and exceeds_slots(s, config.observation)
                     else None for s in self.scenes]
        # raises CapacityError naming the scene and the limit (never truncates)
        self.static_obs = np.stack([scene_static_row(s, config.observation) if sel is None else sel.static_row()
                                    for s, sel in zip(self.scenes, selectors)])
        self.selectors = [(k, sel) for k, sel in enumerate(selectors) if sel is not None]
        (self.obstacle_columns, self.obs_size, self.P, self.local, self.b_ranges, self.off_c, self.off_s, self.offsets,
         self.headings, self.scales0, self.scales1, self.basis, self.dbasis) = config_arrays(config)
        self._sampler = start_sampler
        cn = config.connector
        n, c = self.num_envs, cn.n_candidates
        self.h_pts = np.empty((n, c, 2, cn.n_samples))
        self.h_kbar_max = np.empty((n, c))
        self.h_dk = np.empty((n, c))
        self.h_len = np.empty((n, c))
        self.h_cost = np.empty((n, c))
        self.S = np.zeros((n, K.S_SIZE))
        self.R = np.zeros((n, K.R_SIZE))
        self.obs = np.zeros((n, self.obs_size), np.float32)
        self._corners = np.empty((4, 2))
        self.bev = bev_encoder(config.observation) if config.observation.use_bev else None
        self._all = np.arange(n)

    @property
    def sampler(self) -> StartSampler:
        """The start sampler: the one given, else the full-range sampler over the scenes, built when first asked
        (a planner's cores start from given poses and never need one)."""
        if self._sampler is None:
            self._sampler = UniformStartSampler(self.scenes, self.config.vehicle, arrays=self.arrays)
        return self._sampler

    @sampler.setter
    def sampler(self, sampler: StartSampler) -> None:
        self._sampler = sampler

    # ------------------------------------------------------------------------------------------------------------
    def reset_envs(self, env_ids: np.ndarray, rng: np.random.Generator, scene_index=None, start=None) -> None:
        """Start new episodes in ``env_ids``: scenes uniformly at random (or ``scene_index``: one index or one per
        env), starts from the sampler (or ``start``: one pose or one per env, which must be valid under the
        collision convention)."""
        env_ids = np.asarray(env_ids, np.int64)
        n = len(env_ids)
        if scene_index is None:
            scenes = rng.integers(len(self.scenes), size=n)
        else:
            scenes = np.broadcast_to(np.asarray(scene_index, np.int64), (n,)).copy()
            bad = scenes[(scenes < 0) | (scenes >= len(self.scenes))]
            if len(bad):
                raise ConfigError(f"reset: scene_index {int(bad[0])} out of range [0, {len(self.scenes)})")
        if start is None:
            poses = np.asarray(self.sampler(rng, scenes), float).reshape(n, 3)
        else:
            poses = np.broadcast_to(np.asarray(start, float).reshape(-1, 3), (n, 3)).copy()
            for pose, k in zip(poses, scenes):
                if not pose_valid(self.geo, k, pose[0], pose[1], pose[2], self.config.collision == "footprint",
                                  self.local, self._corners):
                    raise StartInCollisionError(
                        f"reset: start pose {pose.tolist()} is in collision in scene "
                        f"{self.scenes[k].name or k!r} under the {self.config.collision} convention"
                    )
        self.S[env_ids] = 0.0
        self.S[env_ids, K.S_X:K.S_TH + 1] = poses
        self.S[env_ids, K.S_SCENE] = scenes
        K.observe_batch(self.geo, self.arrays.targets, self.static_obs, self.S, self.P, self.b_ranges, self.off_c,
                        self.off_s, env_ids, self.obs)
        self.observe_nearest(env_ids)
        self.observe_bev(env_ids)

    def step(self, actions: np.ndarray, rows=None) -> None:
        """Advance every env by its normalised action row, or with ``rows`` (distinct env indices) only those envs,
        env ``rows[r]`` by ``actions[r]``; fills their rows of ``obs`` and ``R``. The other envs are not stepped:
        their state, observation, results and Hermite scratch stay as they were (a finished rollout costs
        nothing)."""
        rows = self._all if rows is None else checked_rows(rows, self.num_envs)
        a = checked_actions(actions, len(rows))
        K.step_rows(self.geo, self.arrays.targets, self.static_obs, self.S, self.P, rows, np.ascontiguousarray(a),
                    self.local, self.b_ranges, self.off_c, self.off_s, self.offsets, self.headings, self.scales0,
                    self.scales1, self.basis, self.dbasis, self.h_pts, self.h_kbar_max, self.h_dk, self.h_len,
                    self.h_cost, self.obs, self.R)
        self.observe_nearest(rows)
        self.observe_bev(rows)

    def copy_env(self, source: int, rows) -> None:
        """Envs ``rows`` continue from env ``source``'s state: pose, episode counters, scene and observation
        (the Hermite scratch and ``R`` are per-step outputs and are not state). Branching several actions from one
        state is then one ``step`` over those rows."""
        rows = checked_rows(rows, self.num_envs)
        source = int(checked_rows([source], self.num_envs)[0])
        self.S[rows] = self.S[source]
        self.obs[rows] = self.obs[source]

    def observe_nearest(self, env_ids: np.ndarray) -> None:
        """Obstacle slots of the envs ``env_ids`` whose scene exceeds the slots: the nearest obstacles to their
        current poses (`np_sim.nearest`); other envs keep the scene's constant slots."""
        for k, selector in self.selectors:
            rows = np.asarray(env_ids)[self.S[env_ids, K.S_SCENE] == k]
            if len(rows):
                start, stop = self.obstacle_columns
                self.obs[rows, start:stop] = selector.slots(self.S[rows, K.S_X: K.S_TH + 1])

    def observe_bev(self, env_ids: np.ndarray) -> None:
        """With ``use_bev``: the BEV latent of the envs ``env_ids`` at their current poses (ego-aligned raster, no
        trajectory tail, frozen encoder; paper App. B) into their observation rows."""
        if self.bev is None or len(env_ids) == 0:
            return
        images = render_bev_batch(self.arrays, self.S[env_ids, K.S_SCENE].astype(np.int64),
                                  self.S[env_ids, K.S_X: K.S_TH + 1], config=self.bev.raster,
                                  vehicle=self.config.vehicle)
        start, stop = observation_sections(self.config.observation)["bev"]
        self.obs[env_ids, start:stop] = self.bev(images)

    def episode_metrics(self) -> dict[str, np.ndarray]:
        """Per env, the paper's eq:metrics of the episode so far including a Hermite segment of the last step:
        L = Σ|l_t| + L_H, reversals = Σ I[l_t l_{t−1} < 0] + I[l_T q_H < 0], Δκ = Σ|κ_t − κ_{t−1}| + Δκ_H."""
        S, R = self.S, self.R
        with_h = R[:, K.R_HERMITE] >= 0
        final_rev = with_h & (S[:, K.S_PREV_L] * R[:, K.R_H_FORWARD] < 0)
        return {
            "path_length": S[:, K.S_SUM_LEN] + np.where(with_h, R[:, K.R_H_LEN], 0.0),
            "reversals": (S[:, K.S_N_REV] + final_rev).astype(np.int64),
            "delta_kappa": S[:, K.S_SUM_DK] + np.where(with_h, R[:, K.R_H_DK], 0.0),
        }

    def step_info(self) -> dict[str, np.ndarray]:
        """Per-env info arrays of the last step."""
        R = self.R
        info = {
            "success": R[:, K.R_SUCCESS] > 0,
            "collision": R[:, K.R_COLLISION] > 0,
            "hermite_index": R[:, K.R_HERMITE].astype(np.int64),
            "hermite_length": R[:, K.R_H_LEN].copy(),
            "hermite_delta_kappa": R[:, K.R_H_DK].copy(),
            "scene_index": self.S[:, K.S_SCENE].astype(np.int64),
            "pose": self.S[:, K.S_X:K.S_TH + 1].copy(),
            "n_arcs": self.S[:, K.S_N_ARCS].astype(np.int64),
        }
        info.update(self.episode_metrics())
        return info
