"""Render a scene (and optionally a path) to a PNG: ``python -m np_sim.show SCENE.json [--out PNG] [--path FILE]``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from np_sim.cli import cli_boundary, existing_file, positive_int
from np_sim.errors import SceneError
from np_sim.plotting import plot_scene
from np_sim.scene import Scene


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m np_sim.show``."""
    parser = argparse.ArgumentParser(
        prog="python -m np_sim.show",
        description=(
            "Validate a scene JSON file (spec §10) and draw it to a PNG: boundary, obstacles, start region "
            "(hatched), the target as a T-marker (bar across the pose, stem along the heading) with the vehicle "
            "footprint, and an optional path. Prints where the PNG went."
        ),
        epilog="example: python -m np_sim.show np_sim/examples/reverse_bay.json --out bay.png",
    )
    parser.add_argument("scene", type=existing_file, metavar="SCENE.json",
                        help="scene file to draw (validated on load)")
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="PNG",
        help="output PNG (default: the scene file's stem + .png in the current directory)",
    )
    parser.add_argument(
        "--path",
        type=Path,
        default=None,
        metavar="PATH_FILE",
        help="path to overlay: a .npy array or a .json list of [x, y] or [x, y, theta] rows (metres, radians)",
    )
    parser.add_argument("--dpi", type=positive_int, default=150,
                        help="resolution of the PNG in dots per inch (default 150)")
    return parser


def load_path(path_file: Path) -> np.ndarray:
    """Read a path file (.npy, or .json list of [x, y(, θ)] rows) as an (N, 2) or (N, 3) float64 array.

    Raises
    ------
    SceneError
        If the file is not .npy/.json, is not valid JSON, or does not hold finite (N, 2) or (N, 3) numbers.
    """
    suffix = path_file.suffix.lower()
    if suffix == ".npy":
        data = np.load(path_file, allow_pickle=False)
    elif suffix == ".json":
        try:
            data = json.loads(path_file.read_text(encoding="utf-8"))
        except json.JSONDecodeError as error:
            raise SceneError(
                f"{path_file}: invalid JSON at line {error.lineno}, column {error.colno}: {error.msg}"
            ) from None
    else:
        raise SceneError(f"{path_file}: expected a .npy or .json path file, got suffix {suffix!r}")
    try:
        points = np.array(data, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneError(f"{path_file}: expected a list of [x, y] or [x, y, theta] rows of numbers") from None
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) == 0:
        raise SceneError(f"{path_file}: expected shape (N, 2) or (N, 3) with N >= 1, got {points.shape}")
    if not np.all(np.isfinite(points)):
        raise SceneError(f"{path_file}: expected finite numbers")
    return points


@cli_boundary
def main(argv: list[str] | None = None) -> Path:
    """Run the CLI on ``argv`` (default: ``sys.argv[1:]``); returns the path of the PNG written. A bad scene or path
    file prints one ``error:`` line and exits with status 2."""
    args = build_parser().parse_args(argv)
    scene = Scene.load(args.scene)
    path = load_path(args.path) if args.path is not None else None
    out = args.out if args.out is not None else Path.cwd() / f"{args.scene.stem}.png"
    figure = Figure(figsize=(9.0, 6.5), layout="constrained")
    plot_scene(figure.add_subplot(), scene, path=path)
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=args.dpi)
    print(f"wrote {out}")
    return out


if __name__ == "__main__":
    main()
