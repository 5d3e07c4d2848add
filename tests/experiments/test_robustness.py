"""experiments.robustness: the study's runs, resumption after a kill, the outputs and the confidence bands."""

import csv
import json

import pytest

from experiments.robustness import RecordLog, main, study_jobs
from experiments.robustness_report import FailureCase, failure_cases, format_table, rates, wilson
from np_sim.clips import load_clips

CLIP = "eval-1000016"
"""A short clip Hybrid A* parks in closed loop."""


@pytest.mark.parametrize("k,n,low,high", [(8, 10, 0.4902, 0.9433), (0, 10, 0.0, 0.2775), (10, 10, 0.7225, 1.0),
                                          (47, 94, 0.4009, 0.5991)])
def test_wilson_matches_hand_computed_intervals(k, n, low, high):
    # hand values: p̂ = k/n, z = 1.96, (p̂ + z²/2n ± z√(p̂(1−p̂)/n + z²/4n²)) / (1 + z²/n)
    assert wilson(k, n) == pytest.approx((low, high), abs=1e-4)


def test_wilson_covers_the_observed_rate_and_narrows_with_more_runs():
    for n in (1, 5, 47, 200):
        for k in range(n + 1):
            lo, hi = wilson(k, n)
            assert 0.0 <= lo <= k / n <= hi <= 1.0
    assert wilson(30, 47)[1] - wilson(30, 47)[0] > wilson(300, 470)[1] - wilson(300, 470)[0]


def test_jobs_cover_every_factor_level_and_clip_once_and_skip_finished_runs():
    units = [c.name for c in load_clips("eval")[:3:2]]
    names = ["hybrid_astar", "np_guided_astar"]
    jobs = study_jobs(["latency", "friction"], ["mild", "severe"], units, names)
    assert len(jobs) == 2 * (1 + 2 * 2) and jobs[0][:2] == ("none", "none")
    assert {(f, lv, k) for f, lv, k, _ in jobs} == {("none", "none", 0), ("none", "none", 1)} | {
        (f, lv, k) for f in ("latency", "friction") for lv in ("mild", "severe") for k in (0, 1)}
    done = {("latency", "mild", "hybrid_astar", units[0]), ("none", "none", "hybrid_astar", units[1]),
            ("none", "none", "np_guided_astar", units[1])}
    left = study_jobs(["latency", "friction"], ["mild", "severe"], units, names, done)
    assert ("latency", "mild", 0, ("np_guided_astar",)) in left and len(left) == len(jobs) - 1
    assert sum(len(j[3]) for j in left) == 2 * 10 - 3


def test_the_record_log_appends_and_drops_a_row_a_kill_cut_short(tmp_path):
    path = tmp_path / "records.csv"
    log = RecordLog(path)
    log.append([{"factor": "none", "level": "none", "planner": "p", "clip": "a", "x": "[1, 2]"}])
    log.append([{"factor": "latency", "level": "mild", "planner": "p", "clip": "a", "x": "3"}])
    with path.open("a") as fh:
        fh.write("latency,severe,p")  # killed mid-row
    again = RecordLog(path)
    assert again.done() == {("none", "none", "p", "a"), ("latency", "mild", "p", "a")}
    again.append([{"factor": "latency", "level": "severe", "planner": "p", "clip": "a", "x": "4"}])
    assert [r["x"] for r in again.rows()] == ["[1, 2]", "3", "4"]


def test_a_study_runs_resumes_after_a_kill_and_writes_its_outputs(tmp_path):
    out = tmp_path / "study"
    args = ["--clips", "--clip-names", CLIP, "--planners", "hybrid_astar", "--factors", "latency", "--levels",
            "severe", "--workers", "1", "--no-rrd"]
    result = main(args + ["--out", str(out)])
    rows = list(csv.DictReader((out / "records.csv").open()))
    assert [(r["factor"], r["level"], r["setting"]) for r in rows] == [("none", "none", "none"),
                                                                       ("latency", "severe", "0.3 s")]
    assert rows[0]["footprint_success"] == "1" and rows[0]["seed"] == "0"
    assert (out / "plots" / "latency.png").stat().st_size > 0 and "### latency (control)" in result["table"]
    assert json.loads((out / "config.json").read_text())["argv"] == args[:-3]  # the study, not where it ran
    # a kill after the first row: the resumed study runs only the missing one, with the stored settings
    lines = (out / "records.csv").read_text().splitlines(keepends=True)
    (out / "records.csv").write_text("".join(lines[:2]))
    resumed = main(["--resume", str(out), "--workers", "1", "--no-rrd"])
    again = list(csv.DictReader((out / "records.csv").open()))
    assert [(r["factor"], r["level"]) for r in again] == [("none", "none"), ("latency", "severe")]
    assert {k: v for k, v in again[1].items() if "time" not in k and k != "realtime_factor"} == {
        k: v for k, v in rows[1].items() if "time" not in k and k != "realtime_factor"}
    assert len(resumed["rows"]) == 2


def test_an_episode_study_on_frozen_starts_and_on_scene_files_keys_its_runs_by_episode(tmp_path):
    out = tmp_path / "starts"
    args = ["--benchmark", "factorial", "--limit", "1", "--planners", "hybrid_astar", "--factors", "detection_drop",
            "--levels", "severe", "--workers", "1", "--no-rrd"]
    main(args + ["--out", str(out)])
    rows = list(csv.DictReader((out / "records.csv").open()))
    assert [(r["episode"], r["level"]) for r in rows] == [("factorial-test-near-reverse-easy-0#00", "none"),
                                                          ("factorial-test-near-reverse-easy-0#00", "severe")]
    assert int(rows[1]["obstacles_perceived"]) < int(rows[0]["obstacles_perceived"]) == 11  # p = 0.5 dropped some
    lines = (out / "records.csv").read_text().splitlines(keepends=True)
    (out / "records.csv").write_text("".join(lines[:2]))
    resumed = main(["--resume", str(out), "--workers", "1", "--no-rrd"])
    assert [r["level"] for r in resumed["rows"]] == ["none", "severe"]
    files = main(["--scenes", "reverse_bay", "--starts", "2", "--seed", "4", "--planners", "hybrid_astar",
                  "--factors", "latency", "--levels", "mild", "--workers", "1", "--no-rrd",
                  "--out", str(tmp_path / "files")])
    assert [r["episode"] for r in files["rows"]] == ["reverse_bay#00", "reverse_bay#01"] * 2
    assert files["rows"][0]["scene_file"].endswith("reverse_bay.json") and "2 episode(s)" in files["table"]


def test_the_table_reads_rates_per_level_with_the_undisturbed_rows_shared():
    rows = [{"factor": "none", "level": "none", "planner": "hybrid_astar", "clip": c, "footprint_success": s,
             "contacts": 0} for c, s in (("a", 1), ("b", 1))]
    rows += [{"factor": "friction", "level": "severe", "planner": "hybrid_astar", "clip": c, "footprint_success": s,
              "contacts": n, "reason": r} for c, s, n, r in (("a", 1, 0, ""), ("b", 0, 2, "contact"))]
    assert rates(rows, "friction", "hybrid_astar", "footprint_success") == [(2, 2), (0, 0), (0, 0), (1, 2)]
    assert rates(rows, "latency", "hybrid_astar", "contacts")[0] == (0, 2)
    table = format_table(rows, ["friction"], ["hybrid_astar"])
    lo, hi = wilson(1, 2)
    assert f"| Hybrid A* | 1.00 [{wilson(2, 2)[0]:.2f}, 1.00] / 0.00 | – | – | 0.50 [{lo:.2f}, {hi:.2f}] / 0.50 |" \
        in table
    assert "| Hybrid A* | – | – | – | contact 1 |" in table  # failure reasons per level


def test_dry_run_counts_the_runs_and_creates_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    main(["--clips", "--clips-limit", "2", "--planners", "hybrid_astar", "np_guided_astar", "--dry-run"])
    assert capsys.readouterr().out.startswith(f"{2 * 2 * (1 + 8 * 3)} runs ")
    assert not any(tmp_path.iterdir())  # no run folder


@pytest.mark.parametrize("argv,message", [
    (["--planners", "hybrid_astar"], "--clips"),
    (["--resume", "/nonexistent/study"], "config.json"),
    (["--clips", "--factors", "wind"], "invalid choice"),
    (["--benchmark", "factorial", "--starts", "3"], "--starts: only with --scenes"),
    (["--benchmark", "factorial", "--set", "controller=lqr"], "--set: only with --clips"),
    (["--benchmark", "topology", "--planners", "neuralparker", "--limit", "1"], "--checkpoint"),
    (["--clips", "--planners", "staged_astar_np"], "unknown planner"),
])
def test_mistakes_exit_2_with_one_error_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2 and message in capsys.readouterr().err


def test_the_recorded_failure_is_the_first_clip_the_disturbance_made_fail():
    # clip order c3, c1, c2 (not the rows' order nor the alphabet). Undisturbed, A fails c1 and B fails c2 and c3.
    outcomes = {("none", "none", "A"): {"c1": 0, "c2": 1, "c3": 1}, ("none", "none", "B"): {"c1": 1, "c2": 0, "c3": 0},
                ("latency", "mild", "A"): {"c1": 0, "c2": 0, "c3": 0},
                ("latency", "mild", "B"): {"c1": 1, "c2": 0, "c3": 0},
                ("latency", "severe", "A"): {"c1": 1, "c2": 1, "c3": 1},
                ("friction", "mild", "B"): {"c1": 0, "c2": 1, "c3": 0}}
    rows = [{"factor": f, "level": lv, "planner": p, "clip": c, "footprint_success": str(ok)}
            for (f, lv, p), runs in outcomes.items() for c, ok in sorted(runs.items())]
    cases = failure_cases(rows[::-1], ["c3", "c1", "c2"])
    assert cases == [
        FailureCase("friction", "mild", "B", "c1", fallback=False),  # c3 fails undisturbed too; c1 passes there
        FailureCase("latency", "mild", "A", "c3", fallback=False),  # c1 fails undisturbed; c3 comes before c2
        FailureCase("latency", "mild", "B", "c3", fallback=True),  # c2 and c3 fail undisturbed: the first failure
        FailureCase("none", "none", "A", "c1", fallback=True),
        FailureCase("none", "none", "B", "c3", fallback=True)]  # latency severe: nothing failed, nothing recorded
