"""Bad arguments to the experiment CLIs (and the tracking and policy benches): one ``error:`` line, exit status 2,
no traceback; an earlier run's folder is never reused or overwritten; the commands of the README and docs/ still
parse."""

import argparse
import re
import shlex
from pathlib import Path

import pytest
from cli_helpers import one_error_line

from experiments import closed_loop, evaluate, planners, track
from experiments.common import first, run_folder
from np_policy import bench_planner, bench_update
from np_sim.errors import ConfigError
from tracking import bench as tracking_bench

REPO = Path(__file__).resolve().parents[2]
CHECKPOINT = REPO / "checkpoints" / "factorial_np_seed0.pt"
EXPERIMENTS = {"evaluate": (evaluate.main, ["--checkpoints", str(CHECKPOINT)]),
               "planners": (planners.main, ["--methods", "hybrid_astar"]),
               "track": (track.main, []),
               "closed_loop": (closed_loop.main, ["--clips", "--planners", "hybrid_astar"])}
"""Each experiment CLI with the arguments it needs besides the ones under test."""


@pytest.mark.parametrize("experiment, argv, expected", [
    ("evaluate", ["--limit", "-2"], "argument --limit: must be a positive integer, got -2"),
    ("evaluate", ["--limit", "0"], "argument --limit: must be a positive integer, got 0"),
    ("evaluate", ["--limit", "2.5"], "argument --limit: must be a positive integer, got '2.5'"),
    ("evaluate", ["--samples", "-1"], "argument --samples: must be a non-negative integer, got -1"),
    ("evaluate", ["--action-seed", "-1"], "argument --action-seed: must be a non-negative integer, got -1"),
    ("planners", ["--limit", "-2"], "argument --limit: must be a positive integer, got -2"),
    ("planners", ["--limit", "0"], "argument --limit: must be a positive integer, got 0"),
    ("planners", ["--ompl-seed", "-3"], "argument --ompl-seed: must be a non-negative integer, got -3"),
    ("planners", ["--split", "validation", "--scenes", "parallel_slot"],
     "--split validation plans the benchmark's training scenes; it cannot go with --scenes"),
    ("evaluate", ["--starts-per-scene", "0"], "argument --starts-per-scene: must be a positive integer, got 0"),
    ("evaluate", ["--split", "train"], "argument --split: invalid choice: 'train'"),
    ("track", ["--limit", "-1"], "argument --limit: must be a positive integer, got -1"),
    ("track", ["--per-scene", "0"], "argument --per-scene: must be a positive integer, got 0"),
    ("track", ["--rrd-episodes", "-1"], "argument --rrd-episodes: must be a non-negative integer, got -1"),
    ("track", ["--controller", "pid"], "argument --controller: invalid choice: 'pid'"),
    ("closed_loop", ["--clips-limit", "-1"], "argument --clips-limit: must be a positive integer, got -1"),
    ("closed_loop", ["--clips-limit", "0"], "argument --clips-limit: must be a positive integer, got 0"),
    ("closed_loop", ["--workers", "0"], "argument --workers: must be a positive integer, got 0"),
    ("closed_loop", ["--set", "render_clips=-1"],
     "--set render_clips=-1: ClosedLoopConfig.render_clips: expected >= 0"),
    ("closed_loop", ["--set", "clip_run.track_window=0"],
     "--set clip_run.track_window=0: ClipRunConfig.track_window: expected >= 1 frame, got 0"),
    ("closed_loop", ["--set", "planner.neuralparker_footprint.samples=-1"],
     "--set planner.neuralparker_footprint.samples=-1: NeuralParkerConfig.samples: expected an integer >= 0, got -1"),
    ("closed_loop", ["--set", "planner.search_margin_m=-0.1"],
     "--set planner.search_margin_m=-0.1: PlannerOptions.search_margin_m: expected >= 0 m, got -0.1"),
    ("closed_loop", ["--set", "planner.search_time_budget_s=0"],
     "--set planner.search_time_budget_s=0: PlannerOptions.search_time_budget_s: expected a finite number of "
     "seconds > 0, got 0"),
    ("closed_loop", ["--set", "planner.neuralparker_footprint.margin_m=NaN"],
     "--set planner.neuralparker_footprint.margin_m=NaN: NeuralParkerConfig.margin_m: expected a finite number >= 0 m"),
    ("closed_loop", ["--set", "controller=pid"], "--set controller=pid: ClosedLoopConfig.controller: expected one of "),
])
def test_out_of_range_arguments_are_refused_at_parse_time(capsys, tmp_path, experiment, argv, expected):
    main, needed = EXPERIMENTS[experiment]
    line = one_error_line(capsys, main, [*needed, *argv, "--out", str(tmp_path / "run")])
    assert re.search(f"error: {re.escape(expected)}", line), line
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("main, argv, expected", [
    (tracking_bench.main, ["--repeats", "0"], "argument --repeats: must be a positive integer, got 0"),
    (bench_planner.main, ["--episodes", "0"], "argument --episodes: must be a positive integer, got 0"),
    (bench_planner.main, ["--samples", "-2"], "argument --samples: must be a non-negative integer, got -2"),
    (bench_update.main, ["--batch", "0"], "argument --batch: must be a positive integer, got 0"),
    (bench_update.main, ["--chunks", "1024", "-8"], "argument --chunks: must be a positive integer, got -8"),
    (bench_update.main, ["--threads", "0"], "argument --threads: must be a positive integer, got 0"),
])
def test_the_benches_refuse_out_of_range_numbers(capsys, main, argv, expected):
    assert one_error_line(capsys, main, argv).endswith(f"error: {expected}")


def test_a_missing_or_broken_checkpoint_is_one_line(capsys, tmp_path):
    missing = one_error_line(capsys, evaluate.main, ["--checkpoints", str(tmp_path / "none.pt"), "--limit", "1"])
    assert missing.endswith(f"error: argument --checkpoints: no such file: {tmp_path / 'none.pt'}")
    broken = tmp_path / "broken.pt"
    broken.write_bytes(b"not a checkpoint")
    line = one_error_line(capsys, evaluate.main, ["--checkpoints", str(broken), "--limit", "1", "--out",
                                                  str(tmp_path / "run")])
    assert line.startswith(f"error: {broken}")
    line = one_error_line(capsys, bench_planner.main, ["--checkpoint", str(tmp_path / "none.pt"), "--episodes", "1"])
    assert line.startswith("error: ") and "none.pt" in line


def test_user_errors_found_after_parsing_are_one_line(capsys, tmp_path):
    line = one_error_line(capsys, track.main, ["--planner", "neuralparker", "--limit", "1", "--out",
                                               str(tmp_path / "track")])
    assert line == "error: planner neuralparker needs a policy checkpoint; pass --checkpoint PATH"
    assert not (tmp_path / "track").exists()
    line = one_error_line(capsys, closed_loop.main, ["--clips", "--clip-names", "nope", "--planners", "hybrid_astar",
                                                     "--out", str(tmp_path / "closed_loop")])
    assert line.startswith("error: --clip-names: ['nope'] are not eval clips (eval-")


@pytest.mark.parametrize("experiment", sorted(EXPERIMENTS))
def test_a_non_empty_out_folder_is_refused_and_kept_byte_identical(capsys, tmp_path, experiment):
    main, needed = EXPERIMENTS[experiment]
    earlier = tmp_path / "earlier"
    (earlier / "rrd").mkdir(parents=True)
    files = {earlier / "records.csv": b"scene,start_id\n" + b"s,0\n" * 1079, earlier / "table.md": b"| a |\n",
             earlier / "rrd" / "killed_run.rrd": bytes(range(256))}
    for path, data in files.items():
        path.write_bytes(data)
    line = one_error_line(capsys, main, [*needed, "--limit" if experiment != "closed_loop" else "--clips-limit", "1",
                                         "--out", str(earlier)])
    assert f"argument --out: {earlier} exists and is not empty" in line
    assert {p: p.read_bytes() for p in earlier.rglob("*") if p.is_file()} == files


@pytest.mark.parametrize("experiment", sorted(EXPERIMENTS))
def test_an_out_that_is_a_file_is_refused_and_kept(capsys, tmp_path, experiment):
    main, needed = EXPERIMENTS[experiment]
    taken = tmp_path / "records.csv"
    taken.write_bytes(b"scene\n")
    line = one_error_line(capsys, main, [*needed, "--out", str(taken)])
    assert line.endswith(f"error: argument --out: {taken} is a file; expected a new or empty folder")
    assert taken.read_bytes() == b"scene\n"


def test_run_folder_makes_a_fresh_folder_every_time(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("experiments.common.time.strftime", lambda _fmt: "20260101-120000")  # one second
    first, second, third = (run_folder("evaluate", None) for _ in range(3))
    base = Path("results/evaluate")
    assert (first, second, third) == (base / "20260101-120000", base / "20260101-120000-2", base / "20260101-120000-3")
    assert all(p.is_dir() and not any(p.iterdir()) for p in (first, second, third))
    assert run_folder("evaluate", tmp_path / "new" / "run") == tmp_path / "new" / "run"
    assert (tmp_path / "new" / "run").is_dir()
    (first / "records.csv").write_text("kept\n")
    with pytest.raises(ConfigError, match="--out: .* exists and is not empty"):
        run_folder("evaluate", first)
    assert (first / "records.csv").read_text() == "kept\n"


def test_a_limit_below_one_is_refused_by_the_functions_too(tmp_path):
    """`[:limit]` with a negative limit silently drops the last episodes; the experiment functions refuse it."""
    assert first([1, 2, 3], 2) == [1, 2] and first([1, 2, 3], None) == [1, 2, 3] and first([1, 2, 3], 9) == [1, 2, 3]
    for bad in (-2, 0, 2.5, True):
        with pytest.raises(ConfigError, match=f"--limit: expected a positive integer .*got {bad!r}"):
            first([1, 2, 3], bad)
    with pytest.raises(ConfigError, match="--limit: expected a positive integer"):
        evaluate.evaluate("factorial", [CHECKPOINT], out=tmp_path / "evaluate", limit=-2)
    with pytest.raises(ConfigError, match="--per-scene: expected a positive integer"):
        track.track(per_scene=-1, out=tmp_path / "track")
    with pytest.raises(ConfigError, match="ClosedLoopConfig.clips_limit: expected >= 1, got -1"):
        closed_loop.run(closed_loop.ClosedLoopConfig(planners=("hybrid_astar",), clips_limit=-1),
                        out=tmp_path / "closed_loop")
    assert not any(tmp_path.iterdir())  # refused before a run folder was made


def test_closed_loop_merges_only_the_recordings_it_names(tmp_path, monkeypatch):
    assert closed_loop.merge_rrd([], tmp_path / "merged.rrd") is None
    assert not (tmp_path / "merged.rrd").exists()
    assert closed_loop.rrd_path(tmp_path, "eval-1000016", "hybrid_astar") == tmp_path / "eval-1000016_hybrid_astar.rrd"
    stale, ours = tmp_path / "eval-1000001_hybrid_astar.rrd", tmp_path / "eval-1000016_hybrid_astar.rrd"
    stale.write_bytes(b"killed run")
    ours.write_bytes(b"this run")
    calls = []
    monkeypatch.setattr(closed_loop, "merge_recordings", lambda files, out: calls.append(list(files)) or out)
    assert closed_loop.merge_rrd([ours], tmp_path / "merged.rrd") == tmp_path / "merged.rrd"
    assert calls == [[ours]]


USER_DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
"""The README and the user docs pages whose commands must parse (not the dated pages under ``docs/results/``: their
commands are as of their commit)."""


def doc_commands(path: Path) -> list[tuple[str, str]]:
    """(module, arguments) of every complete ``python -m`` command of one page: inline code spans and code-block
    lines, without synopses (``[...]``) or placeholders (``K``, ``SCENE.json``), the trainer and pytest."""
    text = path.read_text()
    found = [(m[1], " ".join(m[2].split())) for m in re.finditer(r"`(?:\.venv/bin/)?python -m ([\w.]+)([^`]*)`", text)]
    block = False
    for line in text.splitlines():
        block = block != line.startswith("```")
        match = re.search(r"(?:^|&& |/)python -m ([\w.]+)([^#]*)", line) if block else None
        if match:
            found.append((match[1], " ".join(match[2].split())))
    skip = re.compile(r"\[|\\|\b(K|M|N|S|k|PATH|PNG)\b|SCENE\.json")
    return [(m, a) for m, a in found if m not in ("np_policy.train", "pytest") and not skip.search(a)]


def readme_commands() -> list[tuple[str, str]]:
    """(module, arguments) of every complete ``python -m`` command of the README and the docs pages, once each."""
    return sorted({command for page in USER_DOCS for command in doc_commands(page)})


def test_the_readme_has_the_commands_this_test_parses():
    modules = {m for m, _ in readme_commands()}
    assert {"experiments.closed_loop", "experiments.evaluate", "experiments.planners", "experiments.track",
            "np_sim.bench", "np_sim.planners.bench", "np_policy.bench_update", "tracking.bench"} <= modules


@pytest.mark.parametrize("module, arguments", readme_commands())
def test_every_readme_command_still_parses(tmp_path, monkeypatch, module, arguments):
    """Parse each README or docs command (in a fresh folder, so its --out folders are new; the checkpoints it
    names linked in, or a stand-in where the README's training creates them) and stop before any work."""
    import importlib

    monkeypatch.chdir(tmp_path)
    (tmp_path / "checkpoints").symlink_to(REPO / "checkpoints")
    for arg in shlex.split(arguments):
        if arg.startswith("results/") and arg.endswith(".pt"):  # written by a README training command
            Path(arg).parent.mkdir(parents=True, exist_ok=True)
            Path(arg).write_bytes(b"")
    parse = argparse.ArgumentParser.parse_args

    class Parsed(Exception):
        pass

    def parse_then_stop(self, args=None, namespace=None):
        raise Parsed(parse(self, args, namespace))

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_then_stop)
    main = importlib.import_module(module if module != "np_sim.benchmarks" else "np_sim.benchmarks.__main__").main
    with pytest.raises(Parsed):
        main(shlex.split(arguments))
