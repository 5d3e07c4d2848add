"""Representative held-out scenes of both benchmarks (paper Fig. ``fig:sceneexamples``, §IV-A).

``python -m experiments.scenes [--difficulty easy|medium|hard] [--out DIR]``

The Factorial block puts the start-distance regimes in rows and the parking types in columns (the test scene of
each cell at ``--difficulty``, default hard); the Topology-Stress block puts the route-choice families in rows and
the difficulties in columns (the first test scene of each cell). Every panel keeps equal x–y metric scaling; the
start region is hatched, the target a red T-marker, axes in metres (`np_sim.plotting.plot_scene`). Writes
``scenes.png`` and ``scenes.json`` (the panel grid: which scene sits where) into a fresh run folder.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from matplotlib.figure import Figure

from experiments.common import run_folder
from np_sim.benchmarks import load_benchmark
from np_sim.cli import cli_boundary, fresh_folder
from np_sim.plotting import plot_scene
from np_sim.scene import Scene

DISTANCES = ("near", "medium", "long")
TYPES = ("reverse", "lateral", "random")
FAMILIES = ("type1", "type2", "type3")
TOPOLOGY_DIFFICULTIES = ("medium", "hard")
FACTORIAL_DIFFICULTIES = ("easy", "medium", "hard")


def _cell(scenes: list[Scene], **tags: str) -> Scene:
    """The first scene whose tags match ``tags`` (ValueError naming the cell when there is none)."""
    for scene in scenes:
        if all(scene.tags.get(key) == value for key, value in tags.items()):
            return scene
    raise ValueError(f"experiments.scenes: no test scene with tags {tags}")


def scene_grids(difficulty: str = "hard") -> dict[str, list[list[Scene]]]:
    """The two panel grids of Fig. ``fig:sceneexamples``: Factorial (distance × type) and Topology-Stress
    (family × difficulty), held-out (test) scenes."""
    if difficulty not in FACTORIAL_DIFFICULTIES:
        raise ValueError(f"experiments.scenes: difficulty must be one of {FACTORIAL_DIFFICULTIES}, got "
                         f"{difficulty!r}")
    factorial, topology = load_benchmark("factorial", "test"), load_benchmark("topology", "test")
    return {"factorial": [[_cell(factorial, distance=d, type=t, difficulty=difficulty) for t in TYPES]
                          for d in DISTANCES],
            "topology": [[_cell(topology, family=f, difficulty=d) for d in TOPOLOGY_DIFFICULTIES]
                         for f in FAMILIES]}


def draw_scene_grids(grids: dict[str, list[list[Scene]]], png: Path) -> None:
    """Draw both grids side by side into ``png`` (one legend for all panels)."""
    figure = Figure(figsize=(17.0, 9.5), layout="constrained")
    blocks = figure.subfigures(1, 2, width_ratios=[3, 2])
    for block, (name, grid) in zip(blocks, grids.items()):
        block.suptitle("Factorial Parking Benchmark" if name == "factorial" else "Topology-Stress Benchmark")
        axes = block.subplots(len(grid), len(grid[0]), squeeze=False)
        for row, scenes in zip(axes, grid):
            for ax, scene in zip(row, scenes):
                plot_scene(ax, scene)
                ax.get_legend().remove()
                ax.set_title(scene.tags["cell"], fontsize="small")
                ax.tick_params(labelsize="x-small")
    handles, labels = axes[0][0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncols=len(labels), frameon=False)
    figure.savefig(png, dpi=110)


def run(difficulty: str = "hard", out: Path | None = None) -> dict:
    """Draw the figure into a fresh run folder; returns ``{"folder", "png", "scenes"}`` (scene names per grid)."""
    grids = scene_grids(difficulty)
    folder = run_folder("scenes", out)
    png = folder / "scenes.png"
    draw_scene_grids(grids, png)
    names = {name: [[scene.name for scene in row] for row in grid] for name, grid in grids.items()}
    (folder / "scenes.json").write_text(json.dumps({"difficulty": difficulty, "scenes": names}, indent=2))
    return {"folder": folder, "png": png, "scenes": names}


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.scenes", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--difficulty", choices=FACTORIAL_DIFFICULTIES, default="hard",
                        help="difficulty of the Factorial panels (default hard)")
    parser.add_argument("--out", type=fresh_folder,
                        help="new or empty run folder (default: a fresh results/scenes/<timestamp>)")
    args = parser.parse_args(argv)
    result = run(args.difficulty, args.out)
    print(f"wrote {result['png']}")
    return result


if __name__ == "__main__":
    main()
