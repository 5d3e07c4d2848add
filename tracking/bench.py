"""Closed-loop speed: simulated time per wall-clock time for one vehicle (goal ≥ 50× unrendered).

``python -m tracking.bench [--repeats N] [--json]``

The workload is a two-gear parking manoeuvre with a cusp (forward curve and straight, reverse curve and straight,
16 m) in a 30 m × 24 m lot with two obstacles, executed by the LQR tracker: unrendered; with
Rerun logging to a temporary ``.rrd``; with off-screen rendering of both cameras at the executor's frame rate and
size (``MUJOCO_GL=egl``). The raw MuJoCo step rate of the same world is printed for reference.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

from np_sim.cli import cli_boundary, positive_int
from np_sim.kinematics import arc_step
from np_sim.plan import Plan
from np_sim.scene import Scene
from tracking.config import TrackerConfig
from tracking.executor import execute
from tracking.world import build_world

GOAL_REALTIME = 50.0
"""Unrendered real-time factor the closed loop must reach for one vehicle."""

_ARCS = np.array([[0.2, 6.0], [0.0, 3.0], [-0.4, -5.0], [0.0, -2.0]])
"""The benchmark manoeuvre (κ, l)."""


def _workload() -> tuple[Scene, Plan]:
    plan = Plan(start=np.array([-6.0, -3.0, 0.3]), arcs=_ARCS, success=True)
    end = plan.start
    for kappa, length in _ARCS:
        end = arc_step(end, kappa, length)
    scene = Scene.from_dict({"boundary": [[-15, -12], [15, -12], [15, 12], [-15, 12]],
                             "obstacles": [{"polygon": [[8, 6], [11, 6], [11, 8], [8, 8]]}, {"circle": [-9, 7, 1]}],
                             "target": end.tolist(), "name": "bench"})
    return scene, plan


def realtime_factor(repeats: int, **kwargs) -> float:
    """Σ sim time / Σ wall time of ``repeats`` executions of the workload (keyword arguments go to `execute`)."""
    scene, plan = _workload()
    sim = wall = 0.0
    for _ in range(repeats):
        record = execute(scene, plan, **kwargs)
        if not record.success:
            raise RuntimeError(f"bench workload failed: {record.reason} {record.detail}")
        sim += record.sim_time_s
        wall += record.wall_time_s
    return sim / wall


def mj_steps_per_s(seconds: float = 1.0) -> float:
    """Raw ``mj_step`` rate of the workload world with the vehicle coasting."""
    scene, plan = _workload()
    world = build_world(scene, plan.start)
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        mujoco.mj_step(world.model, world.data, nstep=100)
        n += 100
    return n / (time.perf_counter() - t0)


def run(repeats: int = 5) -> dict[str, float]:
    """All figures of the module docstring."""
    execute(*_workload())  # warm-up: numba kernels, LQR gain table
    with tempfile.TemporaryDirectory() as tmp:
        logged = realtime_factor(repeats, rerun_path=Path(tmp) / "bench.rrd")
    ec = TrackerConfig().executor
    return {"realtime_unrendered": realtime_factor(repeats), "realtime_rerun_unrendered": logged,
            "realtime_rendered": realtime_factor(max(1, repeats // 5), render=True),
            "render_fps": ec.render_fps, "render_size": f"{ec.render_width}x{ec.render_height}",
            "mj_steps_per_s": mj_steps_per_s(), "timestep_s": TrackerConfig().model.timestep_s,
            "control_dt_s": ec.control_dt_s, "goal_realtime": GOAL_REALTIME}


@cli_boundary
def main(argv=None) -> dict[str, float]:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options)."""
    parser = argparse.ArgumentParser(prog="python -m tracking.bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=positive_int, default=5, help="executions per unrendered figure")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    figures = run(args.repeats)
    if args.json:
        print(json.dumps(figures))
        return figures
    print(f"closed loop, one vehicle (physics {figures['timestep_s'] * 1e3:.0f} ms, control "
          f"{figures['control_dt_s'] * 1e3:.0f} ms):")
    print(f"  unrendered            {figures['realtime_unrendered']:7.1f}× real time   (goal ≥ {GOAL_REALTIME:.0f}×)")
    print(f"  unrendered + Rerun    {figures['realtime_rerun_unrendered']:7.1f}× real time")
    print(f"  rendered (2 cameras, {figures['render_size']} at {figures['render_fps']:.0f} fps of sim time) "
          f"{figures['realtime_rendered']:7.1f}× real time")
    print(f"  raw mj_step           {figures['mj_steps_per_s']:9.0f} steps/s")
    return figures


if __name__ == "__main__":
    main()
