"""Tests for np_sim.show (CLI) and np_sim.plotting: every example renders to a non-empty PNG."""

from __future__ import annotations

import json

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from cli_helpers import help_text  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from np_sim.errors import SceneError  # noqa: E402
from np_sim.examples import example_names, example_path  # noqa: E402
from np_sim.plotting import plot_scene, target_marker  # noqa: E402
from np_sim.scene import Scene  # noqa: E402
from np_sim.show import load_path, main  # noqa: E402
from np_sim.vehicle import VehicleSpec  # noqa: E402

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name", example_names())
def test_main_writes_a_png_for_every_example(name, tmp_path, capsys):
    out = main([str(example_path(name)), "--out", str(tmp_path / f"{name}.png"), "--dpi", "40"])
    assert out == tmp_path / f"{name}.png"
    data = out.read_bytes()
    assert len(data) > 1000 and data.startswith(PNG_SIGNATURE)
    assert str(out) in capsys.readouterr().out


def test_default_output_is_scene_stem_in_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = main([str(example_path("parallel_slot")), "--dpi", "40"])
    assert out == tmp_path / "parallel_slot.png" and out.stat().st_size > 0


@pytest.mark.parametrize("suffix", [".npy", ".json"])
def test_path_overlay_from_npy_and_json(suffix, tmp_path):
    path = np.array([[16.0, 10.0, 0.0], [17.0, 6.0, 1.0], [16.6, 1.429, np.pi / 2]])
    path_file = tmp_path / f"path{suffix}"
    if suffix == ".npy":
        np.save(path_file, path)
    else:
        path_file.write_text(json.dumps(path[:, :2].tolist()))
    out = main([str(example_path("reverse_bay")), "--path", str(path_file), "--out", str(tmp_path / "p.png"),
                "--dpi", "40"])
    assert out.read_bytes().startswith(PNG_SIGNATURE)


def test_load_path_rejects_bad_files(tmp_path):
    bad_shape = tmp_path / "bad.json"
    bad_shape.write_text("[[1, 2, 3, 4]]")
    with pytest.raises(SceneError, match=r"bad\.json: expected shape \(N, 2\) or \(N, 3\)"):
        load_path(bad_shape)
    broken = tmp_path / "broken.json"
    broken.write_text("[[1, 2],")
    with pytest.raises(SceneError, match=r"broken\.json: invalid JSON at line 1"):
        load_path(broken)
    with pytest.raises(SceneError, match=r"expected a \.npy or \.json path file"):
        load_path(tmp_path / "path.csv")


def test_help_explains_the_cli(capsys):
    text = help_text(capsys, main)
    assert "SCENE.json" in text and "--out" in text and "--path" in text


def test_plot_scene_draws_circles_footprint_and_title():
    scene = Scene.load(example_path("clutter_random"))
    ax = Figure().add_subplot()
    assert plot_scene(ax, scene, path=np.array([[5.0, 24.0], [17.9, 9.4]])) is ax
    assert ax.get_title() == "clutter_random"
    assert ax.get_aspect() == 1.0
    assert "(m)" in ax.get_xlabel() and "(m)" in ax.get_ylabel()
    circles = [p for p in ax.patches if type(p).__name__ == "Circle"]
    assert len(circles) == sum(type(o).__name__ == "CircleObstacle" for o in scene.obstacles)


def test_target_marker_bar_is_across_and_stem_along_the_heading():
    spec = VehicleSpec()
    bar, stem = target_marker([1.0, 2.0, np.pi / 2], spec)
    np.testing.assert_allclose(bar, [[1.0 + 0.5 * spec.width_m, 2.0], [1.0 - 0.5 * spec.width_m, 2.0]], atol=1e-12)
    np.testing.assert_allclose(stem, [[1.0, 2.0], [1.0, 2.0 + spec.wheelbase_m]], atol=1e-12)
