"""The reproduction sweep: plan and folder-state logic (dry run on a fake run root), the paper plan against the
shipped run folders, and a tiny sweep on a local Ray that is killed mid-way and finishes on restart.

``pytest -m sweep`` selects these tests; the Ray one starts real training subprocesses (about a minute)."""

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from functools import partial
from pathlib import Path

import pytest

from experiments import sweep as sweep_module
from experiments.sweep import main, run_environment, run_gpus, stop_trainers, task_verdict, train_argv
from np_policy.checkpoint import load_checkpoint
from experiments.sweep_plan import (PAPER_PLAN, active_trainers, configuration_epoch_s, estimate_hours, expand,
                                    format_table, load_plan, metrics_rows, metrics_values, resolved_config,
                                    run_state)

pytestmark = pytest.mark.sweep
REPO = Path(__file__).resolve().parents[2]
TINY = {"curriculum_pool": 8, "env": {"episode": {"max_arcs": 20}},
        "ppo": {"num_train_envs": 4, "num_test_envs": 2, "selection_episodes": 2, "steps_per_collect": 32,
                "steps_per_epoch": 32, "batch_size": 32, "repeats": 1, "epochs": 2, "snapshot_every_epochs": 1}}


def _plan(folder: Path, recipe: dict, epoch_s: float | None = None) -> Path:
    """A plan file with two configurations on the examples scenes (ensemble and fixed connector) and a third one
    that is not available."""
    (folder / "recipe.json").write_text(json.dumps(recipe))
    (folder / "a.json").write_text("{}")
    (folder / "b.json").write_text(json.dumps({"env": {"connector": {"mode": "fixed"}}}))
    extra = {} if epoch_s is None else {"epoch_s": epoch_s}
    rows = [{"name": "a", "benchmark": "examples", "tables": ["main"], "config_file": "a.json",
             "run_name": "{name}_seed{seed}_lot", **extra},
            {"name": "b", "benchmark": "examples", "tables": ["connector"], "config_file": "b.json", **extra},
            {"name": "c", "benchmark": "examples", "tables": ["main"], "missing": "not built yet"}]
    (folder / "plan.json").write_text(json.dumps({"configurations": rows}))
    return folder / "plan.json"


def _fake_run(folder: Path, epochs_done: int, *, best=True, snapshot=True, config=None, torn=False) -> None:
    folder.mkdir(parents=True)
    lines = [json.dumps({"epoch": e, "train_return": 1.0}) for e in range(1, epochs_done + 1)]
    (folder / "metrics.jsonl").write_text("".join(line + "\n" for line in lines) + ('{"epoch": 9' if torn else ""))
    for name, present in (("best.pt", best), ("snapshot.pt", snapshot)):
        if present:
            (folder / name).write_bytes(b"x")
    if config is not None:
        (folder / "config.json").write_text(json.dumps(config))


def _states(text: str) -> dict[str, tuple[str, str]]:
    """{run name: (estimated hours, state)} from the dry-run table."""
    rows = {}
    for line in text.splitlines()[1:-1]:
        name, _tables, hours, state = line.split(maxsplit=3)
        rows[name] = (hours, state)
    return rows


def test_dry_run_lists_each_folder_state_and_the_compute_left(tmp_path, capsys):
    recipe = TINY | {"ppo": TINY["ppo"] | {"epochs": 10, "snapshot_every_epochs": 2}}
    plan = _plan(tmp_path, recipe, epoch_s=3600.0)  # one hour per epoch: hours left = epochs left
    root = tmp_path / "runs"
    a1 = resolved_config("examples", 1, recipe).to_dict()
    _fake_run(root / "a_seed0_lot", 10)                           # finished
    _fake_run(root / "a_seed1_lot", 5, config=a1)                 # interrupted: last snapshot at epoch 4 or later
    _fake_run(root / "b_seed0", 3, snapshot=False, torn=True)  # killed before its first snapshot
    _fake_run(root / "b_seed1", 2, config=a1)                 # holds configuration a, not b
    assert main(["--plan", str(plan), "--seeds", "0", "1", "--out", str(root), "--dry-run"]) == 0
    out = capsys.readouterr().out
    rows = _states(out)
    assert rows["a_seed0_lot"] == ("0.0", "finished (10 epochs)")
    assert rows["a_seed1_lot"] == ("6.0", "interrupted at epoch 5")  # 10 - 4
    assert rows["b_seed0"] == ("10.0", "started, no snapshot at epoch 3")  # the torn row 9 is not counted
    hours, state = rows["b_seed1"]
    assert state.startswith("config differs: env.connector.mode: folder has 'ensemble', plan has 'fixed'")
    assert rows["c_seed0"] == ("?", "not available yet: not built yet")
    assert out.splitlines()[-1].startswith("estimated compute left: 16.0 h")
    assert "not counting 2 run(s) not available yet" in out.splitlines()[-1]
    assert main(["--plan", str(plan), "--seeds", "1", "--only", "connector", "--out", str(root), "--dry-run"]) == 0
    assert list(_states(capsys.readouterr().out)) == ["b_seed1"]


def test_metrics_rows_keep_complete_objects_and_skip_torn_or_foreign_lines(tmp_path):
    path = tmp_path / "metrics.jsonl"
    assert metrics_rows(path) == [] and metrics_values(path, "epoch") == []  # no file yet: a run not started
    path.write_text('{"epoch": 1, "epoch_s": 80.5}\n7\n["epoch", 2]\n\n{"epoch": 2}\n{"epoch": "x"}\n{"epoch": 3, "ep')
    assert metrics_rows(path) == [{"epoch": 1, "epoch_s": 80.5}, {"epoch": 2}, {"epoch": "x"}]
    assert metrics_values(path, "epoch", int) == [1, 2]  # "x" is no epoch number
    assert metrics_values(path, "epoch_s") == [80.5]


def test_an_interrupted_run_is_estimated_at_its_own_median_epoch_time_and_a_new_one_at_its_siblings(tmp_path):
    recipe = TINY | {"ppo": TINY["ppo"] | {"epochs": 10, "snapshot_every_epochs": 2}}
    run, new = expand(load_plan(str(_plan(tmp_path, recipe, epoch_s=3600.0)))[0], [1, 2], tmp_path / "runs",
                      ["main"], tmp_path)[:2]
    _fake_run(run.run_dir, 4)
    assert configuration_epoch_s([run, new]) == {}          # no timed rows yet
    assert estimate_hours(run, run_state(run)) == 6.0      # four rows without epoch_s: the plan's hour per epoch
    rows = [{"epoch": e, "epoch_s": t} for e, t in enumerate([1800, 1800, 900, 1800, 7200, 1800], start=1)]
    (run.run_dir / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert estimate_hours(run, run_state(run)) == 4 * 0.5  # 10 - 6 epochs left at the median 1,800 s
    measured = configuration_epoch_s([run, new])
    assert measured == {"a": 1800.0}
    assert estimate_hours(new, run_state(new)) == 10.0 and estimate_hours(new, run_state(new), measured) == 5.0
    (run.run_dir / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows[:4]))
    assert configuration_epoch_s([run, new]) == {}          # four timed rows are too few to stand for a machine


def test_the_dry_run_says_how_to_stop_the_runs_training_now_without_losing_epochs(tmp_path):
    run = expand(load_plan(str(_plan(tmp_path, TINY)))[0], [0], tmp_path / "runs", ["main"], tmp_path)[0]
    _fake_run(run.run_dir, 1)
    idle = format_table([run], [run_state(run)]).splitlines()
    assert idle[-1].startswith("estimated compute left")
    state = run_state(run, {run.run_dir.resolve(): 4321})
    assert (state.kind, state.detail, state.pid) == ("training now", "pid 4321", 4321)
    assert format_table([run], [state]).splitlines()[-1] == (
        "to stop the runs training now after the epoch (update) in progress, with a snapshot the sweep resumes: "
        "kill -USR1 4321")


def test_each_state_gets_the_train_flags_that_continue_it(tmp_path):
    plan = _plan(tmp_path, TINY)
    run = expand(load_plan(str(plan))[0], [0], tmp_path / "runs", ["main"], tmp_path)[0]

    def flags():
        return [a for a in train_argv(run, tmp_path / "c.json") if a in ("--resume", "--overwrite")]

    assert flags() == []                                  # not started: a plain new run
    _fake_run(run.run_dir, 0, best=False, snapshot=False)  # killed in its first epoch: an empty metrics.jsonl
    assert run_state(run).kind == "started, no snapshot" and flags() == ["--overwrite"]
    (run.run_dir / "snapshot.pt").write_bytes(b"x")
    assert run_state(run).kind == "interrupted" and flags() == ["--resume"]


def test_a_neuralparker_task_given_a_gpu_trains_on_it_and_an_adapted_hope_task_gets_none(tmp_path):
    runs = {r.config.trainer: r for r in expand(PAPER_PLAN, [0], tmp_path, ["main"])}
    np_run, hope_run = runs["np_policy.train"], runs["hope_policy.train"]
    assert "--device" not in train_argv(np_run, tmp_path / "c.json")      # no GPU: the trainer's default, the CPU
    argv = train_argv(np_run, tmp_path / "c.json", gpus=1.0)
    assert argv[argv.index("--device") + 1] == "cuda"
    assert run_gpus(np_run, 1.0) == 1.0 and run_gpus(hope_run, 1.0) == 0.0
    assert "--device" not in train_argv(hope_run, tmp_path / "c.json", gpus=1.0)


def test_shared_geometry_starts_new_neuralparker_runs_with_it_and_leaves_resumed_runs_as_they_were(tmp_path):
    runs = {r.config.trainer: r for r in expand(PAPER_PLAN, [0], tmp_path, ["main"])}
    np_run, hope_run = runs["np_policy.train"], runs["hope_policy.train"]
    assert "--shared-geometry" not in train_argv(np_run, tmp_path / "c.json")
    assert "--shared-geometry" in train_argv(np_run, tmp_path / "c.json", shared_geometry=True)
    assert "--shared-geometry" not in train_argv(hope_run, tmp_path / "c.json", shared_geometry=True)
    _fake_run(np_run.run_dir, 3, best=True, snapshot=True)
    argv = train_argv(np_run, tmp_path / "c.json", shared_geometry=True)
    assert "--resume" in argv and "--shared-geometry" not in argv  # the trainer keeps what the rows record


def test_a_run_trains_on_as_many_torch_and_numba_threads_as_it_has_cpus(monkeypatch):
    monkeypatch.setenv("OMP_NUM_THREADS", "8")
    monkeypatch.setenv("SOMETHING_ELSE", "kept")
    env = run_environment(1.0)
    assert (env["OMP_NUM_THREADS"], env["NUMBA_NUM_THREADS"], env["SOMETHING_ELSE"]) == ("1", "1", "kept")
    assert run_environment(2.5)["NUMBA_NUM_THREADS"] == "2"  # Ray may hand out fractions; at least one thread
    assert run_environment(0.5)["OMP_NUM_THREADS"] == "1"


def test_bad_arguments_are_one_error_line(tmp_path, capsys):
    plan = _plan(tmp_path, TINY)
    for argv, message in ((["--plan", str(plan), "--only", "nope"], "--only: unknown table(s) ['nope']"),
                          (["--plan", "nope"], "--plan: expected one of ['paper'] or a plan .json file"),
                          (["--plan", str(tmp_path / "missing.json")], "missing.json: cannot read"),
                          (["--plan", str(plan), "--out", str(plan)], "is a file, expected a folder")):
        assert main([*argv, "--dry-run"]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and message in err and "Traceback" not in err
    for argv, message in ((["--seeds", "-1"], "argument --seeds: must be a non-negative integer, got -1"),
                          (["--seeds", "0.5"], "argument --seeds: must be a non-negative integer, got '0.5'"),
                          (["--cpus-per-run", "0"], "argument --cpus-per-run: must be a positive integer, got 0"),
                          (["--gpus-per-run", "-1"], "argument --gpus-per-run: must be")):
        with pytest.raises(SystemExit) as exit_info:
            main(["--plan", str(plan), *argv, "--dry-run"])
        err = capsys.readouterr().err
        assert exit_info.value.code == 2 and message in err.splitlines()[-1] and "Traceback" not in err
    (tmp_path / "b.json").write_text(json.dumps({"ppo": {"epochs": 0}}))
    assert main(["--plan", str(plan), "--dry-run"]) == 2
    assert capsys.readouterr().err == (f"error: {tmp_path / 'b.json'}: PPOConfig.epochs: expected a positive "
                                       "integer, got 0\n")
    (tmp_path / "b.json").write_text("{}")
    rows = json.loads(plan.read_text())["configurations"]
    for change, message in (({"tables": []}, "a non-empty list of 'tables'"),
                            ({"run_name": "a"}, "run_name: expected a folder name pattern with {seed}"),
                            ({"name": "b", "run_name": "{name}_seed{seed}"},
                             "[1]: its run folders 'b_seed{seed}' are those of"),
                            ({"config_file": None}, "give 'config_file', or 'missing'"),
                            ({"colour": 1}, "unknown key(s) ['colour']")):
        (tmp_path / "bad.json").write_text(json.dumps({"configurations": [rows[0] | change, *rows[1:]]}))
        assert main(["--plan", str(tmp_path / "bad.json"), "--dry-run"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {tmp_path / 'bad.json'}: configurations[") and message in err, err


def test_a_run_stopped_by_a_signal_is_reported_as_resumable_not_failed(tmp_path, capsys, monkeypatch):
    """A trainer that wrote its snapshot on SIGTERM exits with 143: the sweep names it stopped, resumable by the same
    command, and exits with that status; a failure among the runs makes the status 1."""
    plan = _plan(tmp_path, TINY)
    argv = ["--plan", str(plan), "--seeds", "0", "--out", str(tmp_path / "runs"), "--log-dir", str(tmp_path / "l")]
    results = [{"run": "a_seed0_lot", "rc": 0, "log": "a.log", "tail": ""},
               {"run": "b_seed0", "rc": 128 + signal.SIGTERM, "log": "b.log", "tail": "stopped by SIGTERM"}]
    monkeypatch.setattr(sweep_module, "run_sweep", lambda todo, args: results)
    assert main(argv) == 143
    err = capsys.readouterr().err
    assert "b_seed0: stopped by SIGTERM at a snapshot; the same sweep command resumes it (log b.log)" in err
    assert "failed" not in err and "a_seed0_lot" not in err
    results.append({"run": "x", "rc": 1, "log": "x.log", "tail": "Traceback"})
    assert main(argv) == 1
    assert "x: training failed (exit 1); end of x.log:\nTraceback" in capsys.readouterr().err
    assert task_verdict(results[0]) == "done" and task_verdict(results[2]) == "FAILED (exit 1, log x.log)"


def test_ctrl_c_during_the_sweep_stops_exactly_the_runs_it_submitted_and_exits_130(tmp_path, capsys, monkeypatch):
    """The wiring of Ctrl-C: the interrupt reaching ``main`` hands the runs it submitted (the unfinished ones, not a
    finished one) to ``stop_trainers`` and ends with status 130 and how to continue."""
    plan, root = _plan(tmp_path, TINY), tmp_path / "runs"
    finished = expand(load_plan(str(plan))[0], [0], root, ["main"], tmp_path)[0]
    finished.run_dir.mkdir(parents=True)
    finished.output.write_bytes(b"")
    (finished.run_dir / "metrics.jsonl").write_text("".join(json.dumps({"epoch": e}) + "\n" for e in (1, 2)))
    submitted, asked = [], []

    def interrupted(todo, args):
        submitted.extend(run.name for run in todo)
        raise KeyboardInterrupt

    monkeypatch.setattr(sweep_module, "run_sweep", interrupted)
    monkeypatch.setattr(sweep_module, "stop_trainers", lambda runs: asked.extend(run.name for run in runs))
    argv = ["--plan", str(plan), "--seeds", "0", "1", "--out", str(root), "--log-dir", str(tmp_path / "l")]
    assert main(argv) == 130
    assert asked == submitted and len(submitted) == 3 and finished.name not in submitted
    assert "interrupted; its trainers are stopped. Run the same command again" in capsys.readouterr().err


def test_an_interrupted_sweep_stops_its_trainers_after_their_epoch_each_with_a_snapshot(tmp_path, capsys):
    """What the sweep does on Ctrl-C before its Ray goes down: a trainer of one of its runs, midway between periodic
    snapshots, gets SIGUSR1 and ends with a snapshot at its last complete epoch; a trainer of another run is left."""
    recipe = TINY | {"ppo": TINY["ppo"] | {"epochs": 400, "snapshot_every_epochs": 400}}
    run, other = expand(load_plan(str(_plan(tmp_path, recipe)))[0], [0, 1], tmp_path / "runs", ["main"], tmp_path)[:2]
    config = tmp_path / "long.json"
    config.write_text(json.dumps(recipe))
    logs = [(tmp_path / f"{r.name}.log").open("w") for r in (run, other)]
    trainers = [subprocess.Popen([sys.executable, "-m", "np_policy.train", "--benchmark", "examples", "--config",
                                  str(config), "--out", str(r.run_dir)], cwd=REPO, stdout=subprocess.DEVNULL,
                                 stderr=log) for r, log in zip((run, other), logs)]
    try:
        _wait(lambda: all(_rows(r.run_dir) for r in (run, other)), 300, "both trainers' first epoch")
        assert stop_trainers([run]) == [trainers[0].pid]
        assert trainers[0].wait(timeout=60) == 128 + signal.SIGUSR1 and trainers[1].poll() is None
    finally:
        for trainer, log in zip(trainers, logs):
            trainer.kill()
            trainer.wait()
            log.close()
    rows = [json.loads(line)["epoch"] for line in _rows(run.run_dir)]
    assert 0 < rows[-1] < 400 and load_checkpoint(run.run_dir / "snapshot.pt")["epoch"] == rows[-1]
    assert f"stopped by SIGUSR1 after epoch {rows[-1]} of 400" in (tmp_path / f"{run.name}.log").read_text()
    assert "sweep: stopping 1 trainer(s) after the epoch in progress" in capsys.readouterr().err


def test_paper_plan_recognises_the_shipped_runs():
    runs = {run.name: run for run in expand(PAPER_PLAN, [0, 1, 2], REPO / "checkpoints" / "runs")}
    states = {name: run_state(run, active_trainers()) for name, run in runs.items()}
    for seed in (0, 1):  # finished 240-epoch runs of the recipe: the plan's config equals their config.json
        assert states[f"factorial_np_seed{seed}_lot"].kind == "finished"
        assert states[f"factorial_np_seed{seed}_lot"].epoch == 240
    assert states["factorial_np_seed2_lot"].kind in ("interrupted", "training now", "finished")
    assert states["site_np_seed0"].kind in ("interrupted", "training now", "finished")
    assert states["site_np_seed0"].epoch >= 65 and runs["site_np_seed0"].epochs == 240
    unavailable = sorted(name for name, state in states.items() if state.kind == "not available yet")
    waiting = not (REPO / "checkpoints/bev/topology_ae_v2.pt").exists()  # both backbones' BEV rows need the autoencoder
    assert len(unavailable) == 6 * waiting and all("bev" in n for n in unavailable)
    assert ("topology_ae_v2.pt" in states["topology_hope_bev_seed0"].detail) == waiting
    for added in ("none", "vertices"):  # the HOPE-style backbones of Table III, trained by hope_policy.train
        backbone = runs[f"topology_hope_{added}_seed0"]
        assert backbone.config.trainer == "hope_policy.train" and backbone.epochs == 10_000
        assert backbone.output.name == "final.pt"
        assert states[backbone.name].kind in ("not started", "interrupted", "training now", "finished")
    hope = runs["factorial_hope_seed0"]  # trained by hope_policy.train, progress counted in episodes
    assert hope.config.trainer == "hope_policy.train" and hope.epochs == 10_000
    assert states["factorial_hope_seed0"].kind in ("not started", "interrupted", "training now", "finished")
    fixed = resolved_config("factorial", 0, runs["factorial_np_fixed_seed0_lot"].overrides)
    shipped = json.loads((REPO / "checkpoints/runs/factorial_np_seed0_lot/config.json").read_text())
    assert fixed.env.connector.mode == "fixed" and fixed.curriculum_region == shipped["curriculum_region"] == "lot"
    assert fixed.ppo.epochs == 240 and fixed.curriculum_pool == shipped["curriculum_pool"] == 1024


def test_more_cpus_per_run_than_any_node_has_is_an_error_not_a_hang(tmp_path, capsys, monkeypatch):
    pytest.importorskip("ray")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)  # a local Ray sized to this machine
    plan = _plan(tmp_path, TINY)
    argv = ["--plan", str(plan), "--seeds", "0", "--out", str(tmp_path / "runs"), "--cpus-per-run", "4096"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.splitlines()[-1].startswith("error: --cpus-per-run 4096 / --gpus-per-run ")  # after Ray's own log
    assert f"no node of the Ray cluster has that many (the largest has {os.cpu_count()} CPUs" in err
    assert not (tmp_path / "runs").exists()


def _digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def _rows(folder: Path) -> list[str]:
    path = folder / "metrics.jsonl"
    return path.read_text().splitlines() if path.exists() else []


def _wait(condition, timeout: float, what: str) -> None:
    end = time.time() + timeout
    while not condition():
        assert time.time() < end, f"timed out waiting for {what}"
        time.sleep(0.2)


def _finished_tiny_run(root: Path, name: str) -> bool:
    return len(_rows(root / name)) == 2 and (root / name / "best.pt").exists()


def _midway_tiny_run(root: Path, name: str) -> bool:
    return len(_rows(root / name)) == 1 and (root / name / "snapshot.pt").exists()


def test_killed_sweep_finishes_only_what_was_unfinished(tmp_path):
    pytest.importorskip("ray")
    plan, root = _plan(tmp_path, TINY), tmp_path / "runs"
    names = ["a_seed0_lot", "a_seed1_lot", "b_seed0", "b_seed1"]
    argv = [sys.executable, "-m", "experiments.sweep", "--plan", str(plan), "--seeds", "0", "1", "--out", str(root),
            "--log-dir", str(tmp_path / "logs"), "--cpus-per-run", "1"]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"} | {"PYTHONPATH": str(REPO)}
    sweep = subprocess.Popen(argv, cwd=REPO, env=env, start_new_session=True, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    finished = partial(_finished_tiny_run, root)
    midway = partial(_midway_tiny_run, root)
    ours = {(root / n).resolve() for n in names}
    try:
        _wait(lambda: any(map(finished, names)) and any(map(midway, names)), 600, "one finished and one midway run")
    finally:  # kill it all at once: the sweep's process group (driver and Ray), then its trainers at once, which
        trainers = [pid for out, pid in active_trainers().items() if out in ours]  # would die with Ray seconds later
        os.killpg(sweep.pid, signal.SIGKILL)
        for pid in trainers:
            os.kill(pid, signal.SIGKILL)
        sweep.wait()
    _wait(lambda: not set(active_trainers()) & ours, 60, "the trainers to die")
    done = [n for n in names if finished(n)]
    resumable = {n: _rows(root / n) for n in names if n not in done and (root / n / "snapshot.pt").exists()}
    before = {n: _digests(root / n) for n in done}
    assert done and resumable
    result = subprocess.run(argv, cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
    output = result.stdout + result.stderr
    assert result.returncode == 0, output[-3000:]
    assert all(f"{n}: done" in output for n in set(names) - set(done))
    for n in done:  # finished runs were not touched
        assert f"{n}: done" not in output and _digests(root / n) == before[n]
    for n, rows in resumable.items():  # resumed from the snapshot: the epochs before it kept their rows
        assert _rows(root / n)[:len(rows)] == rows
        log = (tmp_path / "logs" / f"{n}.log").read_text()
        assert log.count("--resume") == 1 and "finished at epoch 2 of 2" in log.rstrip().splitlines()[-1]
    assert all(finished(n) for n in names)
