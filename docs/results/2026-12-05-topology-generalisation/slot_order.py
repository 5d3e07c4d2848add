"""Does the vertices policy know its training scenes by the order of their obstacle slots? Success on the 480
validation starts of the 48 Topology-Stress training scenes with the obstacles as stored, reversed, and shuffled
(seed 0). Run from the repository root: ``python docs/results/2026-12-05-topology-generalisation/slot_order.py``
(about two minutes)."""

import dataclasses

import numpy as np

from np_policy.planner import NeuralParkerPlanner
from np_sim.benchmarks import load_benchmark, validation_starts

CHECKPOINT = "checkpoints/runs/topology_np_vertices_seed0_lot/best.pt"


def orders(obstacles: tuple, rng: np.random.Generator) -> dict[str, tuple]:
    """The three obstacle orders of one scene."""
    return {"as stored": obstacles, "reversed": obstacles[::-1],
            "shuffled": tuple(obstacles[i] for i in rng.permutation(len(obstacles)))}


if __name__ == "__main__":
    scenes, starts = load_benchmark("topology", "train"), validation_starts("topology")
    planner = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, benchmark="topology")
    rng = np.random.default_rng(0)
    solved = {"as stored": 0, "reversed": 0, "shuffled": 0}
    for scene, poses in zip(scenes, starts):
        for name, obstacles in orders(scene.obstacles, rng).items():
            variant = dataclasses.replace(scene, obstacles=obstacles)
            solved[name] += sum(planner.plan(variant, pose).success for pose in poses)
    episodes = starts.shape[0] * starts.shape[1]
    for name, count in solved.items():
        print(f"obstacles {name}: {count} of {episodes} ({count / episodes:.3f})")
