"""Why the hybrid's plan on eval-1000086 (detection noise, severe) passed 0.05 m from the cart's detection.

    python -m experiments.robustness --clips --clip-names eval-1000086 --planners neuralparker_search \
        --factors detection_noise --levels severe --workers 1 --out /tmp/rob_eval-1000086
    python docs/results/2026-12-07-robustness-hybrid/contacts/target_cap.py /tmp/rob_eval-1000086 > target_cap.txt

For the plan followed at the first contact it prints the stage of the call that made it (records.csv), the planned
body's clearance at the plan's first and last pose to the nearest detections of that call and to the boundary, the
touched object's shift, and where along the plan the body passes within `SLACK_M` of the object's true outline and
how far it clears the object's detection there. The preset 'footprint_search' caps the clearance a call asks (the
search's growth of the body included) at the clearance level of the start and of the target pose, on the ladder
0.2 / 0.1 / 0 m: a pose closer than 0.1 m to a detection has level 0, and so does every clearance that call asks.
"""

import ast
import csv
import sys
from pathlib import Path

import numpy as np
import shapely

from experiments.failure_review import bodies, load_study
from experiments.review_case import SLACK_M, clearance, planned_bodies, true_outline
from tracking.rrd_read import read_run


def nearest_detections(pose, body, call, count=3) -> str:
    """The ``count`` detections of ``call`` nearest the body at ``pose``, with their clearances (m)."""
    gaps = sorted((clearance(np.asarray(pose)[None], body, shapely.Polygon(d)), label)
                  for label, d in zip(call.labels, call.detections))
    return ", ".join(f"{label} {gap:.3f}" for gap, label in gaps[:count])


def main(folder: Path) -> None:
    study = load_study(folder)
    (row,) = [r for r in csv.DictReader(open(folder / "records.csv")) if r["level"] != "none"]
    (recording,) = sorted((folder / "rrd").glob("*.rrd"))
    run = read_run(recording)
    _, planned = bodies(study, row["factor"], row["level"])
    contact = run.contacts[0]
    plan = run.plan_at(contact.time_s)
    call = run.call_of(plan)
    stage = ast.literal_eval(row["plan_stages"])[run.calls.index(call)]
    touched = row["first_contact_object"]
    detection = shapely.Polygon(call.detections[call.labels.index(touched)])
    truth = true_outline(run, contact.geom, contact.time_s)
    placed = planned_bodies(plan.poses, planned)
    to_detection, to_truth = shapely.distance(placed, detection), shapely.distance(placed, truth)
    ring = shapely.LinearRing(run.boundary)
    print(f"{recording.name}: first contact at {contact.time_s:.2f} s with {touched} ({contact.geom})")
    print(f"followed plan made at {plan.time_s:.2f} s by a '{stage}' call; {len(plan.poses)} poses")
    for name, pose in (("first pose", plan.poses[0]), ("last pose (the target)", plan.poses[-1])):
        print(f"  {name}: boundary {clearance(np.asarray(pose)[None], planned, ring):.3f} m; nearest detections: "
              f"{nearest_detections(pose, planned, call)}")
    print(f"{touched}: detection shifted {detection.centroid.distance(truth.centroid):.3f} m from its true outline; "
          f"the target's clearance to it {to_truth[-1]:.3f} m (truth), {to_detection[-1]:.3f} m (detection)")
    near = np.flatnonzero(to_truth < SLACK_M)
    print(f"along the plan: least clearance to the detection {to_detection.min():.3f} m (pose "
          f"{int(np.argmin(to_detection))}); within {SLACK_M} m of the true outline at poses {near.min()}-"
          f"{near.max()}, where it clears the detection by {to_detection[near].min():.3f} m or more")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
