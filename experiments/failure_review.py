"""Review the recorded failures of a robustness study (`experiments.robustness`, docs/robustness.md): what each
recording in ``STUDY_DIR/rrd/`` shows at its first contact.

``python -m experiments.failure_review STUDY_DIR``

For the recording of every failure the study records (`experiments.robustness_report.failure_cases`: the failure
each disturbance caused; ``rrd/<factor>_<level>_<planner>_<clip>.rrd``, `experiments.robustness.recording_path`)
it reads the run back (`tracking.rrd_read.read_run`) and writes into ``STUDY_DIR/review/``:

* ``cases.csv`` and ``cases.md``: per recording the factor, level, planner and clip; whether the clip passes
  undisturbed with that planner (``caused``); the study row's outcome, the re-driven run's outcome and whether
  they agree (the searches plan against a wall-time budget, so a re-driven run can end otherwise: such rows are
  marked, and left out of the counts); ``clip_end_s``, the time of the clip's last frame (later frames hold it:
  `tracking.clip_run`); the planner calls up to the first contact, and those after the call that made the plan
  being followed (all failed: the vehicle drove on along that plan); what was touched first and
  when; the cross-track error then and the worst up to then; how far the vehicle was from the plan it followed;
  that plan's clearance to the touched object's true outline with the body the simulator drove (a ``body_length``
  disturbance makes it longer: the disturbance's own tracker configuration gives it; ``plan_clearance_nominal_m``
  with the body planned for); whether the planner call that made the plan had a detection of the object and the
  plan's clearance to it where the plan meets the object; and the kind of failure
  (`experiments.review_case.KINDS`; a run without a contact by its reason, e.g. 'timeout');
* ``<factor>.png``: a panel per level × planner around the first contact (`experiments.review_figure`).

Only clip studies are reviewed (frozen-start episodes have no planner calls in their recordings).
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from experiments.closed_loop import ClosedLoopConfig, disturbed
from experiments.registry import label
from experiments.review_case import KINDS, ContactReview, review_contact
from experiments.review_figure import Panel, review_sheet
from experiments.robustness import recording_path, stored_study, study_spec
from experiments.robustness_report import failure_cases
from experiments.robustness_sources import build_source, disturbance_at
from np_sim.cli import cli_boundary
from np_sim.errors import ConfigError
from np_sim.vehicle import VehicleSpec
from tracking.clip_run import clip_world, object_of_geom
from tracking.rrd_read import RecordedRun, read_run

COLUMNS = ("factor", "level", "planner", "clip", "clip_end_s", "caused", "study_outcome", "recorded_outcome",
           "matches_study", "calls_before_contact", "failed_calls_since_plan", "contact_t_s", "touched_geom",
           "touched_object", "cross_track_then_m", "cross_track_worst_m", "off_plan_m", "plan_made_t_s",
           "plan_clearance_m", "plan_clearance_nominal_m", "seen", "detection_clearance_m", "kind", "recording")
"""The columns of ``cases.csv`` (module docstring)."""


@dataclass
class Study:
    """A clip study's folder, its clips and settings, and its records."""

    folder: Path
    loop: ClosedLoopConfig
    clips: dict
    """Clip name -> `np_sim.clips.Clip`, in study order."""
    planners: list[str]
    factors: list[str]
    levels: list[str]
    seed: int
    rows: list[dict]


def load_study(folder: Path) -> Study:
    """The clip study in ``folder``; a ConfigError naming what is missing when it is none or has no recordings."""
    if not folder.is_dir():
        raise ConfigError(f"{folder}: no such folder; expected the folder of a robustness study")
    for name in ("records.csv", "config.json"):
        if not (folder / name).is_file():
            raise ConfigError(f"{folder}: no {name}; expected the folder of a robustness study "
                              "(python -m experiments.robustness)")
    if not sorted((folder / "rrd").glob("*.rrd")):
        raise ConfigError(f"{folder}: no recordings in rrd/; write them with python -m experiments.robustness "
                          f"--resume {folder}")
    args = stored_study(folder)
    spec, planners, _ = study_spec(args)
    if not isinstance(spec, ClosedLoopConfig):
        raise ConfigError(f"{folder}: a frozen-start study; only clip studies (--clips) are reviewed")
    with (folder / "records.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    source = build_source(spec)
    return Study(folder=folder, loop=spec, clips={c.name: c for c in source.clips}, planners=planners,
                 factors=list(args.factors), levels=list(args.levels), seed=args.seed, rows=rows)


def bodies(study: Study, factor: str, level: str) -> tuple[VehicleSpec, VehicleSpec]:
    """(the body planned for, the body the simulator drove) under ``factor`` at ``level``: the disturbed tracker's
    vehicle and its plant body."""
    tracker = disturbed(study.loop.clip_run, disturbance_at(factor, level, study.seed)).tracker
    return tracker.vehicle, tracker.plant.body(tracker.vehicle)


def _outcome(reason: str) -> str:
    return reason.replace("_", " ") if reason else "parked"


def _number(value: float) -> str:
    return "" if value is None or math.isnan(value) else f"{value:.3f}"


def case_row(study: Study, key: tuple[str, str, str, str], run: RecordedRun,
             body: tuple[VehicleSpec, VehicleSpec], recording: str) -> tuple[dict, ContactReview | None]:
    """The ``cases.csv`` row of ``run``, the recording (file name ``recording``) of ``key``, and its contact review
    (None without a contact); ``body``: (planned, driven) (`bodies`)."""
    factor, level, planner, name = key
    (row,) = [r for r in study.rows if (r["factor"], r["level"], r["planner"], r["clip"]) == key]
    undisturbed = [r for r in study.rows if (r["factor"], r["level"], r["planner"], r["clip"]) ==
                   ("none", "none", planner, name)]
    recorded = "unfinished recording" if run.outcome is None else _outcome(run.outcome.reason)
    first_geom = run.contacts[0].geom if run.contacts else ""
    clip = study.clips[name]
    out = {"factor": factor, "level": level, "planner": planner, "clip": name,
           "clip_end_s": f"{(clip.n_frames - 1) * clip.frame_dt_s:.1f}",
           "caused": "yes" if undisturbed and int(undisturbed[0]["footprint_success"]) else "no",
           "study_outcome": _outcome(row["reason"]), "recorded_outcome": recorded,
           "matches_study": "yes" if (recorded, first_geom) == (_outcome(row["reason"]), row["first_contact_geom"])
           else "no", "recording": recording}
    if not run.contacts:
        _, values = run.controller.get("cross_track_m", ([], []))
        worst = float(np.abs(values).max()) if len(values) else math.nan
        return {**out, "calls_before_contact": len(run.calls), "cross_track_worst_m": _number(worst),
                "kind": recorded}, None
    touched = object_of_geom(clip, clip_world(clip), run.contacts[0].geom)
    review = review_contact(run, body[1], touched, planned=body[0])
    return {**out, "calls_before_contact": review.calls_before,
            "failed_calls_since_plan": review.failed_calls_since_plan, "contact_t_s": f"{review.time_s:.2f}",
            "touched_geom": review.geom, "touched_object": touched, "cross_track_then_m": _number(review.cross_track_m),
            "cross_track_worst_m": _number(review.cross_track_worst_m), "off_plan_m": _number(review.off_plan_m),
            "plan_made_t_s": f"{review.plan_time_s:.2f}", "plan_clearance_m": _number(review.plan_clearance_m),
            "plan_clearance_nominal_m": _number(review.plan_clearance_nominal_m),
            "seen": review.seen, "detection_clearance_m": _number(review.detection_clearance_m),
            "kind": review.kind}, review


def _caption(row: dict) -> str:
    first = f"{row['level']} · {label(row['planner'])} · {row['clip']}"
    if not row.get("touched_geom"):
        return f"{first}\n{row['kind']} (no contact)"
    mark = "" if row["matches_study"] == "yes" else " · differs from study"
    return (f"{first}\n{row['kind']}: {row['touched_object']} at {row['contact_t_s']} s{mark}\n"
            f"plan clear {row['plan_clearance_m']} m · xte {row['cross_track_then_m']} m · seen {row['seen']}")


def cases_markdown(rows: list[dict], study: Study) -> str:
    """``cases.md``: the kinds counted per factor (rows that agree with their study row) and every row."""
    kinds = [*KINDS, *sorted({r["kind"] for r in rows} - set(KINDS))]
    lines = [f"# Recorded failures of {study.folder.name}", "",
             "Written by `python -m experiments.failure_review`; columns as in `cases.csv` (the module's docstring). "
             "Kinds of a contact:", ""]
    lines += [f"* **{k}**: {text}" for k, text in KINDS.items()]
    lines += ["", "Kinds per factor (recordings whose run ended as its study row; 'caused': of those, the clip "
              "passes undisturbed):", "", "| factor | " + " | ".join(kinds) + " | differs from study |",
              "|---|" + "---|" * (len(kinds) + 1)]
    for factor in ["none", *study.factors]:
        mine = [r for r in rows if r["factor"] == factor]
        agree = [r for r in mine if r["matches_study"] == "yes"]
        cells = [f"{sum(r['kind'] == k for r in agree)} ({sum(r['kind'] == k and r['caused'] == 'yes' for r in agree)})"
                 for k in kinds]
        lines.append(f"| {factor} | " + " | ".join(cells) + f" | {len(mine) - len(agree)} |")
    shown = ("level", "planner", "clip", "clip_end_s", "caused", "study_outcome", "matches_study",
             "calls_before_contact", "failed_calls_since_plan", "touched_object", "plan_made_t_s", "contact_t_s",
             "cross_track_then_m", "cross_track_worst_m", "off_plan_m", "plan_clearance_m", "plan_clearance_nominal_m",
             "seen", "detection_clearance_m", "kind")
    for factor in ["none", *study.factors]:
        lines += ["", f"## {factor}", "", "| " + " | ".join(shown) + " |", "|" + "---|" * len(shown)]
        lines += ["| " + " | ".join(str(r.get(c, "")) for c in shown) + " |" for r in rows if r["factor"] == factor]
    return "\n".join(lines) + "\n"


def review_study(study: Study, out: Path) -> dict[str, Any]:
    """Review every recording of ``study`` into ``out`` (cases.csv, cases.md, <factor>.png)."""
    out.mkdir(exist_ok=True)
    rows, panels = [], {}
    for case in failure_cases(study.rows, list(study.clips)):
        path = recording_path(study.folder, case)
        if not path.exists():
            continue  # recorded with --no-rrd, or not yet
        key = (case.factor, case.level, case.planner, case.unit)
        body = bodies(study, case.factor, case.level)
        run = read_run(path)
        row, review = case_row(study, key, run, body, path.name)
        rows.append(row)
        panels.setdefault(case.factor, []).append(Panel(case.level, case.planner, run, review, body[1], _caption(row)))
    with (out / "cases.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS, restval="")
        writer.writeheader()
        writer.writerows(rows)
    (out / "cases.md").write_text(cases_markdown(rows, study))
    sheets = [review_sheet(factor, ["none"] if factor == "none" else study.levels, study.planners, found,
                           out / f"{factor}.png") for factor, found in panels.items()]
    return {"rows": rows, "sheets": sheets}


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m experiments.failure_review", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", type=Path, metavar="STUDY_DIR",
                        help="the folder of a robustness clip study with its recordings in rrd/")
    return parser


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; a bad folder exits 2 with one error line)."""
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    study = load_study(args.study)
    result = review_study(study, args.study / "review")
    print(f"{len(result['rows'])} recordings reviewed: {args.study / 'review'}/cases.csv, cases.md, "
          f"{len(result['sheets'])} sheets")
    return result


if __name__ == "__main__":
    main()
