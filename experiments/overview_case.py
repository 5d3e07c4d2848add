"""Unified NeuralParker versus the staged Hybrid A* → learned planner on one pinned case (paper Fig. ``fig:overview``,
§V-A, Table ``tab:twostage``).

``python -m experiments.overview_case [--benchmark factorial|topology] [--checkpoint PATH] [--start-seed S]
[--out DIR]``

One checkpoint drives the unified arm and the staged arm's downstream stage (`np_policy.staged.StagedPlanner`: a
region-goal Hybrid A* prefix to the first state within 10 m of the target, then the policy from there). The case is
pinned on the **training** split by one rule: the first scene in benchmark order whose full-range start
(`np_sim.starts.UniformStartSampler`, seed ``--start-seed``) lies beyond the hand-off radius and that both arms
solve. No frozen test start is looked at.

- ``--benchmark topology`` is the paper's figure: a Topology-Stress pocket scene (Type 2, the route-choice family
  whose entrance faces away from the arrival side) driven by the Topology-Stress vertices policy (default
  ``POCKET_CHECKPOINT``, the NeuralParker-backbone vertices run of the sweep, seed 0).
- ``--benchmark factorial`` (the default until that run is finished) pins a long-range Factorial scene with the
  shipped Factorial checkpoint; as in the paper's diagnostic a third arm, Hybrid A* → adapted HOPE, plans the same
  case from the same start when the HOPE seed-0 checkpoint exists (``HOPE_CHECKPOINT``; drawn whether it succeeds
  or not: the case is pinned by the first two arms).

Writes ``overview_case.png`` (each planner one line; the staged arm's prefix, downstream arcs and connector share
the dashed green line; the dashed circle is the hand-off boundary), ``case.md`` (L, reversals, Δκ of eq:metrics,
the staged Δκ without the hand-off jump, and plan time per arm) and ``case.json`` into a fresh run folder.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from experiments.common import run_folder
from experiments.hermite_case import DEFAULT_CHECKPOINT, case_main, training_starts
from np_policy.planner import NeuralParkerPlanner
from np_policy.staged import StagedPlanner
from np_sim.benchmarks import load_benchmark
from np_sim.cli import cli_boundary
from np_sim.plan import Plan
from np_sim.plotting import plot_scene, target_marker
from np_sim.scene import Scene

UNIFIED, STAGED, STAGED_HOPE = "Unified NP", "Hybrid A* → NP", "Hybrid A* → HOPE"
HOPE_CHECKPOINT = Path("checkpoints/runs/factorial_hope_seed0/final.pt")
"""The adapted HOPE planner of the Factorial case's third arm (seed 0 of the complete baseline on Factorial)."""
POCKET_CHECKPOINT = Path("checkpoints/runs/topology_np_vertices_seed0_lot/best.pt")
"""The paper's policy for this figure: Topology-Stress, NeuralParker backbone with target-relative vertices, seed 0."""
CASE_SCENES = {"factorial": lambda scene: scene.tags.get("distance") == "long",
               "topology": lambda scene: scene.tags.get("family") == "type2"}
"""Which training scenes each benchmark's case may be pinned on: long-range Factorial scenes; Topology-Stress
pockets."""
DEFAULT_CHECKPOINTS = {"factorial": DEFAULT_CHECKPOINT, "topology": POCKET_CHECKPOINT}


def staged_note(benchmark: str, checkpoint: Path, hope: bool) -> str:
    """Which policy drives the learned arms and which planners the staged arms hand over to."""
    if benchmark == "topology":
        return (f"both learned arms are driven by the Topology-Stress vertices policy `{checkpoint}`, as in the "
                "paper's figure")
    if hope:
        return (f"the learned arms are driven by `{checkpoint}`; the staged arms hand over to NeuralParker and, as in "
                f"the paper's diagnostic, to the adapted HOPE planner (`{HOPE_CHECKPOINT}`); the case is pinned by "
                "the first two arms")
    return (f"the learned arms are driven by `{checkpoint}`; the paper's diagnostic also hands over to the adapted "
            f"HOPE planner, whose arm needs `{HOPE_CHECKPOINT}`")


def find_case(unified: NeuralParkerPlanner, staged: StagedPlanner, scenes: list[Scene],
              starts: np.ndarray) -> tuple[Scene, np.ndarray, dict[str, Plan]]:
    """The pinned case by the rule of the module docstring among ``scenes`` (already the benchmark's candidates):
    (scene, start, {arm: plan})."""
    for scene, start in zip(scenes, starts):
        if np.hypot(*(start[:2] - np.asarray(scene.target[:2], float))) <= staged.handoff_radius_m:
            continue
        plans = {UNIFIED: unified.plan(scene, start), STAGED: staged.plan(scene, start)}
        if all(plan.success for plan in plans.values()):
            return scene, start, plans
    raise RuntimeError("overview_case: no training start beyond the hand-off radius that both arms solve")


def compare_arms(plans: dict[str, Plan]) -> str:
    """One sentence: where the unified arm's path metrics (eq:metrics) are lower than the staged NeuralParker arm's
    on this case (the paper's Table II finds them lower in all three on average; one pinned case need not)."""
    ours, theirs = plans[UNIFIED].metrics(), plans[STAGED].metrics()
    names = ("L", "reversals", "Δκ")
    lower = [n for n, a, b in zip(names, ours, theirs) if a < b]
    rest = [n for n in names if n not in lower]

    def shown(metrics) -> str:
        return " / ".join(str(int(v)) if n == "reversals" else f"{v:.2f}" for n, v in zip(names, metrics))

    verdict = ("lower in all three" if not rest else "lower in none of them" if not lower
               else f"lower in {' and '.join(lower)}, not in {' and '.join(rest)}")
    return (f"On this case the unified arm's L / reversals / Δκ are {shown(ours)} against the staged arm's "
            f"{shown(theirs)}: {verdict}.")


def format_case(scene: Scene, plans: dict[str, Plan], note: str, plan_time: bool = True) -> str:
    """Markdown: one row per arm with eq:metrics and, with ``plan_time``, the plan time measured while the case was
    pinned (a failed arm: its reason)."""
    time_head, time_rule = (" plan time (ms) |", "---|") if plan_time else ("", "")
    lines = [f"Scene `{scene.name}` (training split); {note}.", "",
             f"| Arm | Succ. | L (m) | Rev. | Δκ |{time_head}", f"|---|---|---|---|---|{time_rule}"]
    for arm, plan in plans.items():
        time_cell = f" {1e3 * plan.plan_time_s:.1f} |" if plan_time else ""
        if not plan.success:
            lines.append(f"| {arm} | 0 ({plan.reason}) | – | – | – |{time_cell}")
            continue
        L, rev, dk = plan.metrics()
        lines.append(f"| {arm} | 1 | {L:.2f} | {rev} | {dk:.2f} |{time_cell}")
    return "\n".join(lines)


def draw_case(scene: Scene, plans: dict[str, Plan], radius_m: float, vehicle, png: Path) -> None:
    """Each planner one line over the scene, the hand-off circle and the hand-off pose."""
    figure = Figure(figsize=(10.0, 6.5), layout="constrained")
    ax = figure.add_subplot()
    plot_scene(ax, scene)
    ax.get_legend().remove()
    styles = {UNIFIED: dict(color="tab:blue", linestyle="-"), STAGED: dict(color="tab:green", linestyle="--"),
              STAGED_HOPE: dict(color="tab:orange", linestyle=":")}
    for arm, plan in plans.items():
        if not plan.success:
            continue
        L, rev, dk = plan.metrics()
        ax.plot(*plan.sample(0.1)[:, :2].T, linewidth=2.0, **styles[arm],
                label=f"{arm} (L {L:.1f} m, {rev} rev., Δκ {dk:.2f})")
    staged = plans[STAGED]
    handoff = staged.sample(0.1)[0] if staged.handoff_index == 0 else Plan(
        start=staged.start, arcs=staged.arcs[: staged.handoff_index]).sample(0.1)[-1]
    bar, stem = target_marker(handoff[:3], vehicle)
    ax.plot(*bar.T, color="tab:green", linewidth=2.0, label="hand-off pose")
    ax.plot(*stem.T, color="tab:green", linewidth=2.0)
    ax.add_patch(Circle(tuple(np.asarray(scene.target[:2], float)), radius_m, fill=False, linestyle="--",
                        edgecolor="0.4", label=f"{radius_m:g} m hand-off boundary"))
    downstream = "NeuralParker and HOPE" if STAGED_HOPE in plans else "NeuralParker"
    ax.set_title(f"{scene.name}\nunified versus staged ({downstream} downstream)", fontsize="medium")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
    figure.savefig(png, dpi=120)


def run(checkpoint: Path | None = None, start_seed: int = 0, out: Path | None = None,
        scenes: list[Scene] | None = None, benchmark: str = "factorial") -> dict:
    """Pin the case on ``benchmark``'s training scenes (``scenes``: the candidates to pin it on, default that
    benchmark's ``CASE_SCENES``), draw it and write its table. ``checkpoint`` defaults to ``DEFAULT_CHECKPOINTS``.
    Returns the folder, the PNG, the table with plan times (``table``) and without them (``path_table``: what a
    report regenerated on another machine, or under another load, can quote unchanged)."""
    if benchmark not in CASE_SCENES:
        raise ValueError(f"overview_case: benchmark must be one of {sorted(CASE_SCENES)}, got {benchmark!r}")
    checkpoint = Path(DEFAULT_CHECKPOINTS[benchmark] if checkpoint is None else checkpoint)
    unified = NeuralParkerPlanner.from_checkpoint(checkpoint, benchmark=benchmark)
    staged = StagedPlanner(unified)
    if scenes is None:
        scenes = [s for s in load_benchmark(benchmark, "train") if CASE_SCENES[benchmark](s)]
    scene, start, plans = find_case(unified, staged, scenes, training_starts(scenes, start_seed))
    if benchmark == "factorial" and Path(HOPE_CHECKPOINT).exists():
        from hope_policy.planner import HopePlanner

        plans[STAGED_HOPE] = StagedPlanner(HopePlanner.from_checkpoint(HOPE_CHECKPOINT), staged.search,
                                           name="staged_astar_hope").plan(scene, start)
    folder = run_folder("overview_case", out)
    draw_case(scene, plans, staged.handoff_radius_m, unified.env_config.vehicle, folder / "overview_case.png")
    note = staged_note(benchmark, checkpoint, STAGED_HOPE in plans)
    table = format_case(scene, plans, note)
    (folder / "case.md").write_text(table + "\n")
    (folder / "case.json").write_text(json.dumps({
        "benchmark": benchmark, "checkpoint": str(checkpoint), "start_seed": start_seed, "scene": scene.name,
        "start": start.tolist(), "note": note,
        "arms": {arm: dict(zip(("L", "reversals", "delta_kappa"), plan.metrics()), success=plan.success,
                           plan_time_s=plan.plan_time_s) for arm, plan in plans.items()}}, indent=2, default=float))
    return {"folder": folder, "png": folder / "overview_case.png", "table": table, "scene": scene.name,
            "path_table": format_case(scene, plans, note, plan_time=False), "comparison": compare_arms(plans)}


@cli_boundary
def main(argv=None) -> dict:
    """Command-line entry point (usage in the module docstring)."""
    return case_main("overview_case", __doc__, run, argv, benchmarks=tuple(CASE_SCENES))


if __name__ == "__main__":
    main()
