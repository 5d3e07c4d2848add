"""A first look at the planning core: ``python -m np_sim.demo [--out DIR]``.

Runs the paper's full environment (vertices + LiDAR, 81-candidate Hermite ensemble) with 128 parallel episodes
of uniformly random arcs over the hand-made example scenes, reports throughput and outcomes, and draws, per
scene, the shortest successful random episode (its arcs, then the selected Hermite segment) to a PNG. It stands
in for the main job (``python -m experiments.closed_loop --clips``) until the closed loop exists.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from tqdm import tqdm

from np_sim.cli import cli_boundary, non_negative_int, output_folder, positive_int
from np_sim.env import EnvConfig, ParkingVectorEnv
from np_sim.examples import example_scenes
from np_sim.frames import from_target_frame
from np_sim.kinematics import sample_arc


def _episode_path(start: np.ndarray, arcs: list[tuple[float, float]], hermite_world: np.ndarray | None) -> np.ndarray:
    pts = [start[None, :2]]
    pose = start
    for kappa, length in arcs:
        seg = sample_arc(pose, kappa, length, 30)
        pts.append(seg[:, :2])
        pose = seg[-1]
    if hermite_world is not None:
        pts.append(hermite_world)
    return np.concatenate(pts)


@cli_boundary
def main(argv=None) -> dict:
    """Run the tour (module docstring); returns the outcome counts, the PNGs written and the throughput."""
    parser = argparse.ArgumentParser(prog="python -m np_sim.demo", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=output_folder, default=Path("results/demo"), help="folder for the PNGs")
    parser.add_argument("--steps", type=positive_int, default=400, help="vector-env steps (each steps 128 episodes)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of starts and actions")
    args = parser.parse_args(argv)

    scenes = [s for s in example_scenes() if s.tags.get("expect") != "no_path"]
    config = EnvConfig()
    env = ParkingVectorEnv(scenes, 128, config, seed=args.seed)
    rng = np.random.default_rng(args.seed)
    env.reset()
    starts = env.core.S[:, :3].copy()
    arcs: list[list[tuple[float, float]]] = [[] for _ in range(env.num_envs)]
    best: dict[int, tuple[float, np.ndarray]] = {}
    counts = {"episodes": 0, "success": 0, "hermite": 0, "collision": 0, "timeout": 0}
    t0 = time.perf_counter()
    for _ in tqdm(range(args.steps), desc="random arcs", unit="step", leave=False):
        actions = rng.uniform(-1, 1, (env.num_envs, 2)).astype(np.float32)
        # keep the raw arcs and Hermite candidates of this step before autoreset overwrites them
        _, _, term, trunc, info = env.step(actions)
        for i in np.flatnonzero(term | trunc):
            arcs[i].append((actions[i, 0] * config.vehicle.kappa_max, actions[i, 1] * config.episode.max_length_m))
            counts["episodes"] += 1
            counts["timeout"] += bool(trunc[i])
            counts["collision"] += bool(info["collision"][i])
            if info["success"][i]:
                counts["success"] += 1
                k = int(info["scene_index"][i])
                h = int(info["hermite_index"][i])
                counts["hermite"] += h >= 0
                hermite = from_target_frame(env.core.h_pts[i, h].T, scenes[k].target) if h >= 0 else None
                length = float(info["path_length"][i])
                if k not in best or length < best[k][0]:
                    best[k] = (length, _episode_path(starts[i], arcs[i], hermite))
        for i in np.flatnonzero(~(term | trunc)):
            arcs[i].append((actions[i, 0] * config.vehicle.kappa_max, actions[i, 1] * config.episode.max_length_m))
        for i in np.flatnonzero(term | trunc):
            arcs[i] = []
            starts[i] = env.core.S[i, :3]
    elapsed = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    from np_sim.plotting import plot_scene

    written = []
    for k, (length, path) in sorted(best.items()):
        fig = Figure(figsize=(7, 6))
        ax = fig.add_subplot()
        plot_scene(ax, scenes[k], path=path)
        ax.set_title(f"{scenes[k].name}: shortest random-arc success, L = {length:.1f} m")
        out = args.out / f"{scenes[k].name}.png"
        fig.savefig(out, dpi=110, bbox_inches="tight")
        written.append(out)
    steps = args.steps * env.num_envs
    print(f"{steps:,} env steps in {elapsed:.1f} s ({steps / elapsed:,.0f} steps/s, compile included)")
    print(f"episodes ended {counts['episodes']:,}: success {counts['success']:,} "
          f"({counts['hermite']:,} through the Hermite ensemble), collision {counts['collision']:,}, "
          f"timeout {counts['timeout']:,}")
    for out in written:
        print(f"wrote {out}")
    return {"counts": counts, "written": written, "steps_per_s": steps / elapsed}


if __name__ == "__main__":
    main()
