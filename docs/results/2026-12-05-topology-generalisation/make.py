"""Per-scene success of the Topology-Stress rows measured so far, and the NeuralParker-backbone vertices policy's
mean rollouts on the four test scenes it fails most (the files of this page).

Run from the repository root: ``python docs/results/2026-12-05-topology-generalisation/make.py``.
"""

import collections
import csv
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from np_policy.planner import NeuralParkerPlanner  # noqa: E402
from np_sim.benchmarks import frozen_starts, load_benchmark  # noqa: E402
from np_sim.kinematics import sample_arc  # noqa: E402
from np_sim.plotting import plot_scene  # noqa: E402

HERE = Path(__file__).resolve().parent
RUNS = Path("checkpoints/runs")
ROWS = {"NP vertices s0": "topology_np_vertices_seed0_lot", "NP none s0": "topology_np_none_seed0_lot",
        "HOPE-style vertices s0": "topology_hope_vertices_seed0",
        "HOPE-style vertices s1": "topology_hope_vertices_seed1",
        "HOPE-style vertices s2": "topology_hope_vertices_seed2", "HOPE-style none s0": "topology_hope_none_seed0",
        "HOPE-style BEV s0": "topology_hope_bev_seed0"}
CASES = [("topology-test-type3-medium-2", 0), ("topology-test-type3-hard-1", 0), ("topology-test-type3-hard-2", 0),
         ("topology-test-type1-medium-2", 3)]


def per_scene_table() -> str:
    """Markdown: success per test scene (40 frozen starts each) for every row."""
    success = {}
    for label, run in ROWS.items():
        by_scene = collections.defaultdict(list)
        with (RUNS / run / "eval_topology" / "records.csv").open(newline="") as fh:
            for row in csv.DictReader(fh):
                by_scene[row["scene"]].append(int(row["success"]))
        success[label] = {scene: np.mean(v) for scene, v in by_scene.items()}
    scenes = list(next(iter(success.values())))
    lines = ["| test scene | " + " | ".join(ROWS) + " |", "|---" * (len(ROWS) + 1) + "|"]
    lines += [f"| {s} | " + " | ".join(f"{success[label][s]:.2f}" for label in ROWS) + " |" for s in scenes]
    return "\n".join(lines) + "\n"


def failure_figure(png: Path) -> None:
    """The vertices policy's deterministic rollout (first 60 arcs) from one frozen start of each case."""
    scenes, starts = load_benchmark("topology", "test"), frozen_starts("topology")
    names = [s.name for s in scenes]
    planner = NeuralParkerPlanner.from_checkpoint(RUNS / ROWS["NP vertices s0"] / "best.pt", benchmark="topology")
    fig, axes = plt.subplots(1, len(CASES), figsize=(5 * len(CASES), 5))
    for ax, (name, j) in zip(axes, CASES):
        k = names.index(name)
        plan = planner.plan(scenes[k], starts[k, j])
        pose, points = np.array(starts[k, j], float), [starts[k, j][:2]]
        for kappa, length in plan.arcs[:60]:
            samples = sample_arc(pose, kappa, length, 10)
            points.extend(samples[1:, :2])
            pose = samples[-1]
        plot_scene(ax, scenes[k], np.array(points))
        ax.set_title(f"{name} start {j}: {plan.reason or 'success'}, {len(plan.arcs)} arcs", fontsize=9)
        ax.get_legend().remove() if ax.get_legend() else None
    fig.tight_layout()
    fig.savefig(png, dpi=80)


if __name__ == "__main__":
    (HERE / "per_scene.md").write_text(per_scene_table())
    failure_figure(HERE / "failures.png")
    print((HERE / "per_scene.md").read_text())
