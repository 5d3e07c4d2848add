"""Your own scenes on the experiment CLIs: ``--scenes`` on experiments.planners and experiments.track, and the
one-scene command experiments.scene_run (tiny-budget smoke runs, and a user's mistakes as one error line)."""

from __future__ import annotations

import csv
import json
import re

import numpy as np
import pytest
from cli_helpers import one_error_line

from experiments import planners, scene_run, track
from experiments.scene_files import EXAMPLES, load_scene_files
from np_sim.scene import Scene

BAY = EXAMPLES / "reverse_bay.json"


def _rows(folder):
    return list(csv.DictReader((folder / "records.csv").open()))


def test_planners_on_scene_files_name_the_file_and_the_drawn_starts(tmp_path, capsys):
    result = planners.main(["--scenes", "reverse_bay", "--starts", "2", "--seed", "4", "--methods", "hybrid_astar",
                            "--out", str(tmp_path / "a")])
    rows = _rows(tmp_path / "a")
    assert [r["start_id"] for r in rows] == ["0", "1"] and {r["scene_file"] for r in rows} == {str(BAY)}
    assert {r["start_source"] for r in rows} == {"drawn"}
    drawn = load_scene_files([BAY], 2, 4, "reference_point")[0].starts.poses
    np.testing.assert_array_equal([[float(r[k]) for k in ("start_x", "start_y", "start_theta")] for r in rows], drawn)
    config = json.loads((tmp_path / "a" / "config.json").read_text())
    assert config["benchmark"] is None and config["scenes"][0]["n_starts"] == 2
    assert "rejected in collision under the reference_point convention" in capsys.readouterr().out
    assert "| Hybrid A* |" in result["table"]


def test_explicit_starts_of_a_file_are_used_and_tracked(tmp_path):
    data = Scene.load(BAY).to_dict()
    data["starts"] = [data["start_region"][0], data["start_region"][2]]
    data["starts"] = [[x + 1.5 * (1 - 2 * i), y + 1.5 * (1 - 2 * i), 0.0] for i, (x, y) in enumerate(data["starts"])]
    path = tmp_path / "bay_with_starts.json"
    path.write_text(json.dumps(data))
    track.main(["--scenes", str(path), "--planner", "hybrid_astar", "--rrd-episodes", "0", "--no-render",
                "--per-scene", "1", "--out", str(tmp_path / "t")])
    rows = _rows(tmp_path / "t")
    assert len(rows) == 1 and rows[0]["start_source"] == "file" and rows[0]["scene_file"] == str(path)
    assert [float(rows[0][k]) for k in ("start_x", "start_y", "start_theta")] == data["starts"][0]
    assert rows[0]["plan_success"] == "1"


def test_scene_run_plans_draws_and_records_every_planner_named(tmp_path):
    out = tmp_path / "run"
    result = scene_run.main(["reverse_bay", "--planners", "hybrid_astar", "neuralparker", "--no-render",
                             "--out", str(out)])
    rows = _rows(out)
    assert [r["planner"] for r in rows] == ["hybrid_astar", "neuralparker"]
    assert {r["start_source"] for r in rows} == {"drawn"}
    assert (out / "plans.png").stat().st_size > 10_000 and (out / "table.md").exists()
    assert sorted(p.name for p in (out / "rrd").iterdir()) == ["hybrid_astar.rrd", "neuralparker.rrd"]
    # the start is free under the footprint convention (Hybrid A*'s here) and both runs start there
    assert np.allclose([float(rows[0][k]) for k in ("start_x", "start_y", "start_theta")], result["start"])


@pytest.mark.parametrize("main, argv, message", [
    (planners.main, ["--scenes", "reverse_bay", "--methods", "hybrid_astar"], "lists no starts; give a number"),
    (planners.main, ["--scenes", "reverse_bay", "reverse_bay", "--starts", "1", "--methods", "hybrid_astar"],
     "appear in more than one file"),
    (scene_run.main, ["reverse_bay", "--start", "1", "1", "0", "--planners", "hybrid_astar"],
     r"--start: the start \(1, 1, 0\) is in collision under the footprint convention"),
    (scene_run.main, ["reverse_bay", "--start", "nan", "1", "0"], "--start: expected three finite numbers"),
    (scene_run.main, ["no_such_scene"], "no such file: no_such_scene"),
])
def test_a_users_mistake_is_one_error_line(capsys, tmp_path, main, argv, message):
    assert re.search(message, one_error_line(capsys, main, [*argv, "--out", str(tmp_path / "x")]))
    assert not (tmp_path / "x").exists()  # refused before a run folder was made
