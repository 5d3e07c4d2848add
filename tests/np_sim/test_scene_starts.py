"""Starts of a user's scene: explicit starts and the start box / heading range in the format, and seeded draws that
reject starts in collision under the planner's convention (np_sim.scene_starts).

Draws are checked with shapely (inside the region, footprint or reference point free), and the rejection count
against the blocked share of the region: with a uniform draw, half the region covered means about as many
rejections as accepted starts.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from np_sim.errors import ConfigError, SceneError
from np_sim.scene import Scene
from np_sim.scene_starts import draw_starts, explicit_starts, scene_starts
from np_sim.vehicle import VehicleSpec

BOUNDARY = [[0, 0], [40, 0], [40, 30], [0, 30]]
WALL = [[10, 10], [20, 10], [20, 20], [10, 20]]
"""Covers the left half of the start box below."""


def _scene(**extra) -> Scene:
    return Scene.from_dict({"boundary": BOUNDARY, "obstacles": [{"polygon": WALL}], "target": [32.0, 5.0, 1.0],
                            "start_region": {"box": [10, 10, 30, 20]}, **extra})


def test_a_box_start_region_is_stored_as_its_rectangle_and_round_trips():
    scene = _scene(start_headings=[2.5, 3.8], starts=[[25.0, 15.0, 0.0], [5.0, 25.0, -1.0]])
    assert scene.start_region.tolist() == [[10, 10], [30, 10], [30, 20], [10, 20]]
    again = Scene.from_dict(scene.to_dict())
    assert again.start_headings.tolist() == [2.5, 3.8]
    assert again.starts.tolist() == [[25.0, 15.0, 0.0], [5.0, 25.0, -1.0]]
    assert "starts" not in _scene().to_dict() and "start_headings" not in _scene().to_dict()


@pytest.mark.parametrize("extra, match", [
    ({"start_headings": [1.0, 0.5]}, r"start_headings: expected \[lo, hi\]"),
    ({"start_headings": [0.0, 7.0]}, r"start_headings: .*lo \+ 2π"),
    ({"starts": [[45.0, 5.0, 0.0]]}, r"starts\[0\]: the reference point \(45, 5\) must lie strictly inside"),
    ({"starts": [[5.0, 5.0]]}, r"starts\[0\]: expected an \[x, y, theta\] pose"),
    ({"start_region": {"box": [30, 10, 10, 20]}}, r"start_region.box: expected xmin < xmax"),
])
def test_bad_start_fields_are_errors_naming_the_field(extra, match):
    with pytest.raises(SceneError, match=match):
        _scene(**extra)


def test_drawn_starts_are_reproducible_inside_the_region_and_heading_range():
    scene = _scene(start_headings=[2.5, 3.8])
    first = draw_starts(scene, 40, seed=7, convention="reference_point")
    assert np.array_equal(first.poses, draw_starts(scene, 40, seed=7, convention="reference_point").poses)
    assert not np.array_equal(first.poses, draw_starts(scene, 40, seed=8, convention="reference_point").poses)
    region, wall = Polygon([[10, 10], [30, 10], [30, 20], [10, 20]]), Polygon(WALL)
    for x, y, theta in first.poses:
        assert region.covers(Point(x, y)) and not wall.covers(Point(x, y))
        assert -math.pi <= theta <= math.pi
        unwrapped = theta if theta >= 2.5 else theta + 2 * math.pi  # the range crosses +π
        assert 2.5 <= unwrapped <= 3.8
    assert first.source == "drawn" and first.convention == "reference_point"


def test_the_rejection_count_matches_the_blocked_share_of_the_region():
    # reference points: half the box lies inside the wall, so rejections ~ accepted (negative binomial, sd ~ 28)
    drawn = draw_starts(_scene(), 400, seed=0, convention="reference_point")
    assert 300 < drawn.rejected < 500


def test_footprint_draws_keep_the_whole_vehicle_free():
    vehicle = VehicleSpec()
    drawn = draw_starts(_scene(), 30, seed=1, convention="footprint")
    boundary, wall = Polygon(BOUNDARY), Polygon(WALL)
    for pose in drawn.poses:
        body = Polygon(vehicle.footprint(pose))
        assert boundary.contains(body) and body.disjoint(wall)
    # a footprint-free start needs more room than a free reference point: more rejections on the same draws
    assert drawn.rejected > draw_starts(_scene(), 30, seed=1, convention="reference_point").rejected


def test_explicit_starts_win_and_one_in_collision_is_named():
    scene = _scene(starts=[[25.0, 15.0, 0.0]])
    starts = scene_starts(scene, n=5, seed=0)
    assert starts.source == "file" and starts.poses.tolist() == [[25.0, 15.0, 0.0]] and starts.rejected == 0
    blocked = _scene(starts=[[25.0, 15.0, 0.0], [15.0, 15.0, 0.0]])
    with pytest.raises(SceneError, match=r"starts\[1\]: the start \(15, 15, 0\) is in collision under the "
                                         r"reference_point convention"):
        explicit_starts(blocked, "reference_point")
    # 0.5 m from the wall's edge, facing away: the point is free, the body reaching 0.929 m behind it is not
    near = _scene(starts=[[20.5, 15.0, 0.0]])
    explicit_starts(near, "reference_point")
    with pytest.raises(SceneError, match=r"starts\[0\].*footprint convention"):
        explicit_starts(near, "footprint")


def test_no_starts_and_no_count_is_an_error_asking_for_one():
    with pytest.raises(ConfigError, match=r"lists no starts; give a number of starts"):
        scene_starts(_scene(), None)


def test_a_blocked_region_is_an_error_after_the_candidate_budget():
    # free reference points lie within 0.5 m of the wall; the body reaches 0.929 m behind them at least
    sliver = Scene.from_dict({"boundary": BOUNDARY, "obstacles": [{"polygon": WALL}], "target": [32.0, 5.0, 1.0],
                              "start_region": [[11, 11], [20.5, 11], [20.5, 19], [11, 19]]})
    assert len(draw_starts(sliver, 3, convention="reference_point").poses) == 3
    with pytest.raises(SceneError, match=r"only 0 of 3 starts free under the footprint convention in 500 "):
        draw_starts(sliver, 3, convention="footprint", max_candidates=500)
