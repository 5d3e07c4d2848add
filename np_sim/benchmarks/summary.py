"""Summary statistics and overview figures of the shipped benchmarks (paper §IV-A, Fig. "representative
held-out scenes"): ``python -m np_sim.benchmarks --summary`` and ``--figure DIR``.

Statistics per benchmark and split: scene and per-cell counts, obstacle / boundary-segment / vertex counts
against `SceneCapacity()`, the geodesic distance (1.5 m footprint-inflated grid) of the frozen starts per
distance regime (Factorial; median and 10th–90th percentile), per Topology-Stress family the *route-blocked*
fraction of the frozen starts (straight segment start → target touches an obstacle AND the decisive opening lies
more than 10 m from the start; see `np_sim.benchmarks.topology`) and the fraction with the family structure
beyond 10 m, and the structural-disjointness floor (`np_sim.benchmarks.layout`).
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from np_sim.benchmarks.factorial import DIFFICULTIES as F_DIFFICULTIES
from np_sim.benchmarks.factorial import DISTANCES, PARKING_TYPES
from np_sim.benchmarks.frozen import read_benchmark_file
from np_sim.benchmarks.layout import DISJOINTNESS_FLOOR_M, nearest_train_distances
from np_sim.benchmarks.topology import DIFFICULTIES as T_DIFFICULTIES
from np_sim.benchmarks.topology import FAMILIES, opening_segment, route_blocked, structure_beyond_range
from np_sim.geodesic import geodesic_grid
from np_sim.plotting import plot_scene
from np_sim.scene import PolygonObstacle, Scene, SceneCapacity


def _counts(scenes: list[Scene]) -> dict:
    """Object-capacity statistics of a split."""
    n_obs = [len(s.obstacles) for s in scenes]
    n_seg = [len(s.boundary) for s in scenes]
    n_vtx = [len(o.vertices) if isinstance(o, PolygonObstacle) else 8 for s in scenes for o in s.obstacles]
    return {"scenes": len(scenes), "obstacles_max": max(n_obs), "obstacles_mean": float(np.mean(n_obs)),
            "segments_max": max(n_seg), "segments_mean": float(np.mean(n_seg)), "vertices_max": max(n_vtx),
            "cells": dict(sorted(Counter(s.tags["cell"] for s in scenes).items()))}


def _stats(values) -> dict:
    """Median, 10th and 90th percentile and count of finite values."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return {"n": int(len(v)), "median": float(np.median(v)), "p10": float(np.percentile(v, 10)),
            "p90": float(np.percentile(v, 90))}


def summarize(name: str, data_dir: str | Path | None = None) -> dict:
    """Statistics of the shipped benchmark ``name`` (module docstring), as a JSON-safe dict."""
    doc, scenes, starts = read_benchmark_file(name, data_dir)
    train, test = list(scenes["train"]), list(scenes["test"])
    grids = [geodesic_grid(s) for s in test]
    start_distance = np.stack([g.distance_at(st[:, :2]) for g, st in zip(grids, starts)])  # (n_test, 40)
    out = {"benchmark": name, "splits": {"train": _counts(train), "test": _counts(test)},
           "frozen_starts": list(starts.shape), "rejections": doc.get("generation", {}).get("rejections", {}),
           "capacity": {"max_obstacles": SceneCapacity().max_obstacles,
                        "max_polygon_vertices": SceneCapacity().max_polygon_vertices,
                        "max_boundary_segments": SceneCapacity().max_boundary_segments}}
    nearest = nearest_train_distances(train, test)
    floor_m = doc.get("generation", {}).get("disjointness_floor_m", DISJOINTNESS_FLOOR_M)
    out["disjointness"] = {"floor_m": float(floor_m),
                           "min_nearest_train_m": float(nearest.min()),
                           "median_nearest_train_m": float(np.median(nearest))}
    if name == "factorial":
        out["distance"] = {d: _stats(start_distance[[s.tags["distance"] == d for s in test]].ravel())
                           for d in DISTANCES}
    else:
        families = {}
        for f in FAMILIES:
            rows = [k for k, s in enumerate(test) if s.tags["family"] == f]
            blocked = np.concatenate([route_blocked(test[k], starts[k, :, :2]) for k in rows])
            beyond = np.concatenate([structure_beyond_range(test[k], starts[k, :, :2]) for k in rows])
            families[f] = {"episodes": int(len(blocked)), "route_blocked": float(blocked.mean()),
                           "structure_beyond_10m": float(beyond.mean()),
                           "distance": _stats(start_distance[rows].ravel())}
        out["families"] = families
        out["distance_all"] = _stats(start_distance.ravel())
    return out


def format_summary(summary: dict) -> str:
    """The printed form of `summarize`'s dict."""
    cap = summary["capacity"]
    lines = [f"== {summary['benchmark']} ==",
             f"{'split':<6} {'scenes':>6} {'obst max/mean':>14} {'segs max/mean':>14} {'verts max':>9}"]
    for split, c in summary["splits"].items():
        lines.append(f"{split:<6} {c['scenes']:>6} {c['obstacles_max']:>6}/{c['obstacles_mean']:<7.1f} "
                     f"{c['segments_max']:>6}/{c['segments_mean']:<7.1f} {c['vertices_max']:>9}")
    lines.append(f"capacity: <= {cap['max_obstacles']} obstacles of <= {cap['max_polygon_vertices']} vertices, "
                 f"<= {cap['max_boundary_segments']} boundary segments")
    train_cells, test_cells = summary["splits"]["train"]["cells"], summary["splits"]["test"]["cells"]
    per_cell = Counter((train_cells[c], test_cells.get(c, 0)) for c in train_cells)
    lines.append(f"per-cell counts (train, test): {len(train_cells)} cells, "
                 + ", ".join(f"{n} cells with {a}/{b}" for (a, b), n in sorted(per_cell.items())))
    n_scenes, n_starts = summary["frozen_starts"][:2]
    lines.append(f"frozen starts: {n_scenes} test scenes x {n_starts} = {n_scenes * n_starts} episodes")
    if "distance" in summary:
        lines.append("start geodesic distance over the frozen starts (m):  median  [p10, p90]   n")
        for d, s in summary["distance"].items():
            lines.append(f"  {d:<7} {s['median']:>8.1f}  [{s['p10']:>5.1f}, {s['p90']:>5.1f}]  {s['n']:>4}")
    if "families" in summary:
        lines.append("per family over the frozen starts: route-blocked fraction, structure beyond 10 m, "
                     "geodesic distance median [p10, p90] (m)")
        for f, s in summary["families"].items():
            d = s["distance"]
            lines.append(f"  {f:<6} {s['route_blocked']:>6.3f}  {s['structure_beyond_10m']:>6.3f}  "
                         f"{d['median']:>6.1f} [{d['p10']:>5.1f}, {d['p90']:>5.1f}]  ({s['episodes']} episodes)")
    dj = summary["disjointness"]
    lines.append(f"structural disjointness: min over test scenes of the layout distance to the nearest same-cell "
                 f"train scene = {dj['min_nearest_train_m']:.2f} m (floor {dj['floor_m']:.2f} m, "
                 f"median {dj['median_nearest_train_m']:.2f} m)")
    if summary["rejections"]:
        lines.append("rejected draws during generation: "
                     + ", ".join(f"{k} {v}" for k, v in sorted(summary["rejections"].items())))
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------- figures


def _draw(ax, scene: Scene, starts: np.ndarray, title: str) -> None:
    """One overview panel: the scene (plot_scene), its frozen starts as arrows, a topology scene's opening."""
    plot_scene(ax, scene)
    if ax.get_legend() is not None:
        ax.get_legend().remove()
    ax.quiver(starts[:, 0], starts[:, 1], np.cos(starts[:, 2]), np.sin(starts[:, 2]), color="tab:blue",
              angles="xy", scale_units="xy", scale=1.0, width=0.004, headwidth=3, headlength=3)
    if "opening_x0" in scene.tags:
        o = opening_segment(scene)
        ax.plot(o[:, 0], o[:, 1], color="tab:orange", linewidth=3.0)
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=7)
    ax.xaxis.label.set_size(8)
    ax.yaxis.label.set_size(8)


def _legend(fig: Figure, topology: bool) -> None:
    """Figure-level legend shared by every panel."""
    handles = [Line2D([], [], color="black", lw=1.5, label="boundary"),
               Patch(facecolor="0.55", edgecolor="0.25", label="obstacles"),
               Patch(facecolor="tab:green", alpha=0.3, hatch="//", edgecolor="tab:green", label="start region"),
               Line2D([], [], color="tab:red", lw=2, label="target (T-marker) and footprint"),
               Line2D([], [], color="tab:blue", marker=r"$\rightarrow$", lw=0, markersize=10, label="40 frozen starts")]
    if topology:
        handles.append(Line2D([], [], color="tab:orange", lw=3, label="decisive opening"))
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), frameon=False, fontsize=10)


def write_figures(out_dir: str | Path, data_dir: str | Path | None = None, dpi: int = 110,
                  benchmarks: tuple[str, ...] = ("factorial", "topology")) -> list[Path]:
    """Write the held-out scene overviews (paper §IV-A figure of representative held-out scenes) as PNGs into
    ``out_dir`` and return their paths: one Factorial figure per difficulty (rows = distance regime, columns =
    parking type) and one Topology-Stress figure (rows = family, columns = difficulty × test scene). Equal x–y
    scaling, metres on the axes, the frozen starts as arrows."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    if "factorial" in benchmarks:
        written += _factorial_figures(out, data_dir, dpi)
    if "topology" in benchmarks:
        written.append(_topology_figure(out, data_dir, dpi))
    return written


def _factorial_figures(out: Path, data_dir, dpi: int) -> list[Path]:
    """The three Factorial overview figures (one per difficulty)."""
    written = []
    _, scenes, starts = read_benchmark_file("factorial", data_dir)
    test = list(scenes["test"])
    for q in F_DIFFICULTIES:
        fig = Figure(figsize=(16, 13.5))
        for i, d in enumerate(DISTANCES):
            for j, t in enumerate(PARKING_TYPES):
                k = next(k for k, s in enumerate(test) if s.tags["cell"] == f"{d}-{t}-{q}")
                _draw(fig.add_subplot(3, 3, 3 * i + j + 1), test[k], starts[k], f"{d} / {t} / {q}")
        _legend(fig, topology=False)
        fig.suptitle(f"Factorial Parking Benchmark, held-out scenes, difficulty {q} "
                     "(rows: start distance near / medium / long; columns: reverse / lateral / random)", y=0.965)
        fig.tight_layout(rect=(0, 0, 1, 0.95))
        path = out / f"factorial_test_{q}.png"
        fig.savefig(path, dpi=dpi)
        written.append(path)
    return written


def _topology_figure(out: Path, data_dir, dpi: int) -> Path:
    """The Topology-Stress overview figure."""
    _, scenes, starts = read_benchmark_file("topology", data_dir)
    test = list(scenes["test"])
    fig = Figure(figsize=(26, 14))
    per_cell = sum(1 for s in test if s.tags["cell"] == test[0].tags["cell"])
    for i, f in enumerate(FAMILIES):
        for j, q in enumerate(T_DIFFICULTIES):
            rows = [k for k, s in enumerate(test) if s.tags["cell"] == f"{f}-{q}"]
            for n, k in enumerate(rows):
                ax = fig.add_subplot(3, len(T_DIFFICULTIES) * per_cell, i * len(T_DIFFICULTIES) * per_cell
                                     + j * per_cell + n + 1)
                _draw(ax, test[k], starts[k], f"{f} / {q} / #{n}")
    _legend(fig, topology=True)
    fig.suptitle("Topology-Stress Benchmark, held-out scenes (rows: type1 roof + wall / type2 pocket / "
                 "type3 barrier; columns: medium ×3, hard ×3)", y=0.965)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    path = out / "topology_test.png"
    fig.savefig(path, dpi=dpi)
    return path
