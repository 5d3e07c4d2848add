"""Tests of hope_policy/train.py: a resumed run computes bit for bit what an uninterrupted one computes, the files
a run writes, and the CLI's refusals (one error line, exit status 2)."""

from __future__ import annotations

import dataclasses
import json
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from cli_helpers import one_error_line
from stop_helpers import guarded_stop_signals, signal_after
from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.ppo import HopePPOConfig
from hope_policy.train import HopeTrainConfig, HopeTrainer, main, train
from np_policy.checkpoint import CheckpointError
from np_sim.stop_request import TrainingStopped

TIMING = ("collect_s", "update_s")


def _without_timing(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in TIMING}


ROOT = Path(__file__).resolve().parents[2]


def tiny_config(**overrides) -> HopeTrainConfig:
    """Two envs, batches of 16 transitions, two epochs of minibatches of 8: seconds per update."""
    return HopeTrainConfig(num_envs=2, snapshot_every=1,
                           ppo=HopePPOConfig(batch_size=16, minibatch_size=8, epochs=2), **overrides)


@pytest.fixture(scope="module")
def straight_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("straight")
    rows = train(tiny_config(), out, progress=False, max_updates=2)
    return out, rows


def test_resume_at_an_update_boundary_is_bit_for_bit_the_uninterrupted_run(straight_run, tmp_path):
    straight, straight_rows = straight_run
    # the "kill": another process trains to the update-1 boundary and ends there
    code = (f"from hope_policy.ppo import HopePPOConfig; from hope_policy.train import HopeTrainConfig, train; "
            f"train(HopeTrainConfig.from_dict({tiny_config().to_dict()!r}), {str(tmp_path)!r}, progress=False, "
            f"max_updates=1)")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)
    rows = train(tiny_config(), tmp_path, resume=True, progress=False, max_updates=2)
    assert [r["update"] for r in rows] == [1, 2]
    assert [_without_timing(r) for r in rows] == [_without_timing(r) for r in straight_rows]
    a, b = load_hope_checkpoint(straight / "snapshot.pt"), load_hope_checkpoint(tmp_path / "snapshot.pt")
    assert a["updates"] == b["updates"] == 2
    for key in a["model"]:
        assert torch.equal(a["model"][key], b["model"][key]), key
    for part in ("critic_target",):
        for key, value in a["ppo"][part].items():
            assert torch.equal(value, b["ppo"][part][key]), key
    for branch, stats in a["obs_norm"].items():
        np.testing.assert_array_equal(stats["mean"], b["obs_norm"][branch]["mean"])
        np.testing.assert_array_equal(stats["m2"], b["obs_norm"][branch]["m2"])


def test_sigusr1_stops_a_run_after_its_update_with_a_snapshot_and_the_resume_repeats_the_straight_run(
        straight_run, tmp_path, monkeypatch):
    """SIGUSR1 during update 1 of a run snapshotting every 5 updates: a snapshot at update 1, TrainingStopped with
    the shell's status for the signal, the handlers back as they were; the resume repeats the uninterrupted run."""
    _, straight_rows = straight_run
    real_step = HopeTrainer.step
    monkeypatch.setattr(HopeTrainer, "step", signal_after(real_step, signal.SIGUSR1, lambda t: t.updates == 1))
    config = dataclasses.replace(tiny_config(), snapshot_every=5)
    with guarded_stop_signals() as guard:
        with pytest.raises(TrainingStopped, match="stopped by SIGUSR1 after update 1 ") as stopped:
            train(config, tmp_path, progress=False, max_updates=2)
        assert signal.getsignal(signal.SIGUSR1) is guard and not guard.received  # restored; the run caught it
    assert stopped.value.exit_status == 128 + signal.SIGUSR1
    assert load_hope_checkpoint(tmp_path / "snapshot.pt")["updates"] == 1 and len(json_rows(tmp_path)) == 1
    monkeypatch.setattr(HopeTrainer, "step", real_step)
    rows = train(config, tmp_path, resume=True, progress=False, max_updates=2)
    assert [_without_timing(r) for r in rows] == [_without_timing(r) for r in straight_rows]


def test_a_run_writes_its_files_and_stops_after_its_episode_budget(tmp_path):
    rows = train(tiny_config(episodes=2), tmp_path, progress=False)
    assert rows[-1]["episodes"] >= 2 and all(r["episodes"] < 2 for r in rows[:-1])
    assert not (tmp_path / "snapshot.pt").exists()  # a finished run keeps only its outputs
    final = load_hope_checkpoint(tmp_path / "final.pt")
    assert final["episodes"] == rows[-1]["episodes"] and "ppo" not in final
    assert sorted(final["obs_norm"]) == ["lidar", "target"]  # the mask is not normalised
    assert final["obs_norm"]["lidar"]["count"] > 0
    lines = (tmp_path / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["update"] for line in lines] == [r["update"] for r in rows]
    written = json.loads((tmp_path / "config.json").read_text())
    assert written == json.loads(json.dumps(tiny_config(episodes=2).to_dict()))
    assert list(tmp_path.glob("events.out.tfevents.*"))


def test_a_finished_run_drops_its_snapshot_and_resuming_it_trains_nothing(tmp_path):
    config = tiny_config(episodes=40)
    train(config, tmp_path, progress=False, max_updates=1)
    assert (tmp_path / "snapshot.pt").exists() and not (tmp_path / "final.pt").exists()
    rows = train(config, tmp_path, resume=True, progress=False)
    assert rows[-1]["episodes"] >= 40 and len(rows) > 1
    assert (tmp_path / "final.pt").exists() and not (tmp_path / "snapshot.pt").exists()
    final = (tmp_path / "final.pt").read_bytes()
    (tmp_path / "snapshot.pt").write_bytes(b"left by a kill between final.pt and its removal")
    again = train(config, tmp_path, resume=True, progress=False)
    assert again == json_rows(tmp_path) and [r["update"] for r in again] == [r["update"] for r in rows]
    assert not (tmp_path / "snapshot.pt").exists() and (tmp_path / "final.pt").read_bytes() == final


def json_rows(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "metrics.jsonl").read_text().splitlines()]


def test_cli_refuses_an_existing_run_and_a_missing_snapshot(straight_run, tmp_path, capsys):
    straight, _ = straight_run
    line = one_error_line(capsys, main, ["--out", str(straight)])
    assert "already holds a training run" in line and "--resume" in line
    line = one_error_line(capsys, main, ["--out", str(tmp_path), "--resume"])
    assert "nothing to resume" in line


def test_cli_refuses_what_it_cannot_train(tmp_path, capsys):
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "n"), "--num-envs", "3"])
    assert "multiple of num_envs" in line
    assert not list(tmp_path.iterdir())


def test_resume_refuses_a_different_config(straight_run, tmp_path, capsys):
    straight, _ = straight_run
    with pytest.raises(CheckpointError, match="seed: checkpoint has 0, expected 5"):
        train(tiny_config(seed=5), straight, resume=True, progress=False, max_updates=3)


def test_cli_config_file_fields_are_checked(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"ppo": {"minibatch": 32}}')
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "run"), "--config", str(bad)])
    assert "minibatch" in line
    bad.write_text("[1, 2]")
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "run"), "--config", str(bad)])
    assert f"{bad}: expected a JSON object" in line
    assert not (tmp_path / "run").exists()


def test_collect_stores_the_takeover_chunk_on_takeover_steps_and_the_policy_action_otherwise():
    from hope_policy.train import HopeTrainer

    config = dataclasses.replace(tiny_config(), num_envs=8, ppo=HopePPOConfig(batch_size=256, minibatch_size=8))
    trainer = HopeTrainer(config)  # 32 steps of 8 envs: takeovers happen (about one step in sixteen)
    played, infos = [], []
    step = trainer.envs.step

    def recording_step(actions):
        played.append(np.array(actions))
        result = step(actions)
        infos.append(result[4])
        return result

    trainer.envs.step = recording_step
    roll = trainer.collect()
    takeover = np.stack([info["rs_takeover"] for info in infos])
    assert takeover.any() and not takeover.all()
    chunks = np.stack([info["executed_action"] for info in infos])
    np.testing.assert_array_equal(roll["action"][takeover], chunks[takeover].astype(np.float32))
    np.testing.assert_array_equal(roll["action"][~takeover], np.stack(played)[~takeover])
    with torch.no_grad():  # the stored log-probability is the Gaussian's at the stored action
        obs = {k: torch.tensor(v[5]) for k, v in roll["obs"].items()}
        expected = trainer.model.distribution(obs).log_prob(torch.tensor(roll["action"][5])).sum(-1)
    np.testing.assert_allclose(roll["log_prob"][5], expected.numpy(), rtol=1e-6)


def test_a_holdout_run_trains_without_every_kth_benchmark_scene():
    """``holdout_every`` leaves the same scenes out as the NeuralParker trainer's (`np_policy.train.training_scenes`,
    compared with the benchmark's own list); bad values are one error naming the field."""
    from hope_policy.train import HopeTrainer
    from np_sim.benchmarks import load_benchmark
    from np_sim.errors import ConfigError

    every = [s.name for s in load_benchmark("factorial", "train")]
    trainer = HopeTrainer(tiny_config(holdout_every=4))
    assert [s.name for s in trainer.envs.core.scenes] == [n for k, n in enumerate(every) if k % 4 != 3]
    assert HopeTrainConfig.from_dict(tiny_config(holdout_every=4).to_dict()).holdout_every == 4
    assert HopeTrainConfig.from_dict({}).holdout_every == 0  # a checkpoint written before the field
    with pytest.raises(ConfigError, match=r"HopeTrainConfig.holdout_every: expected 0 or an integer >= 2, got 1"):
        tiny_config(holdout_every=1)
