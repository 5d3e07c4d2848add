"""experiments.planners and experiments.evaluate keep each finished episode (experiments.progress): a killed run
resumes where it stopped and writes the records an uninterrupted run writes; a resume with other settings, or
without an interrupted run to resume, is refused."""

from __future__ import annotations

import json

import pytest

from experiments import evaluate, planners
from experiments.planners import DEFAULT_CHECKPOINT, main
from experiments.progress import PROGRESS_FILE, SETTINGS_FILE
from np_policy.planner import NeuralParkerPlanner
from np_sim.errors import ConfigError

pytestmark = pytest.mark.skipif(not DEFAULT_CHECKPOINT.exists(), reason="no shipped NeuralParker checkpoint")
TIMED = ("plan_time_ms", "guide_time_ms")


def _untimed(records):
    return [{k: v for k, v in r.items() if k not in TIMED} for r in records]


def _killed_at(monkeypatch, module, name, episode):
    """Make ``module.name`` (one episode's planning) raise KeyboardInterrupt at its ``episode``-th call, a kill in
    the middle of a run; returns the real function and the list of calls."""
    real, calls = getattr(module, name), []

    def planned(*args):
        calls.append(args)
        if len(calls) == episode:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(module, name, planned)
    return real, calls


def _run(out, **kwargs):
    # NeuralParker only: its records repeat exactly; a search's stop at its wall-time budget could differ under load
    return planners.run("factorial", ["neuralparker"], out=out, limit=5, progress=False, **kwargs)


def test_a_killed_run_resumes_and_writes_the_uninterrupted_records(tmp_path, monkeypatch):
    straight = _run(tmp_path / "straight")
    real, calls = _killed_at(monkeypatch, planners, "episode_rows", 4)
    with pytest.raises(KeyboardInterrupt):
        _run(tmp_path / "killed")
    progress = tmp_path / "killed" / PROGRESS_FILE
    assert len(progress.read_text().splitlines()) == 3 and not (tmp_path / "killed" / "records.csv").exists()
    progress.write_text(progress.read_text() + '{"episode": [0, 3], "rows": [{"scene')  # torn by the kill
    monkeypatch.setattr(planners, "episode_rows", lambda *args: calls.append(args) or real(*args))
    calls.clear()
    resumed = _run(tmp_path / "killed", resume=True)
    assert len(calls) == 2  # episodes 4 and 5 only (the torn one is planned again)
    assert _untimed(resumed["records"]) == _untimed(straight["records"])
    assert (tmp_path / "killed" / "records.csv").read_text().count("\n") == 6
    assert not (tmp_path / "killed" / PROGRESS_FILE).exists() and not (tmp_path / "killed" / SETTINGS_FILE).exists()
    config = json.loads((tmp_path / "killed" / "config.json").read_text())
    assert config["episodes"] == 5 and config["methods"] == ["neuralparker"]


def test_a_resume_with_other_settings_names_them_and_changes_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(planners, "episode_rows", lambda *args: (_ for _ in ()).throw(KeyboardInterrupt))
    with pytest.raises(KeyboardInterrupt):
        _run(tmp_path / "run")
    before = {p.name: p.read_bytes() for p in (tmp_path / "run").iterdir()}
    with pytest.raises(ConfigError, match=r"started with other settings: ompl_seed: 0, now 7"):
        _run(tmp_path / "run", resume=True, ompl_seed=7)
    assert {p.name: p.read_bytes() for p in (tmp_path / "run").iterdir()} == before


@pytest.mark.parametrize("make, argv, message", [
    (False, ["--resume"], "argument --resume: needs --out, the folder of the interrupted run"),
    (True, ["--resume", "--out", "{finished}"], "exists and is not empty (an earlier run's results are kept); give a "
                                                "new or empty folder, or omit --out for a fresh timestamped one (and "
                                                "it holds no interrupted run to resume)"),
])
def test_resume_needs_an_interrupted_run_in_out(tmp_path, capsys, make, argv, message):
    finished = tmp_path / "finished"
    if make:
        finished.mkdir()
        (finished / "records.csv").write_text("scene\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["--methods", "hybrid_astar", "--limit", "1", *(a.format(finished=finished) for a in argv)])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(message)


def test_a_killed_evaluation_resumes_and_writes_the_uninterrupted_records(tmp_path, monkeypatch):
    def run(out, **kwargs):
        return evaluate.evaluate("factorial", [DEFAULT_CHECKPOINT], out=out, limit=4, progress=False, **kwargs)

    straight = run(tmp_path / "straight")
    real, calls = _killed_at(monkeypatch, evaluate, "episode_row", 3)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path / "killed")
    monkeypatch.setattr(evaluate, "episode_row", lambda *args: calls.append(args) or real(*args))
    calls.clear()
    resumed = run(tmp_path / "killed", resume=True)
    assert len(calls) == 2 and _untimed(resumed["records"]) == _untimed(straight["records"])
    assert evaluate.main(["--checkpoints", str(DEFAULT_CHECKPOINT), "--limit", "1", "--out", str(tmp_path / "cli"),
                          "--resume"])["records"]  # --resume on a new folder is a fresh run


def test_the_validation_split_plans_seeded_starts_on_the_training_scenes(tmp_path):
    from np_sim.benchmarks import load_benchmark, validation_starts

    result = evaluate.main(["--checkpoints", str(DEFAULT_CHECKPOINT), "--split", "validation",
                            "--starts-per-scene", "2", "--limit", "3", "--out", str(tmp_path / "val")])
    train = load_benchmark("factorial", "train")
    assert [(r["scene"], r["start_id"]) for r in result["records"]] == [
        (train[0].name, 0), (train[0].name, 1), (train[1].name, 0)]
    config = json.loads((tmp_path / "val" / "config.json").read_text())
    assert config["split"] == "validation" and config["starts_per_scene"] == 2
    planner = NeuralParkerPlanner.from_checkpoint(DEFAULT_CHECKPOINT, benchmark="factorial")
    plan = planner.plan(train[1], validation_starts("factorial", per_scene=2)[1, 0])
    assert result["records"][2]["success"] == int(plan.success)
    assert result["records"][2]["L"] == pytest.approx(plan.metrics()[0], nan_ok=True)


def test_the_holdout_split_plans_only_the_scenes_the_checkpoint_was_trained_without(tmp_path, capsys):
    from np_policy.checkpoint import load_checkpoint, save_checkpoint
    from np_sim.benchmarks import load_benchmark

    payload = load_checkpoint(DEFAULT_CHECKPOINT)
    payload["config"]["holdout_every"] = 4
    held = save_checkpoint(tmp_path / "held.pt", payload)
    result = evaluate.main(["--checkpoints", str(held), "--split", "holdout", "--starts-per-scene", "1",
                            "--limit", "2", "--out", str(tmp_path / "out")])
    train = load_benchmark("factorial", "train")
    assert [r["scene"] for r in result["records"]] == [train[3].name, train[7].name]
    assert json.loads((tmp_path / "out" / "config.json").read_text())["holdout_every"] == 4
    with pytest.raises(SystemExit) as exit_info:  # the shipped checkpoint trained on every scene
        evaluate.main(["--checkpoints", str(DEFAULT_CHECKPOINT), "--split", "holdout", "--limit", "1",
                       "--out", str(tmp_path / "none")])
    assert exit_info.value.code == 2
    assert "--split holdout: the checkpoints must all have been trained with the same" in capsys.readouterr().err


def test_the_planners_holdout_split_reads_the_learned_methods_checkpoints(tmp_path, capsys):
    """``experiments.planners --split holdout``: the scenes the adapted-HOPE checkpoint was trained without; a
    NeuralParker checkpoint beside it that left out other scenes (none) is one error naming both."""
    from hope_policy.checkpoint import save_hope_checkpoint
    from np_policy.checkpoint import load_checkpoint
    from np_sim.benchmarks import load_benchmark

    payload = load_checkpoint("checkpoints/runs/factorial_hope_seed0/final.pt")
    payload["config"]["holdout_every"] = 4
    hope = save_hope_checkpoint(tmp_path / "hope.pt", payload)
    result = main(["--benchmark", "factorial", "--methods", "hope", "--hope-checkpoint", str(hope), "--split",
                   "holdout", "--starts-per-scene", "1", "--limit", "2", "--out", str(tmp_path / "out")])
    train = load_benchmark("factorial", "train")
    assert [r["scene"] for r in result["records"]] == [train[3].name, train[7].name]
    assert json.loads((tmp_path / "out" / "config.json").read_text())["holdout_every"] == 4
    with pytest.raises(SystemExit) as exit_info:
        main(["--benchmark", "factorial", "--methods", "hope", "neuralparker", "--hope-checkpoint", str(hope),
              "--split", "holdout", "--limit", "1", "--out", str(tmp_path / "mixed")])
    assert exit_info.value.code == 2
    error = capsys.readouterr().err
    assert "--split holdout: the checkpoints must all have been trained with the same holdout_every" in error
    assert str(DEFAULT_CHECKPOINT) in error and str(hope) in error
