"""Train the NeuralParker arc policy with PPO (paper §III-E, Algorithm 1, App. A Table V).

``python -m np_policy.train --benchmark factorial --seed 0 [--config FILE] [--vehicle sedan|van|FILE] [--epochs N]
[--out DIR] [--resume] [--device cpu|cuda|auto] [--shared-geometry]``

One run reads top to bottom: build the batched env on the training scenes with the geodesic start curriculum and the
in-loop Hermite ensemble, then per epoch collect 16,384 transitions at a time from the 128 training envs until at
least 60,000 steps are in, after each collect run 10 shuffled passes of minibatches of 8,192 (Tianshou's on-policy
trainer semantics, spec §6), then score 32 full-range training-distribution episodes with the deterministic policy
for checkpoint selection (never a frozen evaluation episode). Every epoch appends a line to ``metrics.jsonl``
(statistics, and its wall-clock split into ``collect_s``, ``update_s`` and ``selection_s``); ``curves.png`` is
redrawn at most once a minute and at each snapshot and the end; TensorBoard event files beside it hold the same
scalars (``--no-tensorboard`` leaves them out);
``best.pt`` holds the selected policy; ``snapshot.pt`` (every ``ppo.snapshot_every_epochs``, 20 by default and 10 in
the sweep's recipe, and at the last epoch of a run stopped early with ``--epochs``) holds everything needed to
resume exactly — on CPU a resumed run gives the same curve as an uninterrupted one. A run whose last metrics row is
epoch ``ppo.epochs`` is finished: its snapshot (optimiser and env state, about three times the size of ``best.pt``)
is removed, and ``--resume`` on it says it is finished. SIGTERM or SIGUSR1 (``kill -USR1 PID``) stops a run after
the epoch in progress with a snapshot there and exit status 128 + the signal's number (`np_sim.stop_request`); a
second one ends it at once. ``--vehicle`` trains for another vehicle (`np_sim.vehicle`): the env's footprint checks,
LiDAR footprint ranges, start sampling and action bound κ_max follow it, and the connector's curvature bound is its
κ_max unless the ``--config`` file sets ``env.connector.kappa_max``; the checkpoint stores it, and planners for
another vehicle refuse the checkpoint. ``--device cuda`` trains the network on a GPU (the envs stay on the CPU; what
changes is in `np_policy.device`); each metrics row names the device it trained on. ``--shared-geometry`` runs the
network's geometry branch once per distinct scene in each update chunk
(`np_policy.network.SceneEncoder.geometry_token`): the same recipe and values, another float summation order in the
gradient, about 1.5× faster updates on Factorial; each metrics row says whether it was on.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from np_policy.checkpoint import (CheckpointError, check_config, config_differences, load_checkpoint,
                                  load_weights, save_checkpoint, write_atomic)
from np_policy.device import device_label, restore_sampling_rng, sampling_rng_state, training_device
from np_policy.config import (BENCHMARKS, PPOConfig, TrainConfig, benchmark_defaults,  # noqa: F401 (re-exported)
                              checkpoint_config, is_scene_path)
from np_policy.network import ActorCritic, clip_action
from np_policy.ppo import RunningMeanStd, compute_targets, make_optimizer, ppo_update, set_learning_rate
from np_policy.threads import thread_counts, use_threads
from np_sim.curriculum import CurriculumSchedule, CurriculumStartSampler
from np_sim.env import ParkingVectorEnv
from np_sim.clips import cached_training_pool, difficult_clips
from np_sim.cli import vehicle_spec
from np_sim.errors import ConfigError, NPSimError
from np_sim.provenance import PROVENANCE_FILE, record_start
from np_sim.scene import Scene
from np_sim.stop_request import StopRequest, TrainingStopped
from np_sim.starts import UniformStartSampler, fixed_start_sampler

SITE_POOL_FILE = "site_pool.pkl"
"""The site run's reset pool, kept in the run folder so --resume does not draw it again (not committed)."""
RUN_FILES = ("metrics.jsonl", "snapshot.pt", "best.pt")
"""A folder holding any of these holds a training run: a new run there needs ``overwrite``."""
EVENT_FILES = "events.out.tfevents.*"
"""The run's TensorBoard event files (a glob pattern)."""
REPLACED_FILES = (*RUN_FILES, "curves.png", "config.json", PROVENANCE_FILE, EVENT_FILES)
"""What ``overwrite`` removes before a new run starts in an existing run folder: names or glob patterns (the site
pool is a cache keyed by its settings and stays)."""
CURVES_EVERY_S = 60.0
"""Seconds between redraws of ``curves.png`` at the least; it is also drawn at every snapshot and at the run's end.
Drawing it every epoch cost about 15% of a short run's time; TensorBoard's event files carry every epoch."""


def merge_config(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    """``base`` updated by ``override``, nested mappings merged key by key (neither argument is modified)."""
    out = dict(base)
    for key, value in override.items():
        out[key] = merge_config(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) \
            else value
    return out


class PairedStartSampler:
    """Start k for scene k (the site's App. C resets, ``fixed_start_sampler``) behind the curriculum interface,
    with the fraction fixed at 1."""

    fraction = 1.0

    def __init__(self, starts: np.ndarray):
        self._sample = fixed_start_sampler(starts)

    def __call__(self, rng: np.random.Generator, scene_indices) -> np.ndarray:
        return self._sample(rng, scene_indices)

    def set_progress(self, progress: float, schedule: CurriculumSchedule) -> None:
        """No curriculum: every reset is full range."""

    def set_fraction(self, fraction: float) -> None:
        if fraction != 1.0:
            raise CheckpointError(f"PairedStartSampler: a site run has curriculum fraction 1, snapshot has {fraction}")


def training_scenes(benchmark: str, holdout_every: int = 0):
    """The training split of ``benchmark`` (without the scenes `np_sim.benchmarks.frozen.held_out` by
    ``holdout_every``), the hand-made example scenes, or the scenes of a JSON file or folder."""
    if is_scene_path(benchmark):
        path = Path(benchmark)
        files = sorted(path.glob("*.json")) if path.is_dir() else [path]
        if not files:
            raise ConfigError(f"TrainConfig.benchmark: folder {benchmark!r} holds no *.json scene files")
        return [Scene.load(f) for f in files]
    if benchmark == "examples":
        from np_sim.examples import example_scenes

        return [s for s in example_scenes() if s.tags.get("expect") != "no_path"]
    from np_sim.benchmarks import load_benchmark
    from np_sim.benchmarks.frozen import held_out

    scenes = load_benchmark(benchmark, "train")
    left_out = set(held_out(len(scenes), holdout_every).tolist())
    return [scene for k, scene in enumerate(scenes) if k not in left_out]


def curriculum_scenes(scenes: list[Scene], region: str) -> list[Scene]:
    """The scenes the curriculum pool is drawn from (`TrainConfig.curriculum_region`): the training scenes
    themselves, or ('lot') the same scenes with the whole drivable lot (the boundary polygon) as start region."""
    if region == "start_region":
        return list(scenes)
    return [dataclasses.replace(scene, start_region=scene.boundary) for scene in scenes]


def recorded_clips(skip: int) -> list:
    """The difficult training clips (`np_sim.clips.clip_difficulty`) after the first ``skip``: where recorded
    resets come from (``TrainConfig.site_recorded_share``)."""
    difficult = difficult_clips("train")
    if skip >= len(difficult):
        raise ConfigError(f"TrainConfig.site_recorded_skip: {skip} leaves none of the {len(difficult)} difficult "
                          "training clips for recorded resets")
    return difficult[skip:]


class Trainer:
    """State of one training run: model, optimiser, envs, statistics, counters."""

    def __init__(self, config: TrainConfig, out: Path, device: torch.device = torch.device("cpu"),
                 shared_geometry: bool = False):
        self.config = config
        self.out = Path(out)
        self.device = device
        self.shared_geometry = shared_geometry
        ppo = config.ppo
        use_threads(config.torch_threads)
        torch.manual_seed(config.seed)
        env = config.training_env()
        if config.benchmark == "site":
            recorded = recorded_clips(config.site_recorded_skip) if config.site_recorded_share else []
            self.scenes, starts = cached_training_pool(self.out / SITE_POOL_FILE, config.site_pool, config.seed,
                                                       observation=config.env.observation,
                                                       vehicle=env.vehicle, progress=True,
                                                       recorded_share=config.site_recorded_share,
                                                       recorded_clips=recorded)
            self.sampler = PairedStartSampler(starts)
            select_sampler = fixed_start_sampler(starts)
        else:
            self.scenes = training_scenes(config.benchmark, config.holdout_every)
            self.sampler = CurriculumStartSampler(curriculum_scenes(self.scenes, config.curriculum_region),
                                                  fraction=config.curriculum.start_fraction,
                                                  pool_size=config.curriculum_pool, seed=config.seed,
                                                  vehicle=env.vehicle)
            select_sampler = UniformStartSampler(self.scenes, env.vehicle)
        self.envs = ParkingVectorEnv(self.scenes, ppo.num_train_envs, env, seed=config.seed,
                                     start_sampler=self.sampler)
        self.select_envs = ParkingVectorEnv(self.scenes, ppo.num_test_envs, env, seed=config.seed + 1,
                                            start_sampler=select_sampler)
        self.model = ActorCritic(config.env.observation, config.network).to(device)  # initialised on the CPU
        self.optimizer = make_optimizer(self.model, ppo)
        self.return_rms = RunningMeanStd()
        self.shuffle = torch.Generator().manual_seed(config.seed)
        self.epoch = 0
        self.updates = 0
        self.env_steps = 0
        self.best_reward = -np.inf
        self.init_checkpoint: dict[str, Any] | None = None
        self.sampler.set_progress(0.0, config.curriculum)
        self.obs, _ = self.envs.reset()
        self.episode_return = np.zeros(ppo.num_train_envs)

    def _flat_tensor(self, a: np.ndarray) -> torch.Tensor:
        """``a`` (steps, envs, ...) as one tensor of (steps × envs, ...) samples."""
        return self._tensor(np.ascontiguousarray(a.reshape(-1, *a.shape[2:])))

    def _tensor(self, array: np.ndarray) -> torch.Tensor:
        """A numpy array of the envs as a tensor on the training device (the same memory on the CPU)."""
        return torch.from_numpy(array).to(self.device)

    # ------------------------------------------------------------------------------------------------ collect
    def collect(self) -> dict[str, Any]:
        """One collect of ``steps_per_collect`` transitions; returns the rollout arrays and episode stats."""
        ppo = self.config.ppo
        T, N = ppo.steps_per_env_per_collect, ppo.num_train_envs
        D = self.obs.shape[1]
        obs = np.empty((T, N, D), np.float32)
        actions = np.empty((T, N, 2), np.float32)
        log_probs = np.empty((T, N), np.float32)
        values = np.empty((T + 1, N), np.float32)
        rewards = np.empty((T, N), np.float32)
        terminated = np.empty((T, N), bool)
        truncated = np.empty((T, N), bool)
        final_values = np.zeros((T, N), np.float32)
        ended_returns, ended_success = [], []
        self.model.eval()
        with torch.no_grad():
            for t in range(T):
                obs[t] = self.obs
                a, lp, v = self.model.act(self._tensor(self.obs))
                actions[t], log_probs[t], values[t] = a.cpu().numpy(), lp.cpu().numpy(), v.cpu().numpy()
                self.obs, r, term, trunc, info = self.envs.step(clip_action(actions[t]))
                rewards[t], terminated[t], truncated[t] = r, term, trunc
                self.episode_return += r
                done = term | trunc
                if done.any():
                    final_values[t, done] = self.model.value(self._tensor(info["final_obs"][done])).cpu().numpy()
                    ended_returns.extend(self.episode_return[done].tolist())
                    ended_success.extend(info["success"][done].tolist())
                    self.episode_return[done] = 0.0
            values[T] = self.model.value(self._tensor(self.obs)).cpu().numpy()
        done = terminated | truncated
        next_values = np.where(done, final_values, values[1:])
        self.env_steps += T * N
        return {"obs": obs, "actions": actions, "log_probs": log_probs, "values": values[:T], "rewards": rewards,
                "terminated": terminated, "truncated": truncated, "next_values": next_values,
                "ended_returns": ended_returns, "ended_success": ended_success}

    def update(self, roll: dict[str, Any]) -> dict[str, float]:
        """PPO update on one collect (Tianshou semantics: GAE, reward normalisation, 10 passes)."""
        ppo = self.config.ppo
        set_learning_rate(self.optimizer, ppo.lr_at(self.updates))
        advantages, returns = compute_targets(roll["rewards"], roll["values"], roll["next_values"],
                                              roll["terminated"], roll["truncated"], ppo, self.return_rms)
        flat = self._flat_tensor
        batch = {"obs": flat(roll["obs"]), "actions": flat(roll["actions"]), "log_probs": flat(roll["log_probs"]),
                 "advantages": flat(advantages.astype(np.float32)), "returns": flat(returns.astype(np.float32)),
                 "values": flat(roll["values"])}
        stats = ppo_update(self.model, self.optimizer, batch, ppo, self.shuffle, self.shared_geometry)
        self.updates += 1
        return stats

    # ------------------------------------------------------------------------------------------------ selection
    def selection_reward(self) -> tuple[float, float]:
        """Mean return and success of ``selection_episodes`` full-range training-distribution episodes played
        with the deterministic (mean) action on the ``num_test_envs`` test envs, each env playing the same number
        of episodes in turn — the checkpoint-selection score (App. A)."""
        env = self.select_envs
        n = env.num_envs
        per_env = self.config.ppo.selection_episodes // n
        obs, _ = env.reset()
        returns = np.zeros(n)
        running = np.zeros(n)
        successes = np.zeros(n)
        finished = np.zeros(n, np.int64)
        self.model.eval()
        with torch.no_grad():
            while (finished < per_env).any():
                action = clip_action(self.model.mean_action(self._tensor(obs))).cpu().numpy()
                obs, r, term, trunc, info = env.step(action)
                counting = finished < per_env
                running[counting] += r[counting]
                ended = counting & (term | trunc)
                returns[ended] += running[ended]
                successes[ended] += info["success"][ended]
                running[ended] = 0.0
                finished[ended] += 1
        total = per_env * n
        return float(returns.sum() / total), float(successes.sum() / total)

    # ------------------------------------------------------------------------------------------------ state
    def state(self) -> dict[str, Any]:
        """Everything needed to resume exactly."""
        return {
            "model": self.model.state_dict(), "optimizer": self.optimizer.state_dict(),
            "config": self.config.to_dict(), "return_rms": self.return_rms.state_dict(),
            "epoch": self.epoch, "updates": self.updates, "env_steps": self.env_steps,
            "best_reward": self.best_reward, **sampling_rng_state(self.device),
            "shuffle_rng": self.shuffle.get_state(), "obs": self.obs.copy(),
            "episode_return": self.episode_return.copy(),
            "envs": self.envs.state_dict(), "select_envs": self.select_envs.state_dict(),
            "curriculum_fraction": self.sampler.fraction, "init_checkpoint": self.init_checkpoint,
        }

    def restore(self, payload: dict[str, Any], path: str | Path = "snapshot") -> None:
        """Inverse of ``state``; ``path`` (the snapshot) names the file in a CheckpointError when the weights or
        the optimiser state do not fit this run's network."""
        load_weights(self.model, payload["model"], path)
        try:
            self.optimizer.load_state_dict(payload["optimizer"])
        except (KeyError, TypeError, ValueError, RuntimeError) as exc:
            raise CheckpointError(f"{path}: its optimiser state does not fit this run's network: {exc}") from exc
        self.return_rms.load_state_dict(payload["return_rms"])
        self.epoch, self.updates, self.env_steps = payload["epoch"], payload["updates"], payload["env_steps"]
        self.best_reward = payload["best_reward"]
        restore_sampling_rng(payload, self.device)
        self.shuffle.set_state(payload["shuffle_rng"])
        self.obs = payload["obs"].copy()
        self.episode_return = payload["episode_return"].copy()
        self.envs.load_state_dict(payload["envs"], self.obs)
        # the selection envs reset before every scoring: only their generator state matters
        self.select_envs.load_state_dict(payload["select_envs"], self.select_envs.core.obs.copy())
        self.sampler.set_fraction(payload["curriculum_fraction"])
        self.init_checkpoint = payload.get("init_checkpoint")

    def initialize_from(self, path: str | Path) -> None:
        """Warm start: the weights and return statistics of another run's checkpoint whose observation and network
        configs equal this run's (anything else — convention, reward, connector, recipe — may differ); the
        optimiser, schedule and counters start fresh."""
        payload = load_checkpoint(path)
        own = self.config.to_dict()
        theirs = checkpoint_config(path, payload).to_dict()  # fields added since it was saved take their defaults
        diffs = config_differences(
            {"network": own["network"], "observation": own["env"]["observation"]},
            {"network": theirs.get("network"), "observation": theirs.get("env", {}).get("observation")})
        if diffs:
            raise CheckpointError(f"{path}: cannot initialise from it, its network input differs:\n  "
                                  + "\n  ".join(diffs))
        load_weights(self.model, payload["model"], path)
        self.return_rms.load_state_dict(payload["return_rms"])
        self.init_checkpoint = {"path": str(path), "epoch": payload.get("epoch"), "config": payload["config"]}

    def checkpoint_payload(self, selection: float) -> dict[str, Any]:
        """What ``best.pt`` holds: weights, the full config, normalisation statistics, provenance."""
        return {"model": self.model.state_dict(), "config": self.config.to_dict(),
                "return_rms": self.return_rms.state_dict(), "epoch": self.epoch, "selection_reward": selection,
                "env_steps": self.env_steps, "init_checkpoint": self.init_checkpoint}


def _plot_curves(rows: list[dict[str, Any]], path: Path, selection_episodes: int) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 3.2))
    epochs = [r["epoch"] for r in rows]
    panels = [("train_return", "mean episode return (train)"), ("train_success", "success rate (train)"),
              ("selection_reward", f"selection reward ({selection_episodes} full-range episodes)")]
    for i, (key, label) in enumerate(panels):
        ax = fig.add_subplot(1, 3, i + 1)
        ax.plot(epochs, [r[key] for r in rows], marker=".")
        ax.set_xlabel("epoch")
        ax.set_title(label, fontsize="small")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    write_atomic(path, buffer.getvalue())


def write_metrics(path: Path, rows: list[dict[str, Any]]) -> None:
    """``metrics.jsonl`` holding ``rows``, one JSON object a line, written atomically (`write_atomic`): a crash
    leaves the previous file whole."""
    write_atomic(path, "".join(json.dumps(r) + "\n" for r in rows).encode())


def read_metrics(path: Path, key: str = "epoch") -> list[dict[str, Any]]:
    """The rows of ``metrics.jsonl``, each an object with an integer ``key``. A torn last line (a crash in the
    middle of a write by an older version) is discarded with a warning on stderr; a bad line elsewhere is a
    CheckpointError naming the file and line."""
    if not path.exists():
        return []
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    rows = []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
            if not isinstance(row, dict) or not isinstance(row.get(key), int):
                raise ValueError(f"not an object with an integer {key!r}")
        except ValueError as exc:
            if any(rest.strip() for rest in lines[number:]):
                raise CheckpointError(f"{path}: line {number} is not a metrics row ({exc})") from exc
            print(f"warning: {path}: discarding its torn last line {number} ({exc})", file=sys.stderr)
            continue
        rows.append(row)
    return rows


def prepare_run_folder(out: Path, resume: bool, overwrite: bool, run_files: tuple[str, ...] = RUN_FILES,
                       replaced: tuple[str, ...] = REPLACED_FILES) -> None:
    """Refuse to start a new run where one exists (ConfigError naming the folder and its ``run_files``) unless
    ``resume`` (continue it) or ``overwrite`` (the ``replaced`` files are removed first); nothing is written or
    removed before the check."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: expected a run folder, found a file")
    if resume and overwrite:
        raise ConfigError("train: --resume continues the run in the folder, --overwrite replaces it — give one")
    found = [name for name in run_files if (out / name).exists()]
    if resume:
        if not (out / "snapshot.pt").exists():
            raise ConfigError(f"{out}: nothing to resume, no snapshot.pt in it")
    elif found and not overwrite:
        raise ConfigError(f"{out}: already holds a training run ({', '.join(found)}); pass --resume to continue "
                          "it, --overwrite to replace it, or another --out")
    elif found:
        for pattern in replaced:
            for path in out.glob(pattern):
                path.unlink()
    out.mkdir(parents=True, exist_ok=True)


def check_epochs(epochs: Any, ppo: PPOConfig) -> int:
    """``epochs`` (None: the recipe's) as the last epoch to train: an integer in 1..``ppo.epochs``, else a
    ConfigError saying why (the learning-rate schedule and the curriculum end at ``ppo.epochs``)."""
    if epochs is None:
        return ppo.epochs
    if isinstance(epochs, bool) or not isinstance(epochs, int) or not 1 <= epochs <= ppo.epochs:
        raise ConfigError(f"train: --epochs: expected an integer from 1 to ppo.epochs={ppo.epochs} (the last epoch "
                          f"to train; the learning-rate schedule and the curriculum end at ppo.epochs, set it in "
                          f"--config to train longer), got {epochs!r}")
    return epochs


def _resume(trainer: Trainer, config: TrainConfig, out: Path, last: int,
            shared_geometry: bool | None = None) -> list[dict[str, Any]]:
    """Restore ``trainer`` from ``out/snapshot.pt`` and return the metrics rows up to its epoch; a warning when this
    process trains on other thread counts, on another device or with another ``shared_geometry`` than the last row
    records (None keeps the row's; rows written before the field trained without it)."""
    snapshot = out / "snapshot.pt"
    payload = load_checkpoint(snapshot)
    missing = sorted(set(trainer.state()) - set(payload) - {"init_checkpoint", "cuda_rng"})
    if missing:
        raise CheckpointError(f"{snapshot}: not a training snapshot, it lacks {missing} (a best.pt holds weights only)")
    # a field added to TrainConfig after the run started is stored without it: compare with its default
    check_config(snapshot, config.to_dict(), checkpoint_config(snapshot, payload).to_dict())
    trainer.restore(payload, snapshot)
    if last < trainer.epoch:
        raise ConfigError(f"train: --epochs {last}: the snapshot is already at epoch {trainer.epoch}")
    rows = [r for r in read_metrics(out / "metrics.jsonl") if r["epoch"] <= trainer.epoch]
    last_row = rows[-1] if rows else {}
    trainer.shared_geometry = last_row.get("shared_geometry", False) if shared_geometry is None else shared_geometry
    for mismatch in _resume_mismatches(last_row, trainer):
        print(f"warning: {out}: resuming {mismatch}", file=sys.stderr)
    return rows


def _resume_mismatches(last_row: dict[str, Any], trainer: Trainer) -> list[str]:
    """How this process differs from the last metrics row of the run it resumes (none without a row): thread counts,
    device, ``shared_geometry``; rows written before a field existed trained on the CPU, without the shared branch."""
    if not last_row:
        return []
    mismatches = []
    before = {k: last_row[k] for k in thread_counts() if k in last_row}
    now = {k: v for k, v in thread_counts().items() if k in before}
    if before != now:  # a reduction split over other threads differs in its last bits
        mismatches.append(f"on {now} where the run so far trained on {before}: its curve will differ from an "
                          "uninterrupted run's in the last bits (set OMP_NUM_THREADS and NUMBA_NUM_THREADS to match)")
    device_before, device_now = last_row.get("device", "cpu"), device_label(trainer.device)
    if device_before != device_now:
        mismatches.append(f"on {device_now} where the run so far trained on {device_before}: its curve will differ "
                          "from an uninterrupted run's (other kernels, another sampling stream)")
    shared_before = last_row.get("shared_geometry", False)
    if shared_before != trainer.shared_geometry:
        mismatches.append(f"with shared_geometry={trainer.shared_geometry} where the run so far trained with "
                          f"{shared_before}: its curve will differ from an uninterrupted run's in the last bits "
                          f"({'drop' if trainer.shared_geometry else 'give'} --shared-geometry to match)")
    return mismatches


def _train_epoch(trainer: Trainer) -> dict[str, Any]:
    """Collect and update until ``steps_per_epoch`` steps are in, then score selection; the epoch's metrics row."""
    ppo = trainer.config.ppo
    trainer.sampler.set_progress(trainer.epoch / ppo.epochs, trainer.config.curriculum)
    t0 = time.perf_counter()
    steps0 = trainer.env_steps
    returns, successes, stats = [], [], {}
    seconds = dict.fromkeys(("collect_s", "update_s", "selection_s"), 0.0)
    while trainer.env_steps - steps0 < ppo.steps_per_epoch:
        t_phase = time.perf_counter()
        roll = trainer.collect()
        returns += roll["ended_returns"]
        successes += roll["ended_success"]
        t_update = time.perf_counter()
        stats = trainer.update(roll)
        seconds["collect_s"] += t_update - t_phase
        seconds["update_s"] += time.perf_counter() - t_update
    trainer.epoch += 1
    t_phase = time.perf_counter()
    selection, selection_success = trainer.selection_reward()
    seconds["selection_s"] = time.perf_counter() - t_phase
    elapsed = time.perf_counter() - t0
    return {"epoch": trainer.epoch, "env_steps": trainer.env_steps,
            "steps_per_s": (trainer.env_steps - steps0) / elapsed, "epoch_s": elapsed, **seconds,
            "train_return": float(np.mean(returns)) if returns else float("nan"),
            "train_success": float(np.mean(successes)) if successes else float("nan"),
            "episodes": len(returns), "curriculum_fraction": trainer.sampler.fraction,
            "selection_reward": selection, "selection_success": selection_success, **stats, **thread_counts(),
            "device": device_label(trainer.device), "shared_geometry": trainer.shared_geometry}


def finished_rows(out: Path, config: TrainConfig) -> list[dict[str, Any]] | None:
    """The metrics rows of the finished run in ``out`` — its last row is epoch ``ppo.epochs`` and ``best.pt``
    exists, read from the files alone — or None when the run is not finished. A run trained under another config
    is a CheckpointError naming its ``config.json`` and every differing field."""
    rows = read_metrics(out / "metrics.jsonl")
    if not rows or rows[-1]["epoch"] < config.ppo.epochs or not (out / "best.pt").exists():
        return None
    path = out / "config.json"
    try:
        stored = TrainConfig.from_dict(json.loads(path.read_text(encoding="utf-8"))).to_dict()
    except (OSError, ValueError) as exc:  # ValueError covers bad JSON and ConfigError
        raise ConfigError(f"{path}: not a readable TrainConfig of the finished run ({exc})") from exc
    check_config(path, config.to_dict(), stored)
    return rows


def log_scalars(writer: Any, row: dict[str, Any]) -> None:
    """Every number of a metrics row except ``epoch`` as a TensorBoard scalar of the same name at step ``epoch``
    (the ``device`` text is left out)."""
    for key, value in row.items():
        if key != "epoch" and isinstance(value, (int, float)):
            writer.add_scalar(key, value, global_step=row["epoch"])
    writer.flush()


def event_writer(out: Path, rows: list[dict[str, Any]], epoch: int) -> Any:
    """A TensorBoard ``SummaryWriter`` on ``out`` continuing the run after ``epoch``: scalars that a killed run
    wrote after its snapshot are purged (``purge_step``), so no step shows twice; a folder without event files
    (a run started with ``--no-tensorboard``) first gets the kept ``rows``."""
    from torch.utils.tensorboard import SummaryWriter  # imported here: only runs that log load tensorboard

    if any(out.glob(EVENT_FILES)):
        return SummaryWriter(str(out), purge_step=epoch + 1)
    writer = SummaryWriter(str(out))
    for row in rows:
        log_scalars(writer, row)
    return writer


def _write_epoch(trainer: Trainer, out: Path, rows: list[dict[str, Any]], writer: Any, last: int,
                 curves_due: bool) -> bool:
    """The epoch's files, in an order a kill cannot make lie: ``best.pt`` and ``curves.png`` first (the curves when
    ``curves_due``, at a snapshot or at the run's end), then the metrics row (a row means its epoch is written; a
    last row at ``ppo.epochs`` means the run is finished) and its TensorBoard scalars, then the snapshot: written
    every ``snapshot_every_epochs`` and at ``last``, removed once the run is finished. Returns whether it drew the
    curves."""
    row, ppo = rows[-1], trainer.config.ppo
    finished = trainer.epoch == ppo.epochs
    snapshot = not finished and (trainer.epoch % ppo.snapshot_every_epochs == 0 or trainer.epoch == last)
    if row["selection_reward"] > trainer.best_reward:
        trainer.best_reward = row["selection_reward"]
        save_checkpoint(out / "best.pt", trainer.checkpoint_payload(row["selection_reward"]))
    draw = curves_due or finished or snapshot
    if draw:
        _plot_curves(rows, out / "curves.png", ppo.selection_episodes)
    write_metrics(out / "metrics.jsonl", rows)
    if writer is not None:
        log_scalars(writer, row)
    if finished:
        (out / "snapshot.pt").unlink(missing_ok=True)
    elif snapshot:
        save_checkpoint(out / "snapshot.pt", trainer.state())
    return draw


def train(config: TrainConfig, out: str | Path, epochs: int | None = None, resume: bool = False,
          progress: bool = True, init: str | Path | None = None, overwrite: bool = False,
          tensorboard: bool = True, device: str = "cpu", shared_geometry: bool | None = None
          ) -> list[dict[str, Any]]:
    """Run (or resume) training up to ``epochs`` (default: the config's); returns the metrics rows. The network
    trains on ``device`` (`np_policy.device.training_device`: cpu, cuda, cuda:N or auto), with the geometry branch
    once per scene in each update chunk when ``shared_geometry`` (`Trainer.update`; None: off for a new run, as
    the run's last metrics row records for a resumed one). ``init``
    warm-starts a new run from another checkpoint's weights (``Trainer.initialize_from``). A folder that already
    holds a run is refused unless ``resume`` or ``overwrite`` (`prepare_run_folder`); resuming a finished run
    (`finished_rows`) trains nothing and returns its rows. Every file is written atomically; ``tensorboard``
    also logs each row to TensorBoard event files in ``out`` (`event_writer`). SIGTERM or SIGUSR1 during training
    ends it after the epoch in progress, with a snapshot there: `np_sim.stop_request.TrainingStopped`."""
    if init is not None and resume:
        raise ConfigError("train: --init starts a new run from another checkpoint; --resume continues this run's "
                          "snapshot — give one of them")
    out = Path(out)
    last = check_epochs(epochs, config.ppo)
    where = training_device(device)
    if resume and not overwrite and (done := finished_rows(out, config)) is not None:
        (out / "snapshot.pt").unlink(missing_ok=True)  # left by a kill between the last row and its removal
        return done
    prepare_run_folder(out, resume, overwrite)
    trainer = Trainer(config, out, where, bool(shared_geometry))
    rows: list[dict[str, Any]] = []
    if resume:
        rows = _resume(trainer, config, out, last, shared_geometry)
        if trainer.epoch == last:
            return rows
    elif init is not None:
        trainer.initialize_from(init)
    write_atomic(out / "config.json", json.dumps(config.to_dict(), indent=2).encode())
    write_metrics(out / "metrics.jsonl", rows)
    record_start(out, epoch=trainer.epoch, **thread_counts(), device=device_label(where),
                 shared_geometry=trainer.shared_geometry)
    bar = tqdm(range(trainer.epoch, last), desc="epochs", unit="epoch", disable=not progress,
               initial=trainer.epoch, total=last)
    writer = event_writer(out, rows, trainer.epoch) if tensorboard else None
    curves_drawn = time.monotonic()
    try:
        with StopRequest() as stop:
            for _ in bar:
                row = _train_epoch(trainer)
                rows.append(row)
                stopping = stop.requested  # read once: a signal during the writes below waits for the next epoch
                if _write_epoch(trainer, out, rows, writer, trainer.epoch if stopping else last,
                                curves_due=time.monotonic() - curves_drawn >= CURVES_EVERY_S):
                    curves_drawn = time.monotonic()
                bar.set_postfix(steps_s=f"{row['steps_per_s']:,.0f}", ret=f"{row['train_return']:.0f}",
                                succ=f"{row['train_success']:.2f}", cur=f"{row['curriculum_fraction']:.2f}")
                if stopping and trainer.epoch < last:
                    raise TrainingStopped(out, f"epoch {trainer.epoch} of {last}", stop.signum)
    finally:
        if writer is not None:
            writer.close()
    return rows


def _fail(message: str) -> SystemExit:
    """Print ``error: message`` to stderr; the SystemExit (status 2) to raise."""
    print(f"error: {message}", file=sys.stderr)
    return SystemExit(2)


def _read_overrides(path: Path | None) -> dict[str, Any]:
    """The JSON object in the ``--config`` file (empty without one); SystemExit(2) with one error line otherwise."""
    if path is None:
        return {}
    try:
        overrides = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise _fail(f"{path}: not a readable JSON file ({exc})")
    if not isinstance(overrides, dict):
        raise _fail(f"{path}: expected a JSON object of TrainConfig fields, got a {type(overrides).__name__}")
    return overrides


def with_vehicle(data: dict[str, Any], vehicle) -> dict[str, Any]:
    """TrainConfig fields ``data`` for ``vehicle`` (a `np_sim.vehicle.VehicleSpec`): ``env.vehicle`` and, unless
    ``data`` sets it, the connector's curvature bound ``env.connector.kappa_max`` = its κ_max; ConfigError when
    ``data`` names a vehicle too."""
    env = data.get("env", {})
    if not isinstance(env, dict) or not isinstance(env.get("connector", {}), dict):
        return data  # not a mapping: TrainConfig.from_dict names the field
    if "vehicle" in env:
        raise ConfigError("--vehicle and the --config file's env.vehicle both name a vehicle; give one of them")
    connector = {"kappa_max": vehicle.kappa_max, **env.get("connector", {})}
    return {**data, "env": {**env, "vehicle": dataclasses.asdict(vehicle), "connector": connector}}


def main(argv=None) -> list[dict[str, Any]]:
    """Command line of ``train``; a user's mistake is one ``error:`` line on stderr and exit status 2."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.train", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", default="factorial",
                        help=f"training scenes: one of {', '.join(BENCHMARKS)}, or a scene JSON file or folder")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--config", type=Path, help="JSON file with TrainConfig fields overriding the defaults "
                        "(nested: env, ppo, network, curriculum); unknown keys and wrong types are errors")
    parser.add_argument("--vehicle", type=vehicle_spec, help="vehicle to train for: a preset (sedan, the default; "
                        "van) or a vehicle JSON file (docs/vehicles.md)")
    parser.add_argument("--epochs", type=int, help="stop after this epoch, 1..ppo.epochs (default: ppo.epochs); "
                        "the LR schedule and curriculum still follow ppo.epochs")
    parser.add_argument("--out", type=Path, help="run folder (default: results/train/<benchmark>_seed<N>); a folder "
                        "that already holds a run is refused without --resume or --overwrite")
    parser.add_argument("--resume", action="store_true", help="continue from <out>/snapshot.pt (on a finished run: "
                        "says so and trains nothing)")
    parser.add_argument("--overwrite", action="store_true", help="replace the run in --out (its metrics, "
                        "curves and checkpoints are deleted)")
    parser.add_argument("--init", type=Path, help="start a new run from this checkpoint's weights (same observation "
                        "and network config; e.g. the footprint variant from the reference-point site checkpoint)")
    parser.add_argument("--device", default="cpu", help="where the network trains: cpu (the default; a resumed run "
                        "repeats an uninterrupted one bit for bit), cuda, cuda:N, or auto (a CUDA GPU when torch "
                        "sees one); the envs always run on the CPU (np_policy.device)")
    parser.add_argument("--shared-geometry", action=argparse.BooleanOptionalAction, default=None,
                        help="run the network's geometry branch once per distinct scene in each update chunk: the "
                        "same values, about 1.5x faster updates on Factorial, another float summation order in the "
                        "gradient (so a run's curve depends on it; each metrics row records it). Default: off for a "
                        "new run; --resume keeps what the run recorded")
    parser.add_argument("--tensorboard", action=argparse.BooleanOptionalAction, default=True,
                        help="write the metrics as TensorBoard event files beside metrics.jsonl (view them with "
                        "`tensorboard --logdir <out>`)")
    args = parser.parse_args(argv)
    data = merge_config(benchmark_defaults(args.benchmark), _read_overrides(args.config))
    data.update(benchmark=args.benchmark, seed=args.seed)
    try:
        config = TrainConfig.from_dict(data if args.vehicle is None else with_vehicle(data, args.vehicle))
        out = args.out or Path("results/train") / f"{config.benchmark}_seed{config.seed}"
        rows = train(config, out, epochs=args.epochs, resume=args.resume, init=args.init, overwrite=args.overwrite,
                     tensorboard=args.tensorboard, device=args.device, shared_geometry=args.shared_geometry)
    except NPSimError as exc:  # the project's own errors (checkpoint, config, scene) are the user's to fix
        raise _fail(str(exc)) from None
    except TrainingStopped as stopped:
        stopped.exit()
    total = config.ppo.epochs
    if rows and rows[-1]["epoch"] == total:
        print(f"{out}: finished at epoch {total} of {total} (metrics.jsonl, curves.png, best.pt; no snapshot)")
    else:
        print(f"{out}: stopped at epoch {rows[-1]['epoch'] if rows else 0} of {total}; continue it with --resume "
              "(snapshot.pt)")
    return rows


if __name__ == "__main__":
    main()
