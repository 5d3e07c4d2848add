"""Bad arguments to the planning-core CLIs: one ``error:`` line on stderr, exit status 2, no traceback, nothing
written (`np_sim.cli`'s argument types and error boundary)."""

import argparse
import subprocess
import sys

import pytest
from cli_helpers import one_error_line

from np_sim import bench, cli, clips, demo, show
from np_sim.benchmarks import __main__ as benchmarks_cli
from np_sim.benchmarks import generate as generate_cli
from np_sim.errors import ConfigError, SceneError
from np_sim.examples import example_path
from np_sim.planners import bench as planners_bench


@pytest.mark.parametrize("text, value", [("1", 1), ("40", 40), (" 7 ", 7)])
def test_positive_int_accepts_whole_numbers_from_one(text, value):
    assert cli.positive_int(text) == value


@pytest.mark.parametrize("text, expected", [("0", "must be a positive integer, got 0"),
                                            ("-2", "must be a positive integer, got -2"),
                                            ("2.5", "must be a positive integer, got '2.5'"),
                                            ("1e3", "must be a positive integer, got '1e3'"),
                                            ("ten", "must be a positive integer, got 'ten'")])
def test_positive_int_refuses_zero_negatives_and_floats(text, expected):
    with pytest.raises(argparse.ArgumentTypeError, match=f"^{expected}$"):
        cli.positive_int(text)


def test_the_non_negative_and_float_types_draw_the_line_where_their_names_say():
    assert cli.non_negative_int("0") == 0
    with pytest.raises(argparse.ArgumentTypeError, match="must be a non-negative integer, got -1"):
        cli.non_negative_int("-1")
    assert cli.positive_float("0.05") == 0.05 and cli.non_negative_float("0") == 0.0
    assert cli.probability("0") == 0.0 and cli.probability("1") == 1.0
    for kind, bad in ((cli.positive_float, ("0", "-1", "nan", "inf", "x")),
                      (cli.non_negative_float, ("-0.1", "nan", "inf")),
                      (cli.probability, ("1.01", "-0.5", "nan"))):
        for text in bad:
            with pytest.raises(argparse.ArgumentTypeError, match=f"must be .*, got '?{text}'?$"):
                kind(text)


def test_existing_file_and_the_folder_types(tmp_path):
    scene = example_path("reverse_bay")
    assert cli.existing_file(str(scene)) == scene
    with pytest.raises(argparse.ArgumentTypeError, match="no such file: .*none.json"):
        cli.existing_file(str(tmp_path / "none.json"))
    with pytest.raises(argparse.ArgumentTypeError, match="expected a file, got the folder"):
        cli.existing_file(str(tmp_path))
    assert cli.fresh_folder(str(tmp_path)) == tmp_path  # empty
    assert cli.fresh_folder(str(tmp_path / "new" / "run")) == tmp_path / "new" / "run"  # not there yet
    assert not (tmp_path / "new").exists()  # checking creates nothing
    (tmp_path / "records.csv").write_text("scene\n")
    with pytest.raises(argparse.ArgumentTypeError, match="exists and is not empty"):
        cli.fresh_folder(str(tmp_path))
    with pytest.raises(argparse.ArgumentTypeError, match="records.csv is a file; expected a new or empty folder"):
        cli.fresh_folder(str(tmp_path / "records.csv"))
    with pytest.raises(argparse.ArgumentTypeError, match="records.csv is a file; expected a folder"):
        cli.output_folder(str(tmp_path / "records.csv"))
    assert cli.output_folder(str(tmp_path)) == tmp_path  # a folder to write into may hold files


@pytest.mark.parametrize("error", [ConfigError("--x: expected y, got z"), SceneError("a.json: boundary: bad"),
                                   FileNotFoundError(2, "No such file or directory", "a.pt"),
                                   IsADirectoryError(21, "Is a directory", "out")])
def test_the_boundary_turns_user_errors_into_one_line_and_status_2(capsys, error):
    @cli.cli_boundary
    def main(argv=None):
        raise error

    assert one_error_line(capsys, main, []) == f"error: {error}"


@pytest.mark.parametrize("bug", [RuntimeError("bug"), ValueError("a plain ValueError is a bug"), KeyError("k"),
                                 ZeroDivisionError()])
def test_the_boundary_lets_bugs_raise(bug):
    @cli.cli_boundary
    def main(argv=None):
        raise bug

    with pytest.raises(type(bug)):
        main([])


def test_the_boundary_passes_the_result_through():
    assert cli.cli_boundary(lambda argv=None: {"argv": argv})(["a"]) == {"argv": ["a"]}


@pytest.mark.parametrize("main, argv, expected", [
    (demo.main, ["--steps", "-3"], "argument --steps: must be a positive integer, got -3"),
    (demo.main, ["--steps", "0"], "argument --steps: must be a positive integer, got 0"),
    (demo.main, ["--steps", "2.5"], "argument --steps: must be a positive integer, got '2.5'"),
    (demo.main, ["--seed", "-1"], "argument --seed: must be a non-negative integer, got -1"),
    (bench.main, ["--seconds", "0"], "argument --seconds: must be a positive number, got 0"),
    (bench.main, ["--seconds", "nan"], "argument --seconds: must be a positive number, got 'nan'"),
    (bench.main, ["--num-envs", "0"], "argument --num-envs: must be a positive integer, got 0"),
    (planners_bench.main, ["--episodes", "-5"], "argument --episodes: must be a positive integer, got -5"),
    (planners_bench.main, ["--episodes", "0"], "argument --episodes: must be a positive integer, got 0"),
    (planners_bench.main, ["--ompl-episodes", "-1"],
     "argument --ompl-episodes: must be a non-negative integer, got -1"),
    (show.main, [str(example_path("reverse_bay")), "--dpi", "0"],
     "argument --dpi: must be a positive integer, got 0"),
    (clips.main, ["--summary", "--train-sample", "-1"], "argument --train-sample: must be a positive integer, got -1"),
    (clips.main, ["--summary", "--train-sample", "0"], "argument --train-sample: must be a positive integer, got 0"),
    (benchmarks_cli.main, ["--summary", "--dpi", "-3"], "argument --dpi: must be a positive integer, got -3"),
])
def test_out_of_range_numbers_are_refused_at_parse_time(capsys, main, argv, expected):
    assert one_error_line(capsys, main, argv).endswith(f"error: {expected}")


def test_a_missing_scene_a_folder_and_a_bad_path_file_are_one_line(capsys, tmp_path):
    missing = one_error_line(capsys, show.main, [str(tmp_path / "none.json")])
    assert missing.endswith(f"error: argument SCENE.json: no such file: {tmp_path / 'none.json'}")
    folder = one_error_line(capsys, show.main, [str(tmp_path)])
    assert folder.endswith(f"error: argument SCENE.json: expected a file, got the folder {tmp_path}")
    path_file = tmp_path / "path.json"
    path_file.write_text("[[1, 2],")
    bad_path = one_error_line(capsys, show.main, [str(example_path("reverse_bay")), "--path", str(path_file),
                                                  "--out", str(tmp_path / "x.png")])
    assert bad_path == f"error: {path_file}: invalid JSON at line 1, column 9: Expecting value"
    assert not (tmp_path / "x.png").exists()


def test_an_output_that_is_a_file_is_one_line_and_the_file_is_kept(capsys, tmp_path):
    taken = tmp_path / "taken"
    taken.write_bytes(b"earlier output\n")
    for main, flag, argv in ((demo.main, "--out", ["--steps", "1"]), (benchmarks_cli.main, "--figure", []),
                             (generate_cli.main, "--out", ["--benchmark", "topology"])):
        line = one_error_line(capsys, main, [*argv, flag, str(taken)])
        assert line.endswith(f"error: argument {flag}: {taken} is a file; expected a folder")
        assert taken.read_bytes() == b"earlier output\n"


def test_an_unknown_clip_name_is_one_line(capsys, tmp_path):
    line = one_error_line(capsys, clips.main, ["--figure", "nope", "--out", str(tmp_path / "clip.png")])
    assert line.startswith("error: find_clip: no clip named 'nope'; expected an eval clip name")
    assert not (tmp_path / "clip.png").exists()


def test_python_dash_m_prints_one_error_line_and_exits_2(tmp_path):
    """The real entry point, in a fresh interpreter: the boundary's line, no traceback."""
    bad = tmp_path / "bad.json"
    bad.write_text('{"boundary": []}')
    done = subprocess.run([sys.executable, "-m", "np_sim.show", str(bad), "--out", str(tmp_path / "bad.png")],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {bad}") and "Traceback" not in done.stderr
    assert not (tmp_path / "bad.png").exists()
