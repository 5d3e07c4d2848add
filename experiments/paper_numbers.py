"""The paper's simulation results as printed, transcribed from its LaTeX source (§V, Tables and Figures by label).

Each table is a `PaperTable`: its label, the benchmark, the episodes per seed the success column uses, the
common-success cohort sizes of the caption (one per seed) and its rows, each metric a (three-seed mean, sample SD)
pair exactly as printed. Figures whose values are drawn as bars only (``fig:main-comparison``,
``fig:global-family``) carry the cohort sizes and the claim of their caption and text, not numbers.
``tests/experiments/test_paper_report.py`` checks the transcription against the LaTeX source where it is present.
"""

from __future__ import annotations

from dataclasses import dataclass

METRICS = ("success", "L", "reversals", "delta_kappa")
"""Column keys of every simulation table: Succ. (up), L in m (down), Rev. (down), Δκ (down)."""
HIGHER_IS_BETTER = {"success": True, "L": False, "reversals": False, "delta_kappa": False}
"""Direction of each metric (the paper's arrows)."""
METRIC_NAMES = {"success": "Succ.", "L": "L (m)", "reversals": "Rev.", "delta_kappa": "Δκ"}
"""Column headings."""


@dataclass(frozen=True)
class PaperRow:
    """One row of a paper table: its label and each metric's printed (mean, sample SD) over three seeds."""

    label: str
    values: dict[str, tuple[float, float]]


@dataclass(frozen=True)
class PaperTable:
    """One of the paper's simulation tables (or a bar figure, with no rows)."""

    label: str
    """The LaTeX label, e.g. ``tab:hermite``."""
    number: str
    """How the project names it (docs/sweep.md): e.g. "Table IV"."""
    title: str
    benchmark: str
    episodes_per_seed: int
    cohort: tuple[int, ...]
    """Common-success cohort size per seed, from the caption."""
    rows: tuple[PaperRow, ...] = ()


def _row(label: str, *pairs: tuple[float, float]) -> PaperRow:
    return PaperRow(label, dict(zip(METRICS, pairs)))


TWOSTAGE = PaperTable(
    "tab:twostage", "Table II", "Unified versus staged planning", "factorial", 1080, (700, 719, 726), (
        _row("Unified NP", (0.974, 0.007), (19.77, 0.41), (1.02, 0.10), (1.77, 0.10)),
        _row("Hybrid A* → NP", (0.969, 0.002), (22.22, 0.50), (1.42, 0.05), (3.05, 0.09)),
        _row("Hybrid A* → HOPE", (0.686, 0.014), (36.36, 0.38), (6.97, 0.34), (5.16, 0.10)),
    ))
TOPOLOGY_STRESS = PaperTable(
    "tab:topology-stress", "Table III", "Scene-representation ablation on Topology-Stress", "topology", 720,
    (328, 317, 281), (
        _row("NeuralParker backbone: none", (0.897, 0.010), (37.84, 4.01), (2.96, 0.58), (5.74, 0.69)),
        _row("NeuralParker backbone: BEV", (0.848, 0.030), (38.72, 1.07), (4.41, 0.27), (6.25, 0.35)),
        _row("NeuralParker backbone: vertices", (0.916, 0.023), (35.40, 0.93), (2.77, 0.10), (5.06, 0.55)),
        _row("HOPE-style backbone: none", (0.690, 0.018), (58.53, 1.54), (21.70, 1.03), (13.34, 0.63)),
        _row("HOPE-style backbone: BEV", (0.763, 0.100), (58.03, 2.61), (20.74, 4.21), (13.48, 1.54)),
        _row("HOPE-style backbone: vertices", (0.808, 0.103), (49.79, 4.71), (16.95, 3.59), (10.85, 1.47)),
    ))
HERMITE = PaperTable(
    "tab:hermite", "Table IV", "Terminal-connector ablation", "factorial", 1080, (1003, 1000, 1015), (
        _row("Fixed Hermite", (0.965, 0.007), (20.13, 0.69), (1.37, 0.09), (2.36, 0.15)),
        _row("Ensemble, eval. only", (0.972, 0.006), (18.76, 0.23), (1.11, 0.06), (1.91, 0.07)),
        _row("Ensemble, train + eval.", (0.974, 0.007), (18.69, 0.11), (1.15, 0.06), (1.86, 0.08)),
    ))
CURRICULUM = PaperTable(
    "tab:app-controls", "Table V", "Start-curriculum ablation", "factorial", 1080, (1043, 1005, 1028), (
        _row("No curriculum", (0.969, 0.015), (19.90, 0.75), (1.43, 0.10), (2.23, 0.12)),
        _row("Geodesic curriculum", (0.974, 0.007), (18.76, 0.16), (1.17, 0.05), (1.90, 0.06)),
    ))
MAIN_COMPARISON = PaperTable(
    "fig:main-comparison", "Fig. 3", "NeuralParker versus the adapted HOPE planner (bar chart)", "factorial", 1080,
    (773, 748, 790))
GLOBAL_FAMILY = PaperTable(
    "fig:global-family", "Fig. 5", "Family-level success on Topology-Stress (bar chart)", "topology", 240, ())
TABLES = (TWOSTAGE, TOPOLOGY_STRESS, HERMITE, CURRICULUM)
"""The tables with printed numbers, in the project's order."""
FIGURES = {
    "fig:sceneexamples": "Fig. 2",
    "fig:main-comparison": "Fig. 3",
    "fig:overview": "Fig. 4",
    "fig:global-family": "Fig. 5",
    "fig:hermite-case": "Fig. 6",
}
"""The figures of §V the project reproduces, by label (numbering as in docs/sweep.md)."""
