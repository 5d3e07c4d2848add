"""The command line of the clips: ``python -m np_sim.clips [--summary] [--figure CLIP_NAME --out PNG]
[--regenerate]`` prints a summary of the site and both splits, draws a clip, or regenerates the shipped site and
evaluation-clip files; `summarize` gives the summary's numbers."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from np_sim.cli import cli_boundary, positive_int
from np_sim.clips.config import EVAL_PATH, N_CLIPS, OBJECT_KINDS, SEED_BASE
from np_sim.clips.difficulty import CRITERIA
from np_sim.clips.model import Clip
from np_sim.clips.splits import (
    SplitStatistics,
    find_clip,
    generate_split,
    load_clips,
    regenerate_data_files,
    split_statistics,
)
from np_sim.site import SITE_OBSERVATION, SITE_PATH, load_site


def summarize(clips: Sequence[Clip], statistics: SplitStatistics | None = None) -> dict[str, Any]:
    """Counts and rates of a set of clips (frames, detections, drop-outs, jitter, difficulty breakdown)."""
    frames = np.array([c.n_frames for c in clips])
    per_frame = np.concatenate([np.diff(c.det_offsets)[~c.frame_missed] for c in clips])
    objects = np.array([len(c.objects) for c in clips])
    possible = sum(len(c.objects) * int((~c.frame_missed).sum()) for c in clips)
    detected = sum(len(c.det_object) for c in clips)
    missed = sum(int(c.frame_missed.sum()) for c in clips)
    movers = sum(sum(o.moving for o in c.objects) for c in clips)
    kinds = {k: sum(sum(o.kind == k for o in c.objects) for c in clips) for k in OBJECT_KINDS}
    breakdown = {r: sum(r in c.difficulty.reasons for c in clips) for r in CRITERIA}
    n_reasons = [len(c.difficulty.reasons) for c in clips]
    out = {
        "clips": len(clips),
        "frames_total": int(frames.sum()),
        "frames_per_clip": (int(frames.min()), float(frames.mean()), int(frames.max())),
        "objects_per_clip": (int(objects.min()), float(objects.mean()), int(objects.max())),
        "moving_objects_per_clip": movers / max(len(clips), 1),
        "object_kinds": kinds,
        "detections_per_frame": (float(per_frame.mean()), int(per_frame.max())),
        "dropout_rate": 1.0 - detected / max(possible, 1),
        "missed_frame_rate": missed / max(int(frames.sum()), 1),
        "jitter_sd_m": (min(c.jitter_sd_m for c in clips), max(c.jitter_sd_m for c in clips)),
        "difficult": sum(c.difficulty.difficult for c in clips),
        "difficulty_breakdown": breakdown,
        "difficulty_reasons_per_clip": {k: n_reasons.count(k) for k in sorted(set(n_reasons))},
    }
    if statistics is not None:
        out["candidates"] = {"examined": statistics.examined, "rejected": dict(statistics.rejected),
                             "rejected_fraction": 1.0 - statistics.accepted / max(statistics.examined, 1)}
    return out


def _summary_lines(name: str, s: dict[str, Any]) -> list[str]:
    lines = [
        f"{name}: {s['clips']} clips, {s['frames_total']} frames "
        f"(per clip min/mean/max {s['frames_per_clip'][0]}/{s['frames_per_clip'][1]:.1f}/{s['frames_per_clip'][2]})",
        f"  objects per clip min/mean/max {s['objects_per_clip'][0]}/{s['objects_per_clip'][1]:.1f}/"
        f"{s['objects_per_clip'][2]}, moving {s['moving_objects_per_clip']:.2f}/clip; kinds "
        + ", ".join(f"{k} {v}" for k, v in s["object_kinds"].items()),
        f"  detections per received frame mean {s['detections_per_frame'][0]:.1f}, max {s['detections_per_frame'][1]}"
        f"; drop-out rate {100 * s['dropout_rate']:.2f} %; missed frames {100 * s['missed_frame_rate']:.2f} %"
        f"; jitter sd {s['jitter_sd_m'][0]:.3f}–{s['jitter_sd_m'][1]:.3f} m",
        f"  difficult {s['difficult']}/{s['clips']}: "
        + ", ".join(f"{k} {v}" for k, v in s["difficulty_breakdown"].items())
        + " (criteria per clip: " + ", ".join(f"{k}: {v}" for k, v in s["difficulty_reasons_per_clip"].items()) + ")",
    ]
    if "candidates" in s:
        c = s["candidates"]
        lines.append(f"  candidates examined {c['examined']}, rejected {100 * c['rejected_fraction']:.1f} %: "
                     + ", ".join(f"{k} {v}" for k, v in c["rejected"].items()))
    return lines


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m np_sim.clips``."""
    parser = argparse.ArgumentParser(
        prog="python -m np_sim.clips",
        description="The delivery site and its clips (spec §4.4): print a summary, draw a clip, or regenerate "
                    "the shipped site and evaluation-clip files.",
        epilog="example: python -m np_sim.clips --summary --figure eval-1000003 --out clip.png",
    )
    parser.add_argument("--summary", action="store_true",
                        help="print site edge count, clip counts, frames, detections, drop-outs, jitter and the "
                             "difficulty breakdown (eval: all 47; train: the first --train-sample clips)")
    parser.add_argument("--train-sample", type=positive_int, default=50, metavar="N",
                        help="train clips the summary generates (default 50; 1000 = all, about a minute)")
    parser.add_argument("--figure", metavar="CLIP_NAME", help="draw this clip (eval name or train-<seed>)")
    parser.add_argument("--out", type=Path, default=None, metavar="PNG",
                        help="figure file (default <CLIP_NAME>.png)")
    parser.add_argument("--regenerate", action="store_true",
                        help="regenerate np_sim/data/site_v1.json and clips_eval_v1.json.gz from their seeds")
    return parser


@cli_boundary
def main(argv=None) -> dict:
    """Run the CLI (see `build_parser`); returns what it printed as a dict (for tests). A user's mistake (an
    unknown clip name, an unwritable figure path) prints one ``error:`` line and exits with status 2."""
    args = build_parser().parse_args(argv)
    if not (args.summary or args.figure or args.regenerate):
        build_parser().error("nothing to do: give --summary, --figure CLIP_NAME or --regenerate")
    result: dict[str, Any] = {}
    if args.regenerate:
        result["regenerate_s"] = _regenerate()
    if args.summary:
        result.update(_print_summary(args.train_sample))
    if args.figure:
        result["figure"] = _draw_figure(args.figure, args.out)
    return result


def _regenerate() -> float:
    """Regenerate the shipped files and say so; the seconds it took."""
    t0 = time.perf_counter()
    regenerate_data_files()
    seconds = time.perf_counter() - t0
    print(f"wrote {SITE_PATH} ({SITE_PATH.stat().st_size} bytes) and {EVAL_PATH} "
          f"({EVAL_PATH.stat().st_size} bytes) in {seconds:.1f} s")
    return seconds


def _print_summary(train_sample: int) -> dict[str, Any]:
    """Print the site, the splits and the summaries of the eval clips and the first ``train_sample`` train
    clips; their numbers."""
    site = load_site()
    eval_clips, eval_stats = load_clips("eval"), split_statistics("eval")
    t0 = time.perf_counter()
    train_clips, train_stats = generate_split("train", train_sample)
    train_s = time.perf_counter() - t0
    result = {"site_edges": site.n_edges, "eval": summarize(eval_clips, eval_stats),
              "train": summarize(train_clips, train_stats)}
    print(f"site {site.name}: {site.n_edges} boundary edges (observation slots "
          f"{SITE_OBSERVATION.max_boundary_segments}), {len(site.spots)} spots ("
          + ", ".join(f"{k} {sum(s.kind == k for s in site.spots)}"
                      for k in ("reverse", "forward", "parallel", "angled")) + ")")
    print(f"splits: train {N_CLIPS['train']} clips (seeds from {SEED_BASE['train']}, generated on demand), "
          f"eval {len(eval_clips)} clips (seeds from {SEED_BASE['eval']}, shipped {EVAL_PATH.name})")
    for line in _summary_lines("eval", result["eval"]):
        print(line)
    for line in _summary_lines(f"train (first {len(train_clips)} of {N_CLIPS['train']}, "
                               f"{1000 * train_s / max(train_stats.examined, 1):.0f} ms per candidate)",
                               result["train"]):
        print(line)
    return result


def _draw_figure(name: str, out: Path | None) -> Path:
    """Draw the clip ``name`` into the PNG ``out`` (default ``<name>.png``); the path written."""
    from matplotlib.figure import Figure

    from np_sim.plotting import plot_clip  # matplotlib stays out of the library's import path

    clip = find_clip(name)
    fig = Figure(figsize=(11, 8.5))
    plot_clip(fig.add_subplot(), clip)
    out = out if out is not None else Path(f"{clip.name}.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=140, bbox_inches="tight")
    print(f"wrote {out}")
    return out
