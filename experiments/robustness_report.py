"""The outputs of the robustness study (`experiments.robustness`): rates with binomial confidence bands, the
success-vs-level plots, ``table.md`` and the choice of the runs it records (`failure_cases`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments.registry import label
from tracking.disturbance import FACTORS, LEVELS

Z95 = 1.959963984540054
"""Standard normal quantile of a two-sided 95 % interval."""


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (Wilson 1927): centre (k + z²/2)/(n + z²), half-width
    z·√(k(n − k)/n + z²/4)/(n + z²); (nan, nan) for n = 0."""
    if n == 0:
        return math.nan, math.nan
    centre = (successes + 0.5 * z * z) / (n + z * z)
    half = z * math.sqrt(successes * (n - successes) / n + 0.25 * z * z) / (n + z * z)
    # at k = 0 (k = n) the lower (upper) bound is exactly 0 (1); rounding would leave it a hair off
    return (0.0 if successes == 0 else centre - half), (1.0 if successes == n else centre + half)


def rates(rows: list[dict], factor: str, planner: str, column: str) -> list[tuple[int, int]]:
    """(count of ``column`` true, runs) at the levels 'none', then ``LEVELS``, of ``factor`` for ``planner``: the
    undisturbed rows are shared by every factor."""
    out = []
    for level in ("none", *LEVELS):
        name = "none" if level == "none" else factor
        hits = [int(r[column]) > 0 for r in rows if r["factor"] == name and r["level"] == level
                and r["planner"] == planner]
        out.append((sum(hits), len(hits)))
    return out


def level_labels(factor: str) -> list[str]:
    """Tick labels of the levels: the level and its physical setting."""
    spec = FACTORS[factor]
    return ["none"] + [f"{lv}\n{spec.setting(v)}" for lv, v in zip(LEVELS, spec.levels)]


def factor_figure(rows: list[dict], factor: str, planners: list[str], path: Path) -> Path:
    """Footprint success and contact rate against the level of ``factor``, one line per planner, 95 % Wilson
    bands."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.6), sharex=True)
    x = np.arange(1 + len(LEVELS))
    for ax, column, title in zip(axes, ("footprint_success", "contacts"), ("footprint success", "contact rate")):
        for planner in planners:
            counts = rates(rows, factor, planner, column)
            kept = [(i, k, n) for i, (k, n) in enumerate(counts) if n]
            if not kept:
                continue
            xs = np.array([i for i, _, _ in kept])
            band = np.array([wilson(k, n) for _, k, n in kept])
            line, = ax.plot(xs, [k / n for _, k, n in kept], "o-", ms=4, label=label(planner))
            ax.fill_between(xs, band[:, 0], band[:, 1], color=line.get_color(), alpha=0.15)
        ax.set_title(f"{factor}: {title}", fontsize=9)
        ax.set_ylim(-0.02, 1.02)
        ax.set_xticks(x, level_labels(factor), fontsize=7)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def _cell(counts: tuple[int, int], contacts: tuple[int, int]) -> str:
    (k, n), (c, _) = counts, contacts
    if not n:
        return "–"
    lo, hi = wilson(k, n)
    return f"{k / n:.2f} [{lo:.2f}, {hi:.2f}] / {c / n:.2f}"


def failure_reasons(rows: list[dict], factor: str, level: str, planner: str) -> str:
    """The failure reasons of ``planner``'s failed runs under ``factor`` at ``level`` (the undisturbed rows for
    'none'), most frequent first, e.g. 'contact 3, timeout 1'; '–' without failures."""
    name = "none" if level == "none" else factor
    counts: dict[str, int] = {}
    for r in rows:
        if r["factor"] == name and r["level"] == level and r["planner"] == planner and not int(r["footprint_success"]):
            reason = r.get("reason") or "not parked"
            counts[reason] = counts.get(reason, 0) + 1
    return ", ".join(f"{k} {n}" for k, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))) or "–"


def format_table(rows: list[dict], factors: list[str], planners: list[str], key: str = "clip") -> str:
    """Markdown: per factor, per planner, footprint success [95 % Wilson interval] / contact rate at every level
    (``key``: the column naming a clip or an episode)."""
    units = len({r[key] for r in rows})
    lines = [f"Closed-loop robustness on {units} {key}(s): footprint success [95 % Wilson interval] / contact rate "
             f"(runs with a chassis contact), one factor at a time.", ""]
    for factor in factors:
        spec = FACTORS[factor]
        heads = " | ".join(f"{lv} ({spec.setting(v)})" for lv, v in zip(LEVELS, spec.levels))
        lines += [f"### {factor} ({spec.group})", "", f"| Planner | none | {heads} |", "|---|---|---|---|---|"]
        for planner in planners:
            success = rates(rows, factor, planner, "footprint_success")
            contact = rates(rows, factor, planner, "contacts")
            lines.append(f"| {label(planner)} | " + " | ".join(_cell(s, c) for s, c in zip(success, contact)) + " |")
        lines += ["", "Failure reasons:", "", "| Planner | none | mild | moderate | severe |", "|---|---|---|---|---|"]
        for planner in planners:
            lines.append(f"| {label(planner)} | " + " | ".join(
                failure_reasons(rows, factor, level, planner) for level in ("none", *LEVELS)) + " |")
        lines.append("")
    return "\n".join(lines)


@dataclass(frozen=True)
class FailureCase:
    """The run of a factor × level × planner that the study drives again with a recording."""

    factor: str
    level: str
    planner: str
    unit: str
    """The clip (or episode) name."""
    fallback: bool
    """True when no clip failed here while passing undisturbed: the level's first failure instead."""


def failure_cases(rows: list[dict], units: list[str], key: str = "clip") -> list[FailureCase]:
    """Per factor × level × planner with a failed run (footprint success 0) in ``rows``: the first unit in
    ``units`` order that fails there but passes undisturbed (factor and level 'none') with the same planner, the
    failure the disturbance caused; else the level's first failure (``fallback``; always so for the undisturbed
    level). Sorted by factor, level, planner."""
    order = {name: k for k, name in enumerate(units)}
    passes = {(r["planner"], r[key]) for r in rows if r["factor"] == "none" and int(r["footprint_success"])}
    failed: dict[tuple[str, str, str], list[str]] = {}
    for r in rows:
        if not int(r["footprint_success"]):
            failed.setdefault((r["factor"], r["level"], r["planner"]), []).append(r[key])
    cases = []
    for (factor, level, planner), names in sorted(failed.items()):
        names = sorted(names, key=order.__getitem__)
        caused = [n for n in names if (planner, n) in passes]
        cases.append(FailureCase(factor, level, planner, (caused or names)[0], fallback=not caused))
    return cases
