"""Training loop: tiny-budget smoke run, kill-and-resume equality on CPU, checkpoint errors."""

import hashlib
import os
import subprocess
import sys
import json
import re
import shutil
import signal

import pytest
import torch

from np_policy.checkpoint import LEGACY_FORMAT, CheckpointError, load_checkpoint, save_checkpoint
from np_policy.checkpoint import main as checkpoint_main
from np_policy import train as train_module
from np_policy.train import TrainConfig, Trainer, benchmark_defaults, main, train
from np_sim.errors import ConfigError
from stop_helpers import guarded_stop_signals, signal_after

TINY = {"benchmark": "examples", "seed": 3, "curriculum_pool": 32,
        "ppo": {"num_train_envs": 16, "num_test_envs": 4, "selection_episodes": 8, "steps_per_collect": 256,
                "steps_per_epoch": 256,
                "batch_size": 128, "repeats": 2, "epochs": 4, "snapshot_every_epochs": 2}}


def _rows(path):
    rows = [json.loads(line) for line in (path / "metrics.jsonl").read_text().splitlines()]
    for r in rows:
        for key in ("steps_per_s", "epoch_s", "collect_s", "update_s", "selection_s"):
            r.pop(key)
    return rows


def _as_v1(path):
    """Rewrite a checkpoint as the format-v1 writer did (pickled numpy arrays, no digest)."""
    payload = load_checkpoint(path)
    torch.save({"format": LEGACY_FORMAT, **payload}, path)


def _tree(folder):
    """SHA-256 of every file under ``folder``, by relative path."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """A tiny two-epoch run made by the command line: (its folder, its --config file, the rows main returned)."""
    root = tmp_path_factory.mktemp("finished")
    cfg = root / "tiny.json"
    cfg.write_text(json.dumps({k: v for k, v in TINY.items() if k not in ("benchmark", "seed")}))
    rows = main(["--benchmark", "examples", "--config", str(cfg), "--epochs", "2", "--out", str(root / "run")])
    return root / "run", cfg, rows


def test_resume_gives_the_same_curve_as_an_uninterrupted_run(tmp_path, capsys):
    """Also from a snapshot written in format v1 and converted by the upgrade command, and with a torn last line
    in metrics.jsonl (a crash in the middle of a write), which is discarded with a warning."""
    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "straight", progress=False)
    train(config, tmp_path / "killed", epochs=2, progress=False)  # "killed" after the epoch-2 snapshot
    _as_v1(tmp_path / "killed" / "snapshot.pt")
    with pytest.raises(CheckpointError, match="np_policy.checkpoint upgrade"):
        train(config, tmp_path / "killed", resume=True, progress=False)
    assert checkpoint_main(["upgrade", str(tmp_path / "killed" / "snapshot.pt")]) == 0
    metrics = tmp_path / "killed" / "metrics.jsonl"
    metrics.write_text(metrics.read_text() + '{"epoch": 3, "env_st')
    train(config, tmp_path / "killed", resume=True, progress=False)
    assert f"warning: {metrics}: discarding its torn last line 3" in capsys.readouterr().err
    a, b = _rows(tmp_path / "straight"), _rows(tmp_path / "killed")
    assert len(a) == len(b) == 4
    assert a == b
    wa = load_checkpoint(tmp_path / "straight" / "best.pt")["model"]
    wb = load_checkpoint(tmp_path / "killed" / "best.pt")["model"]
    assert all(torch.equal(wa[k], wb[k]) for k in wa)
    assert not (tmp_path / "straight" / "snapshot.pt").exists() and not (tmp_path / "killed" / "snapshot.pt").exists()


def test_a_run_resumes_after_a_field_with_a_default_was_added_to_the_config(tmp_path):
    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "run", epochs=2, progress=False)
    snapshot = tmp_path / "run" / "snapshot.pt"
    payload = load_checkpoint(snapshot)
    for key in ("site_recorded_share", "site_recorded_skip"):  # as a snapshot written before these fields existed
        del payload["config"][key]
    payload["config"]["seed"] = 4  # a real difference stops the resume
    save_checkpoint(snapshot, payload)
    with pytest.raises(CheckpointError, match="seed: checkpoint has 4, expected 3"):
        train(config, tmp_path / "run", resume=True, progress=False)
    payload["config"]["seed"] = 3
    save_checkpoint(snapshot, payload)
    rows = train(config, tmp_path / "run", resume=True, progress=False)
    assert [r["epoch"] for r in rows] == [1, 2, 3, 4]


def test_cli_writes_metrics_curves_and_checkpoints(finished_run):
    run, _, rows = finished_run
    assert [r["epoch"] for r in rows] == [1, 2]
    for r in rows:  # the epoch's wall-clock split into its phases
        phases = r["collect_s"] + r["update_s"] + r["selection_s"]
        assert min(r["collect_s"], r["update_s"], r["selection_s"]) > 0 and phases <= r["epoch_s"] < phases + 0.5
    for name in ("metrics.jsonl", "curves.png", "best.pt", "snapshot.pt", "config.json"):
        assert (run / name).stat().st_size > 0
    assert [json.loads(line)["epoch"] for line in (run / "metrics.jsonl").read_text().splitlines()] == [1, 2]
    names = sorted(p.name for p in run.iterdir())  # no temporary file left behind
    assert len(names) == 7 and names[3].startswith("events.out.tfevents.")
    assert names[:3] + names[4:] == ["best.pt", "config.json", "curves.png", "metrics.jsonl", "provenance.jsonl",
                                     "snapshot.pt"]
    best = load_checkpoint(run / "best.pt", expected_config=TrainConfig.from_dict(TINY | {"seed": 0}).to_dict())
    assert {"model", "config", "return_rms", "epoch", "selection_reward"} <= set(best)


@pytest.mark.parametrize("every_s, drawn", [(1e9, [2, 3, 4]), (0.0, [1, 2, 3, 4])])
def test_the_curves_are_redrawn_when_due_and_always_at_a_snapshot_and_the_end(tmp_path, monkeypatch, every_s, drawn):
    """Four epochs, a snapshot every two, stopped by SIGTERM during epoch 3: snapshots at 2 and 3, the end at 4."""
    epochs = []
    plot = train_module._plot_curves
    monkeypatch.setattr(train_module, "_plot_curves", lambda rows, *a: (epochs.append(rows[-1]["epoch"]),
                                                                        plot(rows, *a)))
    monkeypatch.setattr(train_module, "CURVES_EVERY_S", every_s)
    monkeypatch.setattr(train_module, "_train_epoch",
                        signal_after(train_module._train_epoch, signal.SIGTERM, lambda t: t.epoch == 3))
    config, run = TrainConfig.from_dict(TINY), tmp_path / "run"
    with guarded_stop_signals(), pytest.raises(train_module.TrainingStopped):
        train(config, run, progress=False, tensorboard=False)
    train(config, run, resume=True, progress=False, tensorboard=False)
    assert epochs == drawn and (run / "curves.png").stat().st_size > 0


def test_checkpoint_errors_name_the_file_and_the_difference(tmp_path):
    with pytest.raises(CheckpointError, match="checkpoint file not found"):
        load_checkpoint(tmp_path / "nope.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match=r"bad.pt: not a readable checkpoint"):
        load_checkpoint(bad)
    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "run", epochs=1, progress=False)
    other = TrainConfig.from_dict(TINY | {"env": {"connector": {"mode": "fixed"}}}).to_dict()
    with pytest.raises(CheckpointError, match=r"env.connector.mode: checkpoint has 'ensemble', expected 'fixed'"):
        load_checkpoint(tmp_path / "run" / "best.pt", expected_config=other)


def test_unknown_config_keys_are_errors():
    from np_sim.errors import ConfigError

    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['epohcs'\]"):
        TrainConfig.from_dict({"ppo": {"epohcs": 3}})


def test_benchmark_must_name_a_benchmark_or_scene_files(tmp_path):
    from np_policy.train import training_scenes
    from np_sim.errors import ConfigError

    with pytest.raises(ConfigError, match=r"TrainConfig.benchmark: expected one of .* got 'factorail'"):
        TrainConfig(benchmark="factorail")
    with pytest.raises(ConfigError, match=r"holds no \*.json scene files"):
        training_scenes(str(tmp_path))


def test_a_holdout_run_trains_without_every_kth_benchmark_scene():
    from np_policy.train import training_scenes
    from np_sim.benchmarks import load_benchmark
    from np_sim.errors import ConfigError

    every = [s.name for s in load_benchmark("topology", "train")]
    kept = [s.name for s in training_scenes("topology", 4)]
    assert len(kept) == 36 and kept == [n for k, n in enumerate(every) if k % 4 != 3]
    assert [s.name for s in training_scenes("topology")] == every
    trainer = Trainer(TrainConfig.from_dict(TINY | {"benchmark": "topology", "holdout_every": 4}), "unused")
    assert [s.name for s in trainer.scenes] == kept  # training and selection envs draw from these only
    assert [s.name for s in trainer.select_envs.core.scenes] == [s.name for s in trainer.envs.core.scenes] == kept
    assert TrainConfig.from_dict({"benchmark": "topology", "holdout_every": 4}).holdout_every == 4
    with pytest.raises(ConfigError, match=r"TrainConfig.holdout_every: expected 0 or an integer >= 2 .* got 1"):
        TrainConfig(benchmark="topology", holdout_every=1)
    with pytest.raises(ConfigError, match=r"TrainConfig.holdout_every: .* got 4 on 'examples'"):
        TrainConfig(benchmark="examples", holdout_every=4)


def test_site_defaults_are_the_papers_real_vehicle_configuration():
    from np_policy.train import merge_config
    from np_sim.errors import ConfigError
    from np_sim.site import SITE_OBSERVATION

    config = TrainConfig.from_dict(benchmark_defaults("site"))
    assert config.env.observation == SITE_OBSERVATION and not config.env.observation.use_lidar
    assert config.env.connector.mode == "fixed" and not config.curriculum.enabled
    footprint = TrainConfig.from_dict(merge_config(benchmark_defaults("site"), {"env": {"collision": "footprint"}}))
    assert footprint.env.collision == "footprint" and footprint.env.connector.mode == "fixed"
    with pytest.raises(ConfigError, match="curriculum must be off"):
        TrainConfig(benchmark="site")


def test_site_training_pool_pairs_each_scene_with_a_valid_start():
    from np_policy.train import PairedStartSampler
    from np_sim.clips import load_clips, training_pool
    from np_sim.collision import path_valid
    from np_sim.site import SITE_OBSERVATION

    clips = load_clips("eval")[:3]  # the mechanics only; training uses the training clips
    scenes, starts = training_pool(4, seed=5, clips=clips)
    again, starts_again = training_pool(4, seed=5, clips=clips)
    assert [s.to_dict() for s in scenes] == [s.to_dict() for s in again] and (starts == starts_again).all()
    for scene, start in zip(scenes, starts):
        assert len(scene.obstacles) <= SITE_OBSERVATION.max_obstacles
        assert path_valid(scene, start[None], convention="footprint")
    sampler = PairedStartSampler(starts)
    assert (sampler(None, [2, 0]) == starts[[2, 0]]).all()


def test_init_warm_starts_a_new_run_under_another_convention(tmp_path):
    train(TrainConfig.from_dict(TINY), tmp_path / "base", epochs=1, progress=False)
    source = tmp_path / "base" / "snapshot.pt"
    weights = load_checkpoint(source)["model"]
    footprint = TrainConfig.from_dict(TINY | {"env": {"collision": "footprint"}})
    trainer = Trainer(footprint, tmp_path / "fp")
    trainer.initialize_from(source)
    assert all(torch.equal(weights[k], v) for k, v in trainer.model.state_dict().items())
    assert trainer.epoch == 0 and trainer.updates == 0
    train(footprint, tmp_path / "fp", epochs=1, progress=False, init=source)
    run = load_checkpoint(tmp_path / "fp" / "snapshot.pt", expected_config=footprint.to_dict())
    assert run["epoch"] == 1 and run["init_checkpoint"]["path"] == str(source)
    assert run["init_checkpoint"]["config"]["env"]["collision"] == "reference_point"
    with pytest.raises(CheckpointError, match=r"observation.use_lidar: checkpoint has True, expected False"):
        train(TrainConfig.from_dict(TINY | {"env": {"observation": {"use_lidar": False}}}), tmp_path / "x",
              epochs=1, progress=False, init=source)
    with pytest.raises(ConfigError, match="give one of them"):
        train(footprint, tmp_path / "fp", resume=True, init=source, progress=False)


def test_the_site_pool_is_kept_in_the_run_folder_and_redrawn_when_its_settings_differ(tmp_path, monkeypatch):
    import np_sim.clips.resets as resets_module
    from np_sim.clips import cached_training_pool, load_clips

    clips = load_clips("eval")[:3]
    path = tmp_path / "site_pool.pkl"
    scenes, starts = cached_training_pool(path, 3, seed=5, clips=clips)
    drawn = []
    monkeypatch.setattr(resets_module, "training_pool", lambda *a, **k: drawn.append(a) or (scenes[:1], starts[:1]))
    again, starts_again = cached_training_pool(path, 3, seed=5)  # read back: no clips needed
    assert not drawn and [s.to_dict() for s in again] == [s.to_dict() for s in scenes]
    assert (starts_again == starts).all()
    cached_training_pool(path, 3, seed=6)  # another seed: drawn again
    assert drawn == [(3, 6)]
    path.write_bytes(b"not a pickle")
    cached_training_pool(path, 3, seed=5)  # unreadable: drawn again
    assert len(drawn) == 2
    cached_training_pool(path, 3, seed=5, recorded_share=0.5, recorded_clips=clips)  # recorded resets: drawn again
    assert len(drawn) == 3 and drawn[-1] == (3, 5)


def test_recorded_resets_are_a_site_option_drawn_from_the_difficult_training_clips(monkeypatch):
    import np_policy.train as train_module
    from np_sim.clips import load_clips

    site = benchmark_defaults("site")
    config = TrainConfig.from_dict(site | {"site_recorded_share": 0.5, "site_recorded_skip": 2})
    assert config.site_recorded_share == 0.5 and TrainConfig.from_dict(site).site_recorded_share == 0.0
    with pytest.raises(ConfigError, match="recorded resets exist on the site only, got benchmark 'factorial'"):
        TrainConfig(site_recorded_share=0.5)
    with pytest.raises(ConfigError, match=r"site_recorded_share: expected a share in \[0, 1\], got -0.1"):
        TrainConfig.from_dict(site | {"site_recorded_share": -0.1})
    with pytest.raises(ConfigError, match="site_recorded_skip: expected >= 0 clips, got -1"):
        TrainConfig.from_dict(site | {"site_recorded_skip": -1})
    clips = load_clips("eval")[:5]  # all difficult, standing in for the training split
    monkeypatch.setattr(train_module, "difficult_clips", lambda split: clips)
    assert [c.name for c in train_module.recorded_clips(2)] == [c.name for c in clips[2:]]
    with pytest.raises(ConfigError, match="5 leaves none of the 5 difficult training clips"):
        train_module.recorded_clips(5)


def test_the_curriculum_pool_can_cover_the_whole_lot():
    """curriculum_region='lot': the pool is drawn from the scenes with their boundary as start region, so its
    nearest starts lie by the bay (inside the geodesic distance of the start region's nearest start) while the
    env's scenes and the selection episodes keep their start regions; an unknown region is named."""
    import numpy as np
    import shapely

    from np_policy.train import curriculum_scenes, training_scenes
    from np_sim.curriculum import CurriculumStartSampler

    scenes = training_scenes("examples")[:2]
    assert curriculum_scenes(scenes, "start_region") == scenes
    lot = curriculum_scenes(scenes, "lot")
    for scene, whole in zip(scenes, lot):
        np.testing.assert_array_equal(whole.start_region, scene.boundary)
        assert whole.obstacles == scene.obstacles and np.array_equal(whole.target, scene.target)
    near = CurriculumStartSampler(lot, pool_size=64, seed=0)
    region = CurriculumStartSampler(scenes, pool_size=64, seed=0)
    assert np.all(near.distance[:, 0] < region.distance[:, 0])
    outside = [not shapely.Polygon(s.start_region).covers(shapely.Point(*p[:2])) for s, pool in zip(scenes, near.pool)
               for p in pool]
    assert any(outside)
    with pytest.raises(ConfigError, match=r"TrainConfig.curriculum_region: expected one of \('start_region', 'lot'\)"):
        TrainConfig(curriculum_region="everywhere")


def test_rerunning_a_finished_run_without_resume_changes_no_file(finished_run, capsys):
    run, cfg, _ = finished_run
    before = _tree(run)
    argv = ["--benchmark", "examples", "--config", str(cfg), "--out", str(run)]
    for extra in ([], ["--epochs", "1"], ["--init", str(run / "best.pt")]):
        with pytest.raises(SystemExit) as exit_info:
            main(argv + extra)
        assert exit_info.value.code == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {run}: already holds a training run (metrics.jsonl, snapshot.pt, best.pt)")
        assert "--resume" in err and "--overwrite" in err and len(err.strip().splitlines()) == 1
    with pytest.raises(SystemExit):  # resuming a run already at --epochs changes nothing either
        main(argv + ["--resume", "--epochs", "1"])
    assert "the snapshot is already at epoch 2" in capsys.readouterr().err
    assert [r["epoch"] for r in main(argv + ["--resume", "--epochs", "2"])] == [1, 2]  # nothing left to train
    assert _tree(run) == before


def test_overwrite_removes_the_run_files_and_keeps_the_rest(tmp_path):
    from np_policy.train import prepare_run_folder

    run = tmp_path / "run"
    run.mkdir()
    for name in ("metrics.jsonl", "snapshot.pt", "best.pt", "curves.png", "config.json", "notes.txt",
                 "events.out.tfevents.1796158492.host.11231.0"):
        (run / name).write_text(name)
    with pytest.raises(ConfigError, match="already holds a training run"):
        prepare_run_folder(run, resume=False, overwrite=False)
    assert len(list(run.iterdir())) == 7
    prepare_run_folder(run, resume=False, overwrite=True)
    assert [p.name for p in run.iterdir()] == ["notes.txt"]
    prepare_run_folder(tmp_path / "new", resume=False, overwrite=False)
    assert (tmp_path / "new").is_dir()
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="expected a run folder, found a file"):
        prepare_run_folder(tmp_path / "file", resume=False, overwrite=True)


def test_resume_tolerates_only_a_torn_last_metrics_line(finished_run, tmp_path, capsys):
    """The tear itself is discarded in the kill-and-resume test above; damage before the last line is an error."""
    run, _, _ = finished_run
    copy = tmp_path / "run"
    shutil.copytree(run, copy)
    metrics = copy / "metrics.jsonl"
    whole = metrics.read_text()
    metrics.write_text(whole + '{"epoch": 3, "env_steps": 7')
    rows = train(TrainConfig.from_dict(TINY | {"seed": 0}), copy, epochs=2, resume=True, progress=False)
    assert [r["epoch"] for r in rows] == [1, 2]
    assert f"warning: {metrics}: discarding its torn last line 3" in capsys.readouterr().err
    shutil.copy(copy / "best.pt", copy / "snapshot.pt")  # weights only: named, not a KeyError
    with pytest.raises(CheckpointError, match=r"snapshot.pt: not a training snapshot, it lacks \['best_reward'"):
        train(TrainConfig.from_dict(TINY | {"seed": 0}), copy, epochs=2, resume=True, progress=False)
    shutil.copy(run / "snapshot.pt", copy / "snapshot.pt")
    metrics.write_text('{"epoch": 1}\n{"epo\n{"epoch": 2}\n')
    with pytest.raises(CheckpointError, match=r"metrics.jsonl: line 2 is not a metrics row"):
        train(TrainConfig.from_dict(TINY | {"seed": 0}), copy, epochs=2, resume=True, progress=False)


@pytest.mark.parametrize("args, message", [
    (["--epochs", "0"], r"--epochs: expected an integer from 1 to ppo.epochs=4 .*got 0"),
    (["--epochs", "-2"], r"--epochs: expected an integer from 1 to ppo.epochs=4 .*got -2"),
    (["--epochs", "5"], r"--epochs: expected an integer from 1 to ppo.epochs=4 .*got 5"),
    (["--resume"], r"nothing to resume, no snapshot.pt in it"),
    (["--resume", "--overwrite"], r"give one"),
])
def test_bad_arguments_are_one_error_line_and_write_nothing(tmp_path, capsys, args, message):
    cfg = tmp_path / "tiny.json"
    cfg.write_text(json.dumps({k: v for k, v in TINY.items() if k not in ("benchmark", "seed")}))
    with pytest.raises(SystemExit) as exit_info:
        main(["--benchmark", "examples", "--config", str(cfg), "--out", str(tmp_path / "run"), *args])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1
    assert re.search(message, err), err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("content, message", [
    ("[1, 2]", r"tiny.json: expected a JSON object of TrainConfig fields, got a list"),
    ('{"ppo": {"epochs": 2.5}}', r"TrainConfig.ppo.epochs: expected an integer, got 2.5"),
    ('{"seed": 1, "ppo": {"epohcs": 3}}', r"unknown key\(s\) \['epohcs'\]"),
    ('{"ppo": [1]}', r"TrainConfig.ppo: expected a mapping"),
    ("{not json", r"tiny.json: not a readable JSON file"),
])
def test_bad_config_files_are_one_error_line(tmp_path, capsys, content, message):
    cfg = tmp_path / "tiny.json"
    cfg.write_text(content)
    with pytest.raises(SystemExit) as exit_info:
        main(["--benchmark", "examples", "--config", str(cfg), "--out", str(tmp_path / "run")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1 and re.search(message, err), err
    assert not (tmp_path / "run").exists()


def _scalars(run):
    """TensorBoard scalars under ``run`` as read back by tensorboard's own EventAccumulator: {tag: [(step, value)]}."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    accumulator = EventAccumulator(str(run), size_guidance={"scalars": 0})
    accumulator.Reload()
    return {tag: [(e.step, e.value) for e in accumulator.Scalars(tag)] for tag in accumulator.Tags()["scalars"]}


def _assert_events_equal_metrics(run):
    """Every metrics.jsonl field but ``epoch`` and the ``device`` text is one TensorBoard tag holding each epoch
    once, with the row's value (stored as float32 by TensorBoard)."""
    import numpy as np

    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    scalars = _scalars(run)
    assert all(r["device"] == "cpu" for r in rows)
    assert set(scalars) == set(rows[0]) - {"epoch", "device"}
    for tag, points in scalars.items():
        assert [step for step, _ in points] == [r["epoch"] for r in rows], tag
        np.testing.assert_array_equal([value for _, value in points], np.float32([r[tag] for r in rows]), tag)


def test_a_finished_run_drops_its_snapshot_and_resuming_it_says_it_is_finished(tmp_path, capsys):
    """Reaching ppo.epochs removes snapshot.pt; --resume then trains nothing, changes nothing and prints that the
    run is finished; a snapshot left by a kill between the last row and its removal is removed then; the run's
    config.json must still match."""
    cfg = tmp_path / "tiny.json"
    cfg.write_text(json.dumps({k: v for k, v in TINY.items() if k not in ("benchmark", "seed")}))
    argv = ["--benchmark", "examples", "--config", str(cfg), "--out", str(tmp_path / "run")]
    rows = main(argv + ["--epochs", "2"])
    run = tmp_path / "run"
    assert [r["epoch"] for r in rows] == [1, 2] and (run / "snapshot.pt").exists()
    assert "stopped at epoch 2 of 4; continue it with --resume" in capsys.readouterr().out
    stopped = load_checkpoint(run / "snapshot.pt")
    rows = main(argv + ["--resume"])
    assert [r["epoch"] for r in rows] == [1, 2, 3, 4] and not (run / "snapshot.pt").exists()
    assert f"{run}: finished at epoch 4 of 4" in capsys.readouterr().out
    before = _tree(run)
    assert [r["epoch"] for r in main(argv + ["--resume"])] == [1, 2, 3, 4]
    assert f"{run}: finished at epoch 4 of 4" in capsys.readouterr().out
    assert _tree(run) == before
    save_checkpoint(run / "snapshot.pt", stopped)  # a kill after the last row, before the snapshot was removed
    assert [r["epoch"] for r in main(argv + ["--resume", "--epochs", "3"])] == [1, 2, 3, 4]
    assert _tree(run) == before
    with pytest.raises(SystemExit) as exit_info:
        main(argv[:-2] + ["--seed", "5", "--out", str(run), "--resume"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {run / 'config.json'}: ") and "seed: checkpoint has 0, expected 5" in err
    with pytest.raises(SystemExit):  # without --resume a finished run is still refused
        main(argv)
    assert "already holds a training run (metrics.jsonl, best.pt)" in capsys.readouterr().err


def test_sigterm_stops_a_run_after_its_epoch_with_a_snapshot_and_the_resume_repeats_the_straight_run(
        finished_run, tmp_path, capsys, monkeypatch):
    """SIGTERM during epoch 1 (snapshots every 2 epochs): the run writes a snapshot at epoch 1, exits with status
    143 (128 + SIGTERM) and one line saying so; --resume to epoch 2 then gives the uninterrupted two-epoch run's
    rows and weights (``finished_run``, the same command without the signal), bit for bit."""
    straight, cfg, _ = finished_run
    argv = ["--benchmark", "examples", "--config", str(cfg), "--out", str(tmp_path / "run")]
    monkeypatch.setattr(train_module, "_train_epoch",
                        signal_after(train_module._train_epoch, signal.SIGTERM, lambda t: t.epoch == 1))
    run = tmp_path / "run"
    with guarded_stop_signals() as guard:
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert signal.getsignal(signal.SIGTERM) is guard and not guard.received  # restored; the run caught it
    assert exit_info.value.code == 143
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1] == (f"{run}: stopped by SIGTERM after epoch 1 of 4; snapshot.pt written, "
                                            "continue it with --resume")
    assert [r["epoch"] for r in _rows(run)] == [1] and load_checkpoint(run / "snapshot.pt")["epoch"] == 1
    main(argv + ["--resume", "--epochs", "2"])
    assert _rows(run) == _rows(straight)
    wa, wb = (load_checkpoint(folder / "best.pt")["model"] for folder in (straight, run))
    assert all(torch.equal(wa[k], wb[k]) for k in wa)


def test_tensorboard_events_hold_the_metrics_rows_and_a_resume_purges_what_the_kill_left(tmp_path):
    """The kill leaves epoch 3's row and scalars after the epoch-2 snapshot; the resume drops the row and purges
    the scalars from step 3 on, so every step shows once with the value in metrics.jsonl."""
    config = TrainConfig.from_dict(TINY)
    run = tmp_path / "run"
    train(config, run, epochs=2, progress=False)
    _assert_events_equal_metrics(run)
    at_two = load_checkpoint(run / "snapshot.pt")
    train(config, run, epochs=3, resume=True, progress=False)
    save_checkpoint(run / "snapshot.pt", at_two)  # killed during epoch 4, last snapshot at epoch 2
    assert [step for step, _ in _scalars(run)["train_return"]] == [1, 2, 3]
    train(config, run, resume=True, progress=False)
    assert len(list(run.glob("events.out.tfevents.*"))) == 3
    _assert_events_equal_metrics(run)
    assert [step for step, _ in _scalars(run)["train_return"]] == [1, 2, 3, 4]


def test_no_tensorboard_writes_no_events_and_a_later_logging_resume_fills_them_in(tmp_path):
    config = TrainConfig.from_dict(TINY)
    run = tmp_path / "run"
    train(config, run, epochs=2, progress=False, tensorboard=False)
    assert not list(run.glob("events.out.tfevents.*"))
    train(config, run, epochs=3, resume=True, progress=False)
    _assert_events_equal_metrics(run)
    assert [step for step, _ in _scalars(run)["policy_loss"]] == [1, 2, 3]


def test_init_from_a_checkpoint_saved_before_newer_config_fields_existed():
    """The shipped Factorial checkpoint predates the BEV observation fields: they take their defaults (off) and the
    warm start loads its weights."""
    source = "checkpoints/factorial_np_seed0.pt"
    stored = load_checkpoint(source)
    assert "use_bev" not in stored["config"]["env"]["observation"]
    trainer = Trainer(TrainConfig.from_dict(benchmark_defaults("factorial")), "unused")
    trainer.initialize_from(source)
    assert all(torch.equal(stored["model"][k], v) for k, v in trainer.model.state_dict().items())


def _clearance(scene, pose, vehicle):
    """Shapely distance (m) from the footprint at ``pose`` to the nearest obstacle or the boundary; −1 when it
    touches one or leaves the boundary."""
    import shapely

    body = shapely.Polygon(vehicle.footprint(pose))
    lot = shapely.Polygon(scene.boundary)
    obstacles = [shapely.Polygon(o.vertices) if hasattr(o, "vertices")
                 else shapely.Point(*o.center).buffer(o.radius, 256) for o in scene.obstacles]
    if not lot.contains(body) or any(o.intersects(body) for o in obstacles):
        return -1.0
    return min([lot.exterior.distance(body), *(o.distance(body) for o in obstacles)])


def test_a_training_margin_grows_the_body_of_the_training_envs_and_starts_but_not_the_checkpoints(tmp_path):
    """train_margin_m: every start the run draws (curriculum pool, selection episodes) keeps the margin from every
    obstacle and the boundary (shapely), a start closer than the margin is in collision in the training env, and
    the checkpoint keeps the real vehicle, so planners roll the policy out against the real body."""
    import numpy as np

    from np_sim.errors import StartInCollisionError

    margin = 0.1
    config = TrainConfig.from_dict(TINY | {"env": {"collision": "footprint"}, "train_margin_m": margin})
    trainer = Trainer(config, tmp_path / "run")
    real = config.env.vehicle
    pools = [(trainer.scenes[k], pose) for k, pool in enumerate(trainer.sampler.pool) for pose in pool]
    rng = np.random.default_rng(0)
    picks = rng.integers(len(trainer.scenes), size=16)
    selection = trainer.select_envs.core.sampler(rng, picks)
    pools += [(trainer.scenes[k], pose) for k, pose in zip(picks, selection)]
    assert min(_clearance(scene, pose, real) for scene, pose in pools) >= margin - 1e-6
    scene, pose = pools[0]
    plain = Trainer(TrainConfig.from_dict(TINY | {"env": {"collision": "footprint"}}), tmp_path / "plain")
    close = _pose_with_clearance(scene, real, 0.05, pose)
    k = trainer.scenes.index(scene)
    plain.envs.core.reset_envs(np.array([0]), rng, k, close)  # valid for the real body
    with pytest.raises(StartInCollisionError):
        trainer.envs.core.reset_envs(np.array([0]), rng, k, close)
    train(config, tmp_path / "run", epochs=1, progress=False)
    saved = load_checkpoint(tmp_path / "run" / "snapshot.pt")["config"]
    assert saved["train_margin_m"] == margin and saved["env"]["vehicle"]["width_m"] == real.width_m
    with pytest.raises(ConfigError, match="train_margin_m: a clearance margin needs env.collision 'footprint'"):
        TrainConfig.from_dict(TINY | {"train_margin_m": 0.2})
    with pytest.raises(ConfigError, match="train_margin_m: expected a finite number >= 0 m, got -0.1"):
        TrainConfig.from_dict(TINY | {"env": {"collision": "footprint"}, "train_margin_m": -0.1})


def _pose_with_clearance(scene, vehicle, wanted, pose):
    """``pose`` slid along its heading's normal until the footprint is about ``wanted`` m from the scene (bisection
    on the shapely clearance)."""
    import numpy as np

    normal = np.array([-np.sin(pose[2]), np.cos(pose[2]), 0.0])
    for direction in (normal, -normal):
        lo, hi = 0.0, 5.0
        if _clearance(scene, pose + hi * direction, vehicle) > 0:
            continue
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _clearance(scene, pose + mid * direction, vehicle) > wanted else (lo, mid)
        return pose + lo * direction
    raise AssertionError("no obstacle within 5 m on either side")


THREADS_PROBE = """
import json, sys, torch
import np_policy.train as t
seen = []
update = t.ppo_update
def counted(*args, **kwargs):
    seen.append(torch.get_num_threads())
    return update(*args, **kwargs)
t.ppo_update = counted
config = t.TrainConfig.from_dict({**json.loads(sys.argv[1]), "torch_threads": 1})
t.train(config, sys.argv[2], epochs=1, progress=False)
print(json.dumps(sorted(set(seen))))
"""


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: numba's default is one thread anyway")
def test_a_one_thread_run_updates_on_one_thread_after_numba_started_its_loops(tmp_path):
    """In a fresh process (numba's thread pool not started yet): the env steps run numba's parallel loops, whose
    OpenMP start used to raise torch's thread count to every core, so a 'torch_threads: 1' run updated on two."""
    out = subprocess.run([sys.executable, "-c", THREADS_PROBE, json.dumps(TINY), str(tmp_path / "run")],
                         capture_output=True, text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [1]


def test_rows_record_the_thread_counts_and_a_resume_on_others_warns(tmp_path, capsys, monkeypatch):
    import np_policy.train as train_module

    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "run", epochs=2, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()]
    assert all(r["torch_threads"] == torch.get_num_threads() >= 1 and r["numba_threads"] >= 1 for r in rows)
    capsys.readouterr()
    train(config, tmp_path / "run", epochs=3, resume=True, progress=False)  # the same counts: no warning
    assert "resuming on" not in capsys.readouterr().err
    monkeypatch.setattr(train_module, "thread_counts",
                        lambda: {"torch_threads": rows[-1]["torch_threads"] + 1, "numba_threads": 1})
    train(config, tmp_path / "run", epochs=4, resume=True, progress=False)
    assert "resuming on {'torch_threads': " in capsys.readouterr().err


def test_each_start_and_resume_is_logged_with_its_code_and_threads(tmp_path):
    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "run", epochs=2, progress=False)
    train(config, tmp_path / "run", epochs=3, resume=True, progress=False)
    starts = [json.loads(line) for line in (tmp_path / "run" / "provenance.jsonl").read_text().splitlines()]
    assert [s["epoch"] for s in starts] == [0, 2]
    assert all(s["git_commit"] and "git_modified" in s and s["torch_threads"] >= 1 for s in starts)
    train(config, tmp_path / "run", epochs=2, overwrite=True, progress=False)  # a new run: a new log
    assert len((tmp_path / "run" / "provenance.jsonl").read_text().splitlines()) == 1


def test_rows_record_shared_geometry_a_resume_keeps_it_and_turning_it_off_warns(tmp_path, capsys):
    config = TrainConfig.from_dict(TINY)
    train(config, tmp_path / "run", epochs=2, progress=False, shared_geometry=True)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()]
    assert [r["shared_geometry"] for r in rows] == [True, True]
    capsys.readouterr()
    train(config, tmp_path / "run", epochs=3, resume=True, progress=False)  # keeps what the rows record
    assert "shared_geometry" not in capsys.readouterr().err
    train(config, tmp_path / "run", epochs=4, resume=True, progress=False, shared_geometry=False)
    assert ("resuming with shared_geometry=False where the run so far trained with True"
            in capsys.readouterr().err)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()]
    assert [r["shared_geometry"] for r in rows] == [True, True, True, False]
