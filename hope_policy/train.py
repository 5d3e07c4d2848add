"""Train the adapted HOPE policy with HOPE's PPO for 10,000 episodes (paper §IV-B, App. ``app:hope-adaptation``).

``python -m hope_policy.train --benchmark factorial|topology --seed S --out DIR [--resume|--overwrite]
[--episodes N] [--input none|bev|vertices] [--bev-encoder FILE] [--no-mask] [--no-takeover] [--curriculum-scale 0.05]
[--config FILE]``

A run reads top to bottom: build ``num_envs`` adapted-HOPE envs on the benchmark's training scenes (full-range
starts, or the geodesic start curriculum with ``--curriculum-scale``), then repeat: collect ``batch_size`` (8,192)
transitions (a BEV raster replaced by its frozen encoder's latent, `hope_policy.inputs`), normalising the LiDAR,
target and vertex branches with running statistics updated by every observation a step returns; run one PPO update
(`hope_policy.ppo`); count the episodes that ended in the batch. Training stops
after the update whose batch completes episode ``--episodes`` (10,000), and ``final.pt`` holds that policy with its
normalisation statistics: the checkpoint that is evaluated, with no selection.

Each collect starts every env on a fresh episode, drawn from a seed derived from the run seed and the update
index, and the episodes still running when the batch is full are cut there (their last step bootstrapped from the
critic, as a truncation) and not counted. That makes an update boundary a complete description of the run's
state: ``snapshot.pt`` (every ``snapshot_every`` updates, and where ``max_updates`` stops a run) holds the weights,
both optimisers, the critic copy, the normalisation statistics, the counters and the generator states, and a run
resumed from it computes bit for bit what the uninterrupted run computes. A finished run keeps only its outputs:
once ``final.pt`` is written the snapshot is removed, and ``--resume`` on a finished run trains nothing. SIGTERM
or SIGUSR1 stops a run after the update in progress with a snapshot there and exit status 128 + the signal's number
(`np_sim.stop_request`).
``metrics.jsonl`` gets one line per update and TensorBoard event files beside it hold the same scalars.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch.utils.tensorboard import SummaryWriter
from tqdm import tqdm

from hope_policy.action_mask import apply_mask
from hope_policy.checkpoint import load_hope_checkpoint, save_hope_checkpoint
from hope_policy.config import ADDED_INPUTS, HopeEnvConfig
from hope_policy.env import HopeVectorEnv
from hope_policy.inputs import PolicyInputs
from hope_policy.network import HopeActorCritic
from hope_policy.normalization import ObservationNormaliser
from hope_policy.ppo import HopePPO, HopePPOConfig
from hope_policy.spaces import observation_space
from np_policy.checkpoint import CheckpointError, check_config, load_weights, write_atomic
from np_policy.config import CURRICULUM_REGIONS, check_types
from np_policy.threads import thread_counts
from np_policy.train import (curriculum_scenes, merge_config, prepare_run_folder, read_metrics, training_scenes,
                             write_metrics)
from np_sim.cli import cli_boundary, non_negative_int, positive_float, positive_int
from np_sim.config import config_from_dict
from np_sim.curriculum import CurriculumSchedule, CurriculumStartSampler
from np_sim.errors import ConfigError
from np_sim.provenance import PROVENANCE_FILE, record_start
from np_sim.stop_request import StopRequest, TrainingStopped

BENCHMARKS = ("factorial", "topology")
RUN_FILES = ("metrics.jsonl", "snapshot.pt", "final.pt")
"""A folder holding any of these holds a training run."""
REPLACED_FILES = (*RUN_FILES, "config.json", PROVENANCE_FILE)
"""What ``overwrite`` removes (with the TensorBoard event files) before a new run starts there."""
EVENTS_GLOB = "events.out.tfevents.*"


@dataclass(frozen=True)
class HopeTrainConfig:
    """Everything an adapted-HOPE run depends on; written beside its checkpoints and stored inside them."""

    benchmark: str = "factorial"
    """Training scenes: the train split of 'factorial' or 'topology'."""
    seed: int = 0
    """Seed of torch (weights, action noise), the minibatch shuffling and the envs' episodes."""
    episodes: int = 10_000
    """Training stops after the update whose batch completes this many episodes (paper: 10,000)."""
    num_envs: int = 16
    """Envs stepped together; ``ppo.batch_size`` must be a multiple of it."""
    snapshot_every: int = 5
    """Updates between snapshots (one is also written at the end)."""
    curriculum_pool: int = 256
    """Start poses per scene in the geodesic curriculum pool (when ``env.curriculum.enabled``)."""
    curriculum_region: str = "start_region"
    """Where the curriculum pool is drawn: each scene's start region, or 'lot' (the whole drivable lot), as
    ``np_policy.config.TrainConfig.curriculum_region``; the Table III rows use the NeuralParker recipe's 'lot'."""
    bev_encoder_file: str = ""
    """The pretrained BEV autoencoder file (``python -m np_policy.pretrain_bev``) of ``env.added_input='bev'``;
    empty for the other inputs."""
    holdout_every: int = 0
    """Beyond the paper: leave every this-many-th training scene out of training (as
    ``np_policy.config.TrainConfig.holdout_every``), so ``python -m experiments.planners --split holdout`` can measure
    how the run carries over to scenes it never saw without looking at the test scenes; 0 (the paper's) trains on
    all of them."""
    torch_threads: int = 1
    """torch intra-op threads, set again before every update: the envs' numba parallel loops reset the OpenMP
    thread count, and a sum split over another number of threads can differ in its last bit."""
    env: HopeEnvConfig = field(default_factory=HopeEnvConfig)
    ppo: HopePPOConfig = field(default_factory=HopePPOConfig)

    def __post_init__(self) -> None:
        if self.benchmark not in BENCHMARKS:
            raise ConfigError(f"HopeTrainConfig.benchmark: expected one of {BENCHMARKS}, got {self.benchmark!r}")
        for name in ("episodes", "num_envs", "snapshot_every", "curriculum_pool", "torch_threads"):
            if getattr(self, name) < 1:
                raise ConfigError(f"HopeTrainConfig.{name}: expected an integer >= 1, got {getattr(self, name)!r}")
        if self.ppo.batch_size % self.num_envs:
            raise ConfigError(f"HopeTrainConfig.num_envs: ppo.batch_size={self.ppo.batch_size} must be a multiple "
                              f"of num_envs, got {self.num_envs}")
        if isinstance(self.holdout_every, bool) or self.holdout_every < 0 or self.holdout_every == 1:
            raise ConfigError(f"HopeTrainConfig.holdout_every: expected 0 or an integer >= 2, got "
                              f"{self.holdout_every!r}")
        if self.curriculum_region not in CURRICULUM_REGIONS:
            raise ConfigError(f"HopeTrainConfig.curriculum_region: expected one of {CURRICULUM_REGIONS}, got "
                              f"{self.curriculum_region!r}")
        if (self.env.added_input == "bev") != bool(self.bev_encoder_file):
            raise ConfigError(f"HopeTrainConfig.bev_encoder_file: expected the pretrained autoencoder file exactly "
                              f"when env.added_input is 'bev', got {self.bev_encoder_file!r} with "
                              f"{self.env.added_input!r}")

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "HopeTrainConfig":
        """Inverse of ``to_dict``; unknown keys and wrong types are a ConfigError naming the field."""
        check_types(cls, data)
        return config_from_dict(cls, data)


def collect_seed(seed: int, update: int) -> int:
    """Seed of the episodes of the collect before update ``update`` (run seed and update index)."""
    return int(np.random.SeedSequence([seed, update]).generate_state(1)[0])


def _tensors(obs: dict[str, np.ndarray]) -> dict[str, torch.Tensor]:
    """float32 copies in torch's own memory: MKL's sums can differ in the last bit with the alignment of a
    numpy buffer, and a resumed run must compute bit for bit what the uninterrupted one does."""
    return {key: torch.tensor(np.asarray(value, np.float32)) for key, value in obs.items()}


class HopeTrainer:
    """State of one adapted-HOPE run: envs, model, PPO, normaliser, generators and counters."""

    def __init__(self, config: HopeTrainConfig):
        self.config = config
        torch.set_num_threads(config.torch_threads)  # the orthogonal initialisation's QR depends on it too
        torch.manual_seed(config.seed)
        scenes = training_scenes(config.benchmark, config.holdout_every)
        schedule = config.env.curriculum
        self.sampler = (CurriculumStartSampler(curriculum_scenes(scenes, config.curriculum_region),
                                               fraction=schedule.start_fraction,
                                               pool_size=config.curriculum_pool, seed=config.seed,
                                               vehicle=config.env.vehicle) if schedule.enabled else None)
        self.envs = HopeVectorEnv(scenes, config.num_envs, config.env, seed=config.seed, start_sampler=self.sampler)
        space = observation_space(config.env)
        self.inputs = PolicyInputs(config.env, config.bev_encoder_file)
        self.model = HopeActorCritic(self.inputs.modalities(space))
        self.ppo = HopePPO(self.model, config.ppo)
        self.normaliser = ObservationNormaliser.for_space(space, config.env)
        self.shuffle = np.random.default_rng(config.seed)
        self.action_rng = np.random.default_rng([config.seed, 1])
        self.updates = self.episodes = self.env_steps = 0

    @property
    def done(self) -> bool:
        """The episode budget is spent."""
        return self.episodes >= self.config.episodes

    # ------------------------------------------------------------------------------------------------ collect
    def _act(self, obs: dict[str, np.ndarray], obs_n: dict[str, np.ndarray]) -> tuple[np.ndarray, Any]:
        """The actions to play and the policy's distribution: with the mask, an anchor drawn by HOPE's masked choice
        (`hope_policy.action_mask.apply_mask`, from the raw mask); without it ``clip(μ + σ ε, −1, 1)``."""
        torch.set_num_threads(self.config.torch_threads)  # the env step just ran numba's parallel loops
        with torch.no_grad():
            dist = self.model.distribution(_tensors(obs_n))
            if "action_mask" not in obs:
                return dist.sample().clamp(-1.0, 1.0).numpy(), dist
        action = apply_mask(dist.mean.numpy(), dist.stddev.numpy(), obs["action_mask"], self.action_rng)
        return action.astype(np.float32), dist

    def collect(self) -> dict[str, Any]:
        """``batch_size`` transitions, time-major ``(T, N)``, from fresh episodes; observations normalised."""
        T, N = self.config.ppo.batch_size // self.config.num_envs, self.config.num_envs
        if self.sampler is not None:
            self.sampler.set_progress(self.episodes / self.config.episodes, self.config.env.curriculum)
        obs, _ = self.envs.reset(seed=collect_seed(self.config.seed, self.updates))
        obs = self.inputs(obs)
        if self.normaliser.stats and all(s.empty for s in self.normaliser.stats.values()):
            self.normaliser.update(obs)  # HOPE initialises its statistics with the first observation
        steps: list[dict[str, Any]] = []
        for _ in range(T):
            obs_n = self.normaliser(obs)
            action, dist = self._act(obs, obs_n)
            obs, reward, terminated, truncated, info = self.envs.step(action)
            obs = self.inputs(obs)
            # a takeover chunk replaces the policy's action; HOPE stores and scores the chunk
            executed = np.where(info["rs_takeover"][:, None], info["executed_action"], action).astype(np.float32)
            with torch.no_grad():
                log_prob = dist.log_prob(torch.tensor(executed)).sum(-1).numpy()
            done = terminated | truncated
            final = self.inputs(info["final_obs"]) if done.any() else None
            following = {key: np.where(_broadcast(done, value), final[key], value)
                         for key, value in obs.items()} if done.any() else obs
            self.normaliser.update(following)
            steps.append({"obs": obs_n, "action": executed, "log_prob": log_prob, "reward": reward,
                          "terminated": terminated, "truncated": truncated, "done": done, "success": info["success"],
                          "next_obs": self.normaliser(following)})
        self.env_steps += T * N
        return _stack(steps)

    # ------------------------------------------------------------------------------------------------ update
    def update(self, roll: dict[str, Any]) -> dict[str, float]:
        """One PPO update on a collect (`hope_policy.ppo.HopePPO`)."""
        torch.set_num_threads(self.config.torch_threads)
        flat = {key: value.reshape(-1, *value.shape[2:]) for key, value in roll["obs"].items()}
        next_flat = {key: value.reshape(-1, *value.shape[2:]) for key, value in roll["next_obs"].items()}
        with torch.no_grad():
            next_values = self.model.value(_tensors(next_flat)).numpy().reshape(roll["reward"].shape)
        obs = _tensors(flat)
        adv, targets = self.ppo.targets(obs, next_values, roll["reward"], roll["terminated"], roll["truncated"])
        actions = torch.tensor(roll["action"].reshape(-1, 2))
        old = torch.tensor(roll["log_prob"].reshape(-1))
        stats = self.ppo.update(obs, actions, old, adv, targets, self.shuffle)
        self.updates += 1
        return stats

    def step(self) -> dict[str, Any]:
        """One collect and one update; the update's metrics row."""
        t0 = time.perf_counter()
        roll = self.collect()
        t1 = time.perf_counter()
        stats = self.update(roll)
        t2 = time.perf_counter()
        ended = roll["done"]
        self.episodes += int(ended.sum())
        returns = _episode_returns(roll["reward"], ended)
        success = roll["success"][ended]
        return {"update": self.updates, "episodes": self.episodes, "env_steps": self.env_steps,
                "ended": int(ended.sum()), "train_return": float(np.mean(returns)) if len(returns) else float("nan"),
                "train_success": float(np.mean(success)) if len(success) else float("nan"),
                "curriculum_fraction": self.sampler.fraction if self.sampler is not None else 1.0,
                "collect_s": t1 - t0, "update_s": t2 - t1, **stats}

    # ------------------------------------------------------------------------------------------------ state
    def policy_payload(self) -> dict[str, Any]:
        """What ``final.pt`` holds: weights, config, normalisation statistics, counters."""
        return {"model": self.model.state_dict(), "config": self.config.to_dict(),
                "obs_norm": self.normaliser.state_dict(), "episodes": self.episodes, "updates": self.updates,
                "env_steps": self.env_steps}

    def state(self) -> dict[str, Any]:
        """Everything needed to resume exactly at this update boundary."""
        return {**self.policy_payload(), "ppo": self.ppo.state_dict(), "torch_rng": torch.get_rng_state(),
                "shuffle_rng": self.shuffle.bit_generator.state,
                "action_rng": self.action_rng.bit_generator.state}

    def restore(self, payload: dict[str, Any], path: Path) -> None:
        """Inverse of ``state``; CheckpointError naming ``path`` when it does not fit this run."""
        missing = sorted(set(self.state()) - set(payload))
        if missing:
            raise CheckpointError(f"{path}: not a training snapshot, it lacks {missing}")
        load_weights(self.model, payload["model"], path)
        try:
            self.ppo.load_state_dict(payload["ppo"])
            self.normaliser.load_state_dict(payload["obs_norm"])
        except (KeyError, ValueError, RuntimeError) as exc:
            raise CheckpointError(f"{path}: its optimiser or normaliser state does not fit this run: {exc}") from exc
        torch.set_rng_state(payload["torch_rng"])
        self.shuffle.bit_generator.state = payload["shuffle_rng"]
        self.action_rng.bit_generator.state = payload["action_rng"]
        self.updates, self.episodes, self.env_steps = payload["updates"], payload["episodes"], payload["env_steps"]


def _broadcast(done: np.ndarray, value: np.ndarray) -> np.ndarray:
    return done.reshape(-1, *([1] * (value.ndim - 1)))


def _stack(steps: list[dict[str, Any]]) -> dict[str, Any]:
    """Per-step dicts → time-major arrays (observation dicts stacked key by key)."""
    out: dict[str, Any] = {}
    for key, first in steps[0].items():
        if isinstance(first, dict):
            out[key] = {k: np.stack([s[key][k] for s in steps]) for k in first}
        else:
            out[key] = np.stack([s[key] for s in steps])
    return out


def _episode_returns(rewards: np.ndarray, done: np.ndarray) -> np.ndarray:
    """Returns of the episodes that ended inside a ``(T, N)`` batch of fresh episodes."""
    returns, running = [], np.zeros(rewards.shape[1])
    for t in range(rewards.shape[0]):
        running += rewards[t]
        returns.extend(running[done[t]].tolist())
        running[done[t]] = 0.0
    return np.asarray(returns)


# ------------------------------------------------------------------------------------------------ run
def _prepare(out: Path, resume: bool, overwrite: bool) -> None:
    """The run-folder rule of ``np_policy.train``: a folder holding a run needs ``resume`` or ``overwrite``."""
    prepare_run_folder(out, resume, overwrite, run_files=RUN_FILES, replaced=REPLACED_FILES)
    if overwrite:
        for events in out.glob(EVENTS_GLOB):
            events.unlink()


def _log(writer: SummaryWriter, row: dict[str, Any]) -> None:
    for key, value in row.items():
        if key != "update" and isinstance(value, (int, float)):
            writer.add_scalar(key, value, row["update"])
    writer.flush()


def train(config: HopeTrainConfig, out: str | Path, resume: bool = False, overwrite: bool = False,
          progress: bool = True, max_updates: int | None = None) -> list[dict[str, Any]]:
    """Run (or resume) training until ``config.episodes`` episodes have ended; returns the metrics rows.
    ``max_updates`` stops earlier, after that many updates in total (a snapshot is written there). The files of an
    update are written in an order a kill cannot make lie: the metrics row, then ``final.pt`` when the budget is
    spent, then the snapshot (removed instead once ``final.pt`` exists). Resuming a finished run (`finished_rows`)
    trains nothing and returns its rows. SIGTERM or SIGUSR1 ends the run after the update in progress, with a
    snapshot there (`np_sim.stop_request.TrainingStopped`)."""
    out = Path(out)
    if resume and not overwrite and (done := finished_rows(out, config)) is not None:
        (out / "snapshot.pt").unlink(missing_ok=True)  # left by a kill between final.pt and its removal
        return done
    PolicyInputs(config.env, config.bev_encoder_file)  # refuses a missing BEV autoencoder before the folder is touched
    _prepare(out, resume, overwrite)
    trainer = HopeTrainer(config)
    metrics_path = out / "metrics.jsonl"
    rows: list[dict[str, Any]] = []
    if resume:
        snapshot = out / "snapshot.pt"
        payload = load_hope_checkpoint(snapshot)
        check_config(snapshot, config.to_dict(), payload["config"])
        trainer.restore(payload, snapshot)
        rows = [r for r in read_metrics(metrics_path, key="update") if r["update"] <= trainer.updates]
    write_atomic(out / "config.json", json.dumps(config.to_dict(), indent=2).encode())
    write_metrics(metrics_path, rows)
    record_start(out, update=trainer.updates, episodes=trainer.episodes, **thread_counts())
    writer = SummaryWriter(str(out), purge_step=trainer.updates + 1 if resume else None)
    bar = tqdm(total=config.episodes, initial=min(trainer.episodes, config.episodes), desc="episodes",
               unit="ep", disable=not progress)
    try:
        with StopRequest() as stop:
            while not trainer.done and (max_updates is None or trainer.updates < max_updates):
                row = trainer.step()
                rows.append(row)
                stopping = stop.requested  # read once: a signal during the writes below waits for the next update
                write_metrics(metrics_path, rows)
                _log(writer, row)
                if trainer.done:
                    save_hope_checkpoint(out / "final.pt", trainer.policy_payload())
                    (out / "snapshot.pt").unlink(missing_ok=True)
                elif stopping or trainer.updates % config.snapshot_every == 0 or trainer.updates == max_updates:
                    save_hope_checkpoint(out / "snapshot.pt", trainer.state())
                bar.update(min(row["episodes"], config.episodes) - bar.n)
                bar.set_postfix(ret=f"{row['train_return']:.2f}", succ=f"{row['train_success']:.2f}")
                if stopping and not trainer.done:
                    raise TrainingStopped(out, f"update {trainer.updates} ({trainer.episodes} episodes)", stop.signum)
    finally:
        bar.close()
        writer.close()
    return rows


def finished_rows(out: Path, config: HopeTrainConfig) -> list[dict[str, Any]] | None:
    """The metrics rows of the finished run in ``out`` (its last row has counted ``config.episodes`` and
    ``final.pt`` exists, read from the files alone), or None when it is not finished. A run trained under another
    config is a CheckpointError naming its ``config.json`` and every differing field (a field added since is
    compared with its default)."""
    rows = read_metrics(out / "metrics.jsonl", key="update")
    if rows and rows[-1]["episodes"] >= config.episodes and (out / "final.pt").exists():
        stored = HopeTrainConfig.from_dict(read_config_file(out / "config.json"))
        check_config(out / "config.json", config.to_dict(), stored.to_dict())
        return rows
    return None


def read_config_file(path: Path | None) -> dict[str, Any]:
    """The JSON object of HopeTrainConfig fields in ``--config`` (empty without one); ConfigError naming the file
    when it is not readable JSON or not an object."""
    if path is None:
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ConfigError(f"{path}: not a readable JSON file ({exc})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a JSON object of HopeTrainConfig fields, got a {type(data).__name__}")
    return data


def build_config(args: argparse.Namespace) -> HopeTrainConfig:
    """The run's config from the command line: the complete adapted baseline or a representation variant from the
    flags, the ``--config`` file's fields merged over it, benchmark and seed from the flags."""
    env = HopeEnvConfig(action_mask=not args.no_mask, rs_takeover=not args.no_takeover, added_input=args.input,
                        curriculum=CurriculumSchedule(enabled=args.curriculum_scale is not None,
                                                      start_fraction=args.curriculum_scale or 0.05))
    flags = dict(episodes=args.episodes, num_envs=args.num_envs, env=env.to_dict(),
                 bev_encoder_file=str(args.bev_encoder or ""))
    data = merge_config(flags, read_config_file(args.config))
    data.update(benchmark=args.benchmark, seed=args.seed)
    return HopeTrainConfig.from_dict(data)


@cli_boundary
def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Command line of the adapted-HOPE trainer (module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m hope_policy.train", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=BENCHMARKS, default="factorial", help="training scenes")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="training seed")
    parser.add_argument("--out", type=Path, help="run folder (default: results/hope_train/<benchmark>_seed<S>); "
                        "a folder that already holds a run is refused without --resume or --overwrite")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--resume", action="store_true", help="continue from <out>/snapshot.pt (on a finished run: "
                      "trains nothing)")
    mode.add_argument("--overwrite", action="store_true", help="replace the run in --out")
    parser.add_argument("--episodes", type=positive_int, default=10_000, help="episode budget (paper: 10,000)")
    parser.add_argument("--input", choices=ADDED_INPUTS, default="none", help="added scene input (Table III)")
    parser.add_argument("--bev-encoder", type=Path, help="pretrained BEV autoencoder of --input bev "
                        "(python -m np_policy.pretrain_bev)")
    parser.add_argument("--no-mask", action="store_true", help="disable HOPE's action mask (and its branch)")
    parser.add_argument("--no-takeover", action="store_true", help="disable the Reeds-Shepp takeover")
    parser.add_argument("--curriculum-scale", type=positive_float, default=None,
                        help="geodesic start curriculum starting at this fraction (Table III variants: 0.05); "
                        "default: full-range starts")
    parser.add_argument("--num-envs", type=positive_int, default=16, help="envs stepped together")
    parser.add_argument("--config", type=Path, help="JSON file of HopeTrainConfig fields merged over what the flags "
                        "give (nested: env, ppo); unknown keys and wrong types are errors")
    args = parser.parse_args(argv)
    config = build_config(args)
    out = args.out or Path("results/hope_train") / f"{config.benchmark}_seed{config.seed}"
    try:
        rows = train(config, out, resume=args.resume, overwrite=args.overwrite)
    except TrainingStopped as stopped:
        stopped.exit()
    print(f"{out}: finished after {len(rows)} updates, {rows[-1]['episodes'] if rows else 0} episodes "
          "(metrics.jsonl, final.pt; no snapshot)")
    return rows


if __name__ == "__main__":
    main()
