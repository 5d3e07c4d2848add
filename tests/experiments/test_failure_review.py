"""experiments.failure_review and experiments.review_case: planned-body clearances derived by hand, the kind of a
contact, whether the planner saw the touched object, the CLI's errors and a review of a one-clip study."""

import csv
import math

import numpy as np
import pytest
import shapely
from cli_helpers import help_text, one_error_line
from PIL import Image

from experiments.failure_review import bodies, load_study, main
from experiments.review_case import KINDS, SLACK_M, clearance, contact_kind, review_contact
from experiments.robustness import main as robustness_main
from np_sim.vehicle import VehicleSpec
from tracking.rrd_read import PlanSegment, RecordedCall, RecordedContact, RecordedPlan, RecordedRun, read_run

CAR = VehicleSpec()
"""Rear overhang 0.929 m, front end 3.76 m ahead of the reference point (2.8 + 0.96), half-width 0.971 m."""
LONGER = VehicleSpec(front_overhang_m=0.96 + 0.235, rear_overhang_m=0.929 + 0.235)
"""The same car 0.47 m longer, half at each end."""


def _box(x0, x1, y0, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]], float)


def _straight(x0, x1, n=61, heading=0.0):
    """Poses from (x0, 0) to (x1, 0) facing ``heading``."""
    return np.column_stack([np.linspace(x0, x1, n), np.zeros(n), np.full(n, heading)])


def test_planned_body_clearances_match_hand_derived_values():
    forward = _straight(0.0, 5.0)
    # beside: the box's near side y = 1.5, the body's side at 0.971
    assert clearance(forward, CAR, shapely.Polygon(_box(2, 3, 1.5, 2.5))) == pytest.approx(1.5 - 0.971)
    # ahead: the front end reaches 5 + 3.76 = 8.76 at the end of the plan
    assert clearance(forward, CAR, shapely.Polygon(_box(10, 11, -0.5, 0.5))) == pytest.approx(10 - 8.76)
    # reversing from x = 5 to 0 (still facing +x): the rear end reaches −0.929, and 0.235 further with the longer body
    back = forward[::-1]
    behind = shapely.Polygon(_box(-3, -2, -0.5, 0.5))
    assert clearance(back, CAR, behind) == pytest.approx(2 - 0.929)
    assert clearance(back, LONGER, behind) == pytest.approx(2 - 0.929 - 0.235)
    # facing +y at the origin: the body spans x in [−0.971, 0.971], y in [−0.929, 3.76]
    turned = np.array([[0.0, 0.0, math.pi / 2]])
    assert clearance(turned, CAR, shapely.Polygon(_box(2, 3, 0, 1))) == pytest.approx(2 - 0.971)
    assert clearance(turned, CAR, shapely.Polygon(_box(-0.5, 0.5, 3.0, 4.0))) == 0.0  # overlapping


@pytest.mark.parametrize("plan_m,seen,detection_m,kind", [
    (0.30, "yes", 0.40, "left the plan"), (0.30, "no", math.nan, "left the plan"),
    (0.0, "no", math.nan, "unseen"), (0.0, "yes", 0.20, "detection off"), (0.0, "yes", 0.0, "planned through"),
    (0.0, "map", 0.0, "planned through"), (SLACK_M / 2, "yes", SLACK_M / 2, "planned through"),
    (SLACK_M / 2, "yes", 0.20, "detection off"), (SLACK_M, "yes", SLACK_M, "left the plan")])
def test_the_kind_of_a_contact(plan_m, seen, detection_m, kind):
    assert contact_kind(plan_m, seen, detection_m) == kind
    assert kind in KINDS


def _recording(truth, detection, label="vehicle 3", plan_to=6.0) -> RecordedRun:
    """A hand-made recording: one plan straight along x from the origin to ``plan_to``, made by the call at 0 s
    that detected ``detection`` as ``label``; failed calls at 1 s and 2.5 s; the body touches ``truth`` at 2 s with
    the reference point at (3, 0.3); cross-track errors 0.01, −0.1, 0.3, 0.5 at 0, 1, 2, 3 s."""
    plan = RecordedPlan(0.0, (PlanSegment(1, _straight(0.0, plan_to)),))
    calls = [RecordedCall(0.0, 0, True, "", 0.1, (detection,), (label,)),
             RecordedCall(1.0, 10, False, "", 0.1, (), ()), RecordedCall(2.5, 25, False, "", 0.1, (), ())]
    times = np.array([0.0, 1.0, 2.0, 3.0])
    return RecordedRun(
        name="hand", clip="c", boundary=_box(-20, 20, -20, 20), obstacles={"obstacle_0": truth},
        target=_box(0, 1, 0, 1), plans=[plan], calls=calls, footprint_times=times,
        footprints=np.array([_box(0, 1, 0, 1)] * 4),
        reference_points=np.array([[0, 0], [1.5, 0.1], [3, 0.3], [4, 0.5]]),
        mover_times=np.zeros(0), movers=[], contacts=[RecordedContact(2.0, "obstacle_0_1", np.array([3.0, 1.2]))],
        controller={"cross_track_m": (times, np.array([0.01, -0.1, 0.3, 0.5]))}, executed=np.zeros((0, 2)),
        outcome=None)


def test_a_contact_beside_a_clear_plan_is_the_vehicle_leaving_it():
    run = _recording(truth=_box(3, 5, 1.2, 2.2), detection=_box(3, 5, 1.5, 2.5))
    review = review_contact(run, CAR, "vehicle 3")
    assert review.plan_clearance_m == pytest.approx(1.2 - 0.971)
    assert review.seen == "yes" and review.detection_clearance_m == pytest.approx(1.5 - 0.971)
    assert (review.cross_track_m, review.cross_track_worst_m) == (0.3, 0.3)  # up to 2 s, not the 0.5 after
    assert review.off_plan_m == pytest.approx(0.3) and review.plan_time_s == 0.0
    assert (review.calls_before, review.failed_calls_since_plan) == (2, 1)  # the calls at 0 and 1 s, not 2.5 s
    assert review.kind == "left the plan" and review.geom == "obstacle_0_1"


def test_seen_detection_off_and_unseen_read_from_the_plans_call():
    run = _recording(truth=_box(3, 5, 0.95, 1.95), detection=_box(3, 5, 1.5, 2.5))  # the true box reaches the body
    off = review_contact(run, CAR, "vehicle 3")
    assert off.plan_clearance_m == 0.0 and off.seen == "yes" and off.kind == "detection off"
    unseen = review_contact(run, CAR, "vehicle 4")  # the call detected another object only
    assert unseen.seen == "no" and math.isnan(unseen.detection_clearance_m) and unseen.kind == "unseen"


def test_the_detection_counts_where_the_plan_meets_the_object_not_elsewhere():
    # the true box reaches the body's side (0.971) while the reference point is below x = 1 + 0.929; its detection,
    # shifted 14 m ahead, is 0.03 m beyond the front end at the plan's end (12 + 3.76), over 9 m from those poses
    run = _recording(truth=_box(0, 1, 0.95, 1.95), detection=_box(15.79, 16.79, -0.5, 0.5), plan_to=12.0)
    review = review_contact(run, CAR, "vehicle 3")
    assert clearance(run.plans[0].poses, CAR, shapely.Polygon(_box(15.79, 16.79, -0.5, 0.5))) == pytest.approx(0.03)
    assert review.plan_clearance_m == 0.0 and review.detection_clearance_m > 9.0
    assert review.kind == "detection off"
    beside = review_contact(_recording(truth=_box(0, 1, 0.95, 1.95), detection=_box(0, 1, 0.99, 1.99),
                                       plan_to=12.0), CAR, "vehicle 3")
    assert beside.detection_clearance_m == pytest.approx(0.99 - 0.971) and beside.kind == "planned through"


def test_the_longer_body_turns_a_clear_plan_into_one_planned_through():
    box = _box(10.0, 11.0, -0.5, 0.5)  # the plan's front end reaches 6 + 3.76 = 9.76, the longer body's 9.995
    run = _recording(truth=box, detection=box)
    nominal, longer = review_contact(run, CAR, "vehicle 3"), review_contact(run, LONGER, "vehicle 3", planned=CAR)
    assert nominal.plan_clearance_m == pytest.approx(0.24) and nominal.kind == "left the plan"
    assert longer.plan_clearance_m == pytest.approx(0.005) and longer.kind == "planned through"
    assert longer.plan_clearance_nominal_m == pytest.approx(0.24)


def test_a_bad_study_folder_is_one_error_line(tmp_path, capsys):
    assert "no such folder" in one_error_line(capsys, main, [str(tmp_path / "missing")])
    assert "no records.csv" in one_error_line(capsys, main, [str(tmp_path)])
    (tmp_path / "records.csv").write_text("factor,level\n")
    (tmp_path / "config.json").write_text("{}")
    assert "no recordings in rrd/" in one_error_line(capsys, main, [str(tmp_path)])


def test_help_explains_the_review(capsys):
    text = help_text(capsys, main)
    assert "STUDY_DIR" in text and "cases.csv" in text and "true outline" in text


CLIP = "eval-1000015"
"""Hybrid A* touches the site boundary on this clip undisturbed and with the longer body, after one plan."""


def test_a_one_clip_study_is_reviewed_end_to_end(tmp_path):
    out = tmp_path / "study"
    robustness_main(["--clips", "--clip-names", CLIP, "--planners", "hybrid_astar", "--factors", "body_length",
                     "--levels", "severe", "--workers", "1", "--out", str(out)])
    recordings = sorted(p.name for p in (out / "rrd").glob("*.rrd"))
    assert recordings == [f"body_length_severe_hybrid_astar_{CLIP}.rrd", f"none_none_hybrid_astar_{CLIP}.rrd"]
    main([str(out)])
    rows = {r["factor"]: r for r in csv.DictReader((out / "review" / "cases.csv").open())}
    study = {r["factor"]: r for r in csv.DictReader((out / "records.csv").open())}
    assert set(rows) == {"none", "body_length"}
    for factor, row in rows.items():
        run = read_run(out / "rrd" / row["recording"])
        assert (row["level"], row["planner"], row["clip"], row["caused"]) == (
            "severe" if factor == "body_length" else "none", "hybrid_astar", CLIP, "no")  # fails undisturbed too
        assert row["study_outcome"] == "contact" == study[factor]["reason"]
        assert row["matches_study"] == ("yes" if run.contacts[0].geom == study[factor]["first_contact_geom"] else "no")
        assert float(row["contact_t_s"]) == pytest.approx(run.contacts[0].time_s, abs=0.005)
        assert row["touched_object"] == "boundary" and row["seen"] == "map" and row["kind"] in KINDS
        assert int(row["calls_before_contact"]) == sum(c.time_s <= run.contacts[0].time_s for c in run.calls)
    # the same single plan, driven with a body 0.47 m longer, passes the wall closer
    assert float(rows["body_length"]["plan_clearance_m"]) < float(rows["none"]["plan_clearance_m"])
    assert rows["none"]["plan_clearance_m"] == rows["none"]["plan_clearance_nominal_m"]
    for sheet in ("none.png", "body_length.png"):
        path = out / "review" / sheet
        assert path.stat().st_size < 300_000 and Image.open(path).size[0] > 300
    assert "| body_length |" in (out / "review" / "cases.md").read_text()


def test_the_driven_body_is_the_disturbed_plant_body(tmp_path):
    out = tmp_path / "study"
    robustness_main(["--clips", "--clip-names", CLIP, "--planners", "hybrid_astar", "--factors", "body_length",
                     "--levels", "severe", "--workers", "1", "--no-rrd", "--out", str(out)])
    (out / "rrd").mkdir()
    (out / "rrd" / "placeholder.rrd").write_bytes(b"")
    study = load_study(out)
    (planned, nominal), (planned_too, longer) = bodies(study, "none", "none"), bodies(study, "body_length", "severe")
    assert planned == nominal == planned_too == CAR  # the planners keep the nominal spec
    assert longer.length_m - CAR.length_m == pytest.approx(0.10 * CAR.length_m)  # +10 % at the severe level
    assert longer.front_overhang_m - CAR.front_overhang_m == pytest.approx(longer.rear_overhang_m - CAR.rear_overhang_m)
