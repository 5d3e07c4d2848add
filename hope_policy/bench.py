"""Speed of the adapted HOPE baseline beside HOPE's published environment: ``python -m hope_policy.bench
[--benchmark factorial] [--envs 16] [--steps 200] [--plans 100] [--checkpoint PATH] [--bev-encoder FILE] [--json]``.

* **Env step**: ``--steps`` steps of ``--envs`` environments stepped together (the trainer's batch), uniform random
  actions, for the complete baseline (42-anchor action mask and Reeds–Shepp takeover on) and the Table III
  backbones (none, vertices, and BEV with ``--bev-encoder``: raster plus frozen encoder); one warm-up step first
  loads the compiled kernels. Printed per env step beside HOPE's published environment (``jiamiya/HOPE``: a
  Python per-step env with shapely checks and a pygame raster, about 9.2 ms per step, 110 steps/s).
* **Training**: the wall clock, env steps and episodes of every finished adapted-HOPE run under
  ``checkpoints/runs/`` (collect and update seconds summed from its ``metrics.jsonl``; those runs shared this
  machine with other jobs, so they are upper figures); HOPE's published training runs about 46 steps/s end to
  end.
* **Planning**: ``HopePlanner.plan`` per query (the deterministic rollout plus validation) on the first
  ``--plans`` frozen test starts with ``--checkpoint`` (default: seed 0's ``final.pt``).

Time it on an idle machine: pause a training run (``kill -STOP``) first.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from hope_policy.config import HopeEnvConfig
from hope_policy.env import HopeVectorEnv
from hope_policy.inputs import PolicyInputs
from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.cli import cli_boundary, existing_file, positive_int

HOPE_ENV_STEP_MS = 9.2
"""HOPE's published environment, ms per env step (docs/specification.md)."""
HOPE_TRAIN_STEPS_PER_S = 46.0
"""HOPE's published training, env steps per second end to end."""
RUNS = Path("checkpoints/runs")
DEFAULT_CHECKPOINT = RUNS / "factorial_hope_seed0" / "final.pt"


def env_variants(bev_encoder: Path | None) -> dict[str, tuple[HopeEnvConfig, str]]:
    """(env config, BEV encoder file) of the complete baseline and each backbone (BEV only with an encoder)."""
    variants = {"complete baseline (mask + RS takeover)": (HopeEnvConfig(), ""),
                "backbone: none": (HopeEnvConfig.backbone("none"), ""),
                "backbone: vertices": (HopeEnvConfig.backbone("vertices"), "")}
    if bev_encoder is not None:
        variants["backbone: BEV (raster + frozen encoder)"] = (HopeEnvConfig.backbone("bev"), str(bev_encoder))
    return variants


def time_env(scenes, config: HopeEnvConfig, bev_encoder: str, envs: int, steps: int) -> dict:
    """Milliseconds per env step of ``steps`` batched steps of ``envs`` envs (random actions; inputs prepared as
    the trainer prepares them, the BEV raster encoded)."""
    env = HopeVectorEnv(scenes, envs, config, seed=0)
    inputs = PolicyInputs(config, bev_encoder)
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=0)
    obs, *_ = env.step(rng.uniform(-1.0, 1.0, (envs, 2)))  # warm-up: compiled kernels loaded
    started = time.perf_counter()
    ended = 0
    for _ in range(steps):
        inputs(obs)
        obs, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, (envs, 2)))
        ended += int((terminated | truncated).sum())
    seconds = time.perf_counter() - started
    per_step_ms = 1e3 * seconds / (steps * envs)
    return {"ms_per_env_step": per_step_ms, "env_steps_per_s": 1e3 / per_step_ms, "episodes_ended": ended,
            "speed_up_vs_hope": HOPE_ENV_STEP_MS / per_step_ms}


def training_runs(root: Path = RUNS) -> list[dict]:
    """Wall clock, env steps and episodes of every finished adapted-HOPE run (a ``final.pt`` beside its
    ``metrics.jsonl``)."""
    out = []
    for run in sorted(root.glob("*hope*")):
        if not (run / "final.pt").exists() or not (run / "metrics.jsonl").exists():
            continue
        rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines() if line.strip()]
        seconds = sum(r["collect_s"] + r["update_s"] for r in rows)
        steps = rows[-1]["env_steps"]
        out.append({"run": run.name, "updates": len(rows), "episodes": rows[-1]["episodes"], "env_steps": steps,
                    "hours": seconds / 3600.0, "env_steps_per_s": steps / seconds})
    return out


def time_plans(benchmark: str, checkpoint: Path, plans: int) -> dict:
    """Per-query plan time and success of the adapted HOPE planner on the first ``plans`` frozen starts."""
    from hope_policy.planner import HopePlanner

    planner = HopePlanner.from_checkpoint(checkpoint)
    scenes, starts = load_benchmark(benchmark, "test"), frozen_starts(benchmark)
    episodes = [(k, j) for k in range(len(scenes)) for j in range(len(starts[k]))][:plans]
    planner.plan(scenes[0], starts[0][0])  # warm-up
    results = [planner.plan(scenes[k], starts[k][j]) for k, j in episodes]
    times = np.array([p.plan_time_s for p in results]) * 1e3
    return {"queries": len(results), "success": float(np.mean([p.success for p in results])),
            "plan_time_median_ms": float(np.median(times)), "plan_time_p90_ms": float(np.percentile(times, 90))}


def report(figures: dict) -> str:
    """The figures as text, each beside the figure to beat."""
    lines = [f"env step ({figures['envs']} envs together, random actions; HOPE's published env: "
             f"{HOPE_ENV_STEP_MS} ms per step, {1e3 / HOPE_ENV_STEP_MS:.0f} steps/s)"]
    for name, f in figures["env"].items():
        lines.append(f"  {name:42s} {f['ms_per_env_step']:7.3f} ms  {f['env_steps_per_s']:8.0f} steps/s  "
                     f"{f['speed_up_vs_hope']:6.1f}× HOPE's")
    lines.append(f"training, finished runs (HOPE's published training: about {HOPE_TRAIN_STEPS_PER_S:.0f} steps/s "
                 "end to end; these shared the machine)")
    for r in figures["training"]:
        lines.append(f"  {r['run']:42s} {r['hours']:5.2f} h  {r['episodes']} episodes  {r['env_steps']} steps  "
                     f"{r['env_steps_per_s']:6.0f} steps/s")
    p = figures.get("planning")
    if p:
        lines.append(f"planning ({p['queries']} frozen starts, {figures['checkpoint']}): median "
                     f"{p['plan_time_median_ms']:.1f} ms, p90 {p['plan_time_p90_ms']:.1f} ms, success "
                     f"{p['success']:.3f}")
    return "\n".join(lines)


@cli_boundary
def main(argv: list[str] | None = None) -> dict:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m hope_policy.bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=["factorial", "topology"], default="factorial")
    parser.add_argument("--envs", type=positive_int, default=16, help="envs stepped together (the trainer's 16)")
    parser.add_argument("--steps", type=positive_int, default=200, help="timed batched steps per variant")
    parser.add_argument("--plans", type=int, default=100, help="planning queries (0: none)")
    parser.add_argument("--checkpoint", type=existing_file, default=None,
                        help=f"adapted-HOPE checkpoint of the planning figure (default {DEFAULT_CHECKPOINT})")
    parser.add_argument("--bev-encoder", type=existing_file, default=None,
                        help="pretrained BEV autoencoder: adds the BEV backbone's env step")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args(argv)
    scenes = load_benchmark(args.benchmark, "train")
    figures = {"envs": args.envs, "env": {name: time_env(scenes, config, encoder, args.envs, args.steps)
                                          for name, (config, encoder) in env_variants(args.bev_encoder).items()},
               "training": training_runs()}
    checkpoint = args.checkpoint or DEFAULT_CHECKPOINT
    if args.plans > 0 and Path(checkpoint).exists():
        figures["checkpoint"] = str(checkpoint)
        figures["planning"] = time_plans(args.benchmark, Path(checkpoint), args.plans)
    print(json.dumps(figures, indent=2) if args.json else report(figures))
    return figures


if __name__ == "__main__":
    main()
