"""Self-imitation of the anytime footprint planner (beyond the paper): fine-tune a site policy's mean action towards
the plans its own best-of-N planner chooses, so that its mean rollout is accepted on more calls.

``python -m np_policy.distill [--checkpoint checkpoints/site_np_footprint.pt] [--out DIR] [--resets 1500]
[--epochs 20] [--learning-rate 1e-4] [--seed 0] [--pairs EARLIER/pairs.npz]``

The footprint planner (`np_policy.planner`, preset 'footprint_anytime') answers a call at the price of one rollout
only when the policy's mean rollout succeeds with 0.2 m of clearance (``accept_mean_m``); on the site clips that
is a third of the calls, and the rest pay the sampled and rescue rounds (docs/best_of_n.md). Those rounds do find
clear plans: this module collects them and teaches them to the mean (expert iteration, the planner being the
expert of its own policy).

1. **Collect.** ``--resets`` recorded-task resets (`np_sim.clips.resets.sample_recorded_reset`: a training clip's
   own start, exact or jittered, at a random frame) from the difficult training clips after the first 94, which
   stay the validation set of `experiments.mean_rollout` and `experiments.plan_time` (as for
   ``TrainConfig.site_recorded_skip``). The planner plans each; a plan its anytime test accepts (success, steerable,
   0.2 m of clearance: `NeuralParkerPlanner.accepted`), whatever stage found it, is replayed through the planner's
   env with its own actions (`replay_observations`), which gives the observation before every arc.
2. **Fit.** The actor's mean (encoder and actor head; the critic and log σ untouched) is regressed onto those
   normalised actions (`imitation_loss`: squared error, none where the clipped mean already plays a ±1 target) with
   Adam, minibatches of 256, a seeded tenth of the resets held out to report the fit.
3. **Write** a run folder: ``DIR/best.pt`` (the source checkpoint's payload with the new weights, loadable by
   every planner and CLI, provenance under ``distill``), ``DIR/config.json`` (the policy's training config, as
   every run folder holds), ``DIR/metrics.jsonl`` (per-epoch losses), ``DIR/distill.json`` (settings and counts)
   and ``DIR/pairs.npz`` (the collected observations and actions, so the fit can be rerun without planning again).

Judge the result on the validation clips only: ``python -m experiments.mean_rollout --clips-limit 94 --checkpoint
DIR/best.pt`` (how many first frames the mean rollout answers) and ``python -m experiments.plan_time --split
train-difficult --clips-limit 94 --planners neuralparker_footprint --set planner.footprint_checkpoint=…``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from np_policy.checkpoint import load_checkpoint, save_checkpoint
from np_policy.config import FOOTPRINT_ANYTIME
from np_policy.planner import NeuralParkerPlanner, Policy
from np_policy.sampling import PolicyRollouts
from np_policy.train import recorded_clips
from np_sim.cli import cli_boundary, fresh_folder, non_negative_int, positive_float, positive_int
from np_sim.clips.resets import sample_recorded_reset
from np_sim.errors import ConfigError, StartInCollisionError

VALIDATION_CLIPS = 94
"""The first difficult training clips, kept out of the collection (the validation set of the tuning tools)."""


class _Exhausted(Exception):
    """The replayed episode wants an arc after the last given action."""


class _Replay:
    """An 'actor' for `PolicyRollouts` that plays fixed actions and keeps the observation it was shown each time."""

    def __init__(self, actions: np.ndarray):
        self.actions, self.seen = np.asarray(actions, np.float64), []

    def batch(self, obs: np.ndarray) -> np.ndarray:
        """(1, 2) next given action for the observation batch ``obs`` (its first row is kept)."""
        if len(self.seen) == len(self.actions):
            raise _Exhausted
        self.seen.append(np.array(obs[0], np.float32))
        return self.actions[len(self.seen) - 1][None]


def replay_observations(planner: NeuralParkerPlanner, scene, start, actions: np.ndarray) -> np.ndarray | None:
    """The observation before each arc of the normalised ``actions`` (n, 2) played from ``start`` in ``planner``'s
    env, or None when the replay does not end in the same success (it always should: the env is deterministic)."""
    replay = _Replay(actions)
    nearest = planner.config.over_capacity == "nearest"
    try:
        plan = PolicyRollouts(replay, np.zeros(2), planner.env_config, nearest=nearest)(scene, start)[0]
    except _Exhausted:
        return None
    if not plan.success or len(replay.seen) != len(actions):
        return None
    return np.stack(replay.seen)


def collect(planner: NeuralParkerPlanner, clips: list, resets: int, seed: int,
            progress: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, int]]:
    """(observations (m, d), normalised actions (m, 2), reset index of each pair (m,), counts) from the accepted
    plans of ``resets`` recorded resets of ``clips`` (module docstring, step 1)."""
    rng = np.random.default_rng(seed)
    scale = np.array([planner.env_config.vehicle.kappa_max, planner.env_config.episode.max_length_m])
    obs, actions, owner = [], [], []
    counts = {"resets": resets, "accepted": 0, "by_mean": 0, "not_accepted": 0, "start_in_collision": 0,
              "replay_mismatch": 0}
    for k in tqdm(range(resets), desc="planning recorded resets", unit="reset", disable=not progress):
        scene, start = sample_recorded_reset(rng, clips, vehicle=planner.body)
        try:
            plan = planner.plan(scene, start)
        except StartInCollisionError:
            counts["start_in_collision"] += 1
            continue
        if not planner.accepted(scene, plan):
            counts["not_accepted"] += 1
            continue
        normalised = np.asarray(plan.arcs, np.float64) / scale
        seen = replay_observations(planner, scene, start, normalised)
        if seen is None:
            counts["replay_mismatch"] += 1
            continue
        counts["accepted"] += 1
        counts["by_mean"] += plan.stage == "mean"
        obs.append(seen)
        actions.append(normalised)
        owner.append(np.full(len(seen), k))
    if not obs:
        raise ConfigError(f"distill: none of the {resets} resets gave an accepted plan to imitate")
    return (np.concatenate(obs), np.concatenate(actions).astype(np.float32), np.concatenate(owner), counts)


def imitation_loss(mean: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean squared error of the actor's raw mean against normalised target actions, leaving out the entries where
    the target is at a bound (±1) and the mean is already beyond it: the planner clips the mean, so it plays the
    target there."""
    done = ((target >= 1.0) & (mean >= 1.0)) | ((target <= -1.0) & (mean <= -1.0))
    return torch.where(done, torch.zeros_like(mean), (mean - target) ** 2).mean()


def fit(policy: Policy, obs: np.ndarray, actions: np.ndarray, owner: np.ndarray, epochs: int,
        learning_rate: float, seed: int, progress: bool = True) -> list[dict[str, float]]:
    """Regress ``policy``'s mean onto ``actions`` in place (module docstring, step 2); per-epoch training and
    held-out losses (a seeded tenth of the resets held out, rounded down; None with none, and no training loss
    before the first epoch)."""
    generator = torch.Generator().manual_seed(seed)
    resets = np.unique(owner)
    held = np.isin(owner, np.random.default_rng(seed).choice(resets, len(resets) // 10, replace=False))
    x, y = torch.from_numpy(obs), torch.from_numpy(actions)
    model = policy.model.train()
    params = [*model.encoder.parameters(), *model.actor.parameters()]
    optimizer = torch.optim.Adam(params, lr=learning_rate)
    train_idx, held_idx = torch.from_numpy(np.flatnonzero(~held)), torch.from_numpy(np.flatnonzero(held))

    def held_out_loss() -> float:
        if not len(held_idx):
            return None
        with torch.no_grad():
            return float(imitation_loss(model.actor(model.encoder(x[held_idx])), y[held_idx]))

    rows = [{"epoch": 0, "train_loss": None, "held_out_loss": held_out_loss()}]
    for epoch in tqdm(range(1, epochs + 1), desc="fitting the mean", unit="epoch", disable=not progress):
        order = train_idx[torch.randperm(len(train_idx), generator=generator)]
        losses = []
        for a in range(0, len(order), 256):
            batch = order[a:a + 256]
            loss = imitation_loss(model.actor(model.encoder(x[batch])), y[batch])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            losses.append(loss.item())
        rows.append({"epoch": epoch, "train_loss": float(np.mean(losses)), "held_out_loss": held_out_loss()})
    model.eval()
    return rows


def collected(pairs: Path, checkpoint: Path, resets: int, seed: int, progress: bool,
              clips: list | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """The pairs of step 1: collected now, or read from an earlier run's ``pairs.npz`` (its counts from the
    ``distill.json`` beside it)."""
    if pairs is not None:
        data = np.load(pairs)
        counts = json.loads((Path(pairs).parent / "distill.json").read_text())["counts"]
        return data["obs"], data["actions"], data["owner"], {**counts, "pairs_file": str(pairs)}
    planner = NeuralParkerPlanner(Policy.load(checkpoint, "site"), FOOTPRINT_ANYTIME)
    clips = recorded_clips(VALIDATION_CLIPS) if clips is None else clips
    return collect(planner, clips, resets, seed, progress)


def distill(checkpoint: Path, out: Path, resets: int = 1500, epochs: int = 20, learning_rate: float = 1e-4,
            seed: int = 0, progress: bool = True, clips: list | None = None,
            pairs: Path | None = None) -> dict[str, Any]:
    """Collect (or read ``pairs``), fit and write (module docstring); returns the settings, counts and per-epoch
    losses. ``clips`` replaces the difficult training clips after the first 94 (tests)."""
    obs, actions, owner, counts = collected(pairs, checkpoint, resets, seed, progress, clips)
    np.savez_compressed(out / "pairs.npz", obs=obs, actions=actions, owner=owner)
    policy = Policy.load(checkpoint, "site")
    rows = fit(policy, obs, actions, owner, epochs, learning_rate, seed, progress)
    summary = {"checkpoint": str(checkpoint), "resets": counts["resets"], "epochs": epochs,
               "learning_rate": learning_rate, "seed": seed, "validation_clips_skipped": VALIDATION_CLIPS,
               "pairs": int(len(obs)), "counts": counts, "losses": rows}
    payload = load_checkpoint(checkpoint)
    payload["model"] = policy.model.state_dict()
    payload["distill"] = {k: v for k, v in summary.items() if k != "losses"}
    save_checkpoint(out / "best.pt", payload)
    (out / "config.json").write_text(json.dumps(payload["config"], indent=2))
    (out / "metrics.jsonl").write_text("".join(json.dumps(row) + "\n" for row in rows))
    (out / "distill.json").write_text(json.dumps({k: v for k, v in summary.items() if k != "losses"}, indent=2))
    return summary


@cli_boundary
def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.distill", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--checkpoint", type=Path, default=Path("checkpoints/site_np_footprint.pt"),
                        help="site policy to start from (default the shipped footprint-aware one)")
    parser.add_argument("--out", type=fresh_folder,
                        help="new or empty folder for the run (default: a fresh results/distill/<timestamp>)")
    parser.add_argument("--resets", type=positive_int, default=1500, help="recorded resets to plan (default 1500)")
    parser.add_argument("--epochs", type=positive_int, default=20, help="passes over the pairs (default 20)")
    parser.add_argument("--learning-rate", type=positive_float, default=1e-4, help="Adam's step size (default 1e-4)")
    parser.add_argument("--pairs", type=Path,
                        help="fit on the pairs.npz of an earlier run (same --checkpoint) instead of planning again")
    parser.add_argument("--seed", type=non_negative_int, default=0,
                        help="seed of the resets, the hold-out and the shuffling")
    args = parser.parse_args(argv)
    if args.out is None:
        args.out = Path("results/distill") / time.strftime("%Y%m%d-%H%M%S")
    args.out.mkdir(parents=True, exist_ok=True)
    summary = distill(args.checkpoint, args.out, args.resets, args.epochs, args.learning_rate, args.seed,
                      pairs=args.pairs)
    first, last = (row["held_out_loss"] for row in (summary["losses"][0], summary["losses"][-1]))
    held = "no resets held out" if first is None else f"held-out loss {first:.4f} → {last:.4f}"
    print(f"{summary['counts']['accepted']} of {summary['counts']['resets']} resets gave accepted plans "
          f"({summary['counts']['by_mean']} by the mean rollout), {summary['pairs']} pairs; {held}; "
          f"{args.out / 'best.pt'}")
    return summary


if __name__ == "__main__":
    main()
