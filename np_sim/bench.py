"""Throughput of the planning core: ``python -m np_sim.bench [--json]``.

Measures, in one run on the hand-made example scenes with the paper's full configuration (vertices + LiDAR,
81-candidate Hermite ensemble, reference-point checks) and uniformly random arcs:

* single-env and 128-env vector-env steps per second (resets included);
* the plain reference step (Python loops + shapely, ``tests/reference_step.py``, the way a per-step research env
  such as HOPE's works) and the vector env's speed-up over it;
* microbenchmarks: one 30-sample arc check, one 120-beam cast, one ensemble connection (gate open), and the
  footprint check of a sampled path per pose (`np_sim.collision.path_valid`, the planners' plan checks).

Targets on the 2-core development machine are printed beside each figure.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

from np_sim.cli import cli_boundary, non_negative_int, positive_float, positive_int
from np_sim.config import EnvConfig
from np_sim.env import ParkingEnv, ParkingVectorEnv
from np_sim.examples import example_scenes
from np_sim.frames import pose_to_target_frame
from np_sim.hermite import _candidate_sets
from np_sim.kernels.collision import arc_valid, footprint_valid, poses_valid
from np_sim.kernels.geometry import cast_beams
from np_sim.kernels.hermite import select_candidate
from np_sim.scene_arrays import pack_scenes
from np_sim.starts import UniformStartSampler

TARGETS = {
    "vector_env_steps_per_s": (">=", 25_000.0, "floor 12,000"),
    "speedup_vs_plain_step": (">=", 100.0, ""),
    "ensemble_connect_us": ("<=", 100.0, "median"),
    "cast_120_us": ("<=", 20.0, ""),
    "footprint_path_ns_per_pose": ("<=", 200.0, "(553 before the inlined, chunked check)"),
}


def _timed(fn, min_seconds: float) -> tuple[int, float]:
    """Call ``fn`` (returns units of work done) until ``min_seconds`` pass; (units, seconds)."""
    units, start = 0, time.perf_counter()
    while True:
        units += fn()
        elapsed = time.perf_counter() - start
        if elapsed >= min_seconds:
            return units, elapsed


def bench_vector_env(scenes, config, num_envs: int, seconds: float, seed: int) -> float:
    """Env steps per second of ``ParkingVectorEnv`` with ``num_envs`` envs on random actions, over ``seconds``."""
    env = ParkingVectorEnv(scenes, num_envs, config, seed=seed)
    env.reset()
    rng = np.random.default_rng(seed)
    env.step(rng.uniform(-1, 1, (num_envs, 2)).astype(np.float32))  # compile / warm caches

    def work():
        env.step(rng.uniform(-1, 1, (num_envs, 2)).astype(np.float32))
        return num_envs

    units, elapsed = _timed(work, seconds)
    return units / elapsed


def bench_single_env(scenes, config, seconds: float, seed: int) -> float:
    """Env steps per second of one gymnasium ``ParkingEnv`` on random actions, over ``seconds``."""
    env = ParkingEnv(scenes, config)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)

    def work():
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        if term or trunc:
            env.reset()
        return 1

    units, elapsed = _timed(work, seconds)
    return units / elapsed


def _load_reference_step():
    path = Path(__file__).resolve().parents[1] / "tests" / "reference_step.py"
    if not path.exists():
        return None
    spec = importlib.util.spec_from_file_location("np_reference_step", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def bench_plain_step(scenes, config, seconds: float, seed: int) -> float | None:
    """Steps per second of the plain-Python reference step (``tests/reference_step.py``, the figure the compiled
    env is compared with); None where the tests folder is not there."""
    ref = _load_reference_step()
    if ref is None:
        return None
    rng = np.random.default_rng(seed)
    sampler = UniformStartSampler(scenes, config.vehicle)
    state = {}

    def new_episode():
        k = int(rng.integers(len(scenes)))
        state.update(k=k, pose=sampler(rng, [k])[0], prev_kappa=0.0, prev_length=0.0, first=True, n_rev=0, dk_eff=0.0,
                     n_arcs=0)

    new_episode()

    def work():
        a = rng.uniform(-1, 1, 2)
        out = ref.reference_step(scenes[state["k"]], state["pose"], state["prev_kappa"], state["prev_length"],
                                 state["first"], state["n_rev"], state["dk_eff"], state["n_arcs"], a, config)
        if out["terminated"] or out["truncated"]:
            new_episode()
        else:
            state.update(pose=out["pose"], first=False, n_rev=out["n_rev"], dk_eff=out["dk_eff"],
                         n_arcs=state["n_arcs"] + 1, prev_kappa=a[0] * config.vehicle.kappa_max,
                         prev_length=a[1] * config.episode.max_length_m)
        return 1

    units, elapsed = _timed(work, seconds)
    return units / elapsed


@njit(cache=True)
def _arc_checks(geo, ks, starts, arcs, n_samples, local) -> int:
    corners = np.empty((4, 2))
    n_valid = 0
    for i in range(ks.shape[0]):
        n_valid += arc_valid(geo, ks[i], starts[i, 0], starts[i, 1], starts[i, 2], arcs[i, 0], arcs[i, 1],
                             n_samples, False, local, corners)
    return n_valid


def _valid_paths(geo, poses, local, rng, length: int = 400) -> list:
    """(scene, path) pairs: from each start a smooth random path of poses 5 cm apart, cut before its first pose in
    collision (the footprint convention), so that every path checked is valid to its end."""
    corners = np.empty((4, 2))
    paths = []
    for k, start in poses:
        turn = np.cumsum(rng.normal(0.0, 0.02, length))
        heading = start[2] + turn
        xy = start[:2] + np.cumsum(0.05 * np.stack([np.cos(heading), np.sin(heading)], axis=1), axis=0)
        path = np.ascontiguousarray(np.column_stack([xy, heading]))
        free = [footprint_valid(geo, k, *pose, local, corners) for pose in path]
        end = free.index(False) if False in free else length
        if end:
            paths.append((int(k), np.ascontiguousarray(path[:end])))
    return paths


def bench_kernels(scenes, config, seed: int) -> dict[str, float]:
    """Cost per call of the compiled kernels on random poses: the footprint path check (ns per pose), one 30-sample
    arc check and one 120-beam cast (µs), one ensemble connection (median and p90, µs)."""
    arrays = pack_scenes(scenes)
    geo = arrays.geometry
    local = config.vehicle.footprint_local()
    rng = np.random.default_rng(seed)
    sampler = UniformStartSampler(scenes, config.vehicle, arrays=arrays)
    ks = rng.integers(len(scenes), size=64)
    poses = list(zip(ks, sampler(rng, ks)))

    # one 30-sample arc check (sampling + reference-point checks), looped inside one compiled call so the
    # figure is the check itself, not numba's per-call argument dispatch
    arcs = rng.uniform(-1, 1, (len(poses), 2)) * [config.vehicle.kappa_max, config.episode.max_length_m]
    ks = np.array([k for k, _ in poses], np.int64)
    starts = np.array([p for _, p in poses])

    def arc_check():
        _arc_checks(geo, ks, starts, arcs, config.episode.samples_per_arc, local)
        return len(poses)

    # one 120-beam cast
    out = np.empty(config.observation.n_beams)

    def cast():
        for k, p in poses:
            cast_beams(p[0], p[1], p[2], arrays.segs[k], int(arrays.n_segs[k]), len(out),
                       config.observation.lidar_range_m, out)
        return len(poses)

    # one ensemble connection from gate-open poses 3–12 m from the target
    cands = _candidate_sets(config.connector)
    queries = []
    while len(queries) < 64:
        k = int(rng.integers(len(scenes)))
        tgt = arrays.targets[k]
        r, ang = rng.uniform(3, 12), rng.uniform(-math.pi, math.pi)
        pose = np.array([tgt[0] + r * math.cos(ang), tgt[1] + r * math.sin(ang), tgt[2] + rng.normal(0, 0.7)])
        pt = pose_to_target_frame(pose, tgt)
        if math.sin(pt[2]) > 0:
            queries.append((k, tgt, pt))
    times = []
    for k, tgt, pt in queries * 5:
        t0 = time.perf_counter()
        n = cands.build(pt, 0.1, bool(pt[1] < 0))
        select_candidate(geo, k, tgt, pt[0], pt[1], pt[2], bool(pt[1] < 0), cands.offsets, cands.headings,
                         cands.scales0, cands.scales1, cands.dbasis, cands.pts, cands.kbar_max, cands.costs, n, True,
                         config.connector.kappa_max, False, local)
        times.append(time.perf_counter() - t0)
    paths = _valid_paths(geo, poses, local, rng)

    def path_check():
        return sum(len(path) for k, path in paths if poses_valid(geo, k, path, True, local))

    arc_check()
    cast()
    u_arc, t_arc = _timed(arc_check, 0.5)
    u_cast, t_cast = _timed(cast, 0.5)
    u_path, t_path = _timed(path_check, 0.5)
    return {
        "footprint_path_ns_per_pose": 1e9 * t_path / u_path,
        "arc_check_us": 1e6 * t_arc / u_arc,
        "cast_120_us": 1e6 * t_cast / u_cast,
        "ensemble_connect_us": 1e6 * float(np.median(times[64:])),
        "ensemble_connect_p90_us": 1e6 * float(np.percentile(times[64:], 90)),
    }


def run(seconds: float = 3.0, num_envs: int = 128, seed: int = 0) -> dict[str, float]:
    """All measurements as a dict (keys of spec §10 included)."""
    scenes = example_scenes()
    config = EnvConfig()
    result = {"num_envs": num_envs}
    result["vector_env_steps_per_s"] = bench_vector_env(scenes, config, num_envs, seconds, seed)
    result["single_env_steps_per_s"] = bench_single_env(scenes, config, seconds, seed)
    plain = bench_plain_step(scenes, config, seconds, seed)
    if plain is not None:
        result["plain_step_steps_per_s"] = plain
        result["speedup_vs_plain_step"] = result["vector_env_steps_per_s"] / plain
    result.update(bench_kernels(scenes, config, seed))
    return result


def _format(result: dict[str, float]) -> str:
    lines = [f"{'measurement':<28} {'value':>14}   target"]
    for key, value in result.items():
        target = TARGETS.get(key)
        mark = ""
        if target:
            op, goal, note = target
            ok = value >= goal if op == ">=" else value <= goal
            mark = f"{op} {goal:,.0f} {note}".rstrip() + ("  ok" if ok else "  MISSED")
        lines.append(f"{key:<28} {value:>14,.2f}   {mark}")
    return "\n".join(lines)


@cli_boundary
def main(argv=None) -> dict[str, float]:
    """Run the measurements (module docstring) and print them; returns them as a dict."""
    parser = argparse.ArgumentParser(prog="python -m np_sim.bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    parser.add_argument("--seconds", type=positive_float, default=3.0, help="time per throughput measurement (s)")
    parser.add_argument("--num-envs", type=positive_int, default=128, help="vector-env width")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of actions and starts")
    args = parser.parse_args(argv)
    result = run(args.seconds, args.num_envs, args.seed)
    print(json.dumps(result) if args.json else _format(result))
    return result


if __name__ == "__main__":
    main()
