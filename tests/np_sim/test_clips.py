"""Clips of the delivery site: shipped eval clips, splits, frame scenes, noise model, difficulty rule, resets, CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Point
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim import clips as clips_module
from np_sim.clips import (
    N_CLIPS,
    SEED_BASE,
    SITE_OBSERVATION,
    ClipRejected,
    DifficultyRule,
    clip_difficulty,
    generate_candidate,
    generate_clip,
    generate_split,
    load_clips,
    polygon_distances,
    sample_recorded_reset,
    sample_training_scene,
    training_pool,
    split_of_seed,
)
from np_sim.clips.generation import mover_poses
from np_sim.collision import path_valid
from np_sim.errors import ConfigError
from np_sim.geodesic import geodesic_grid
from np_sim.vehicle import VehicleSpec

VEHICLE = VehicleSpec()


@pytest.fixture(scope="module")
def eval_clips():
    return load_clips("eval")


@pytest.fixture(scope="module")
def train_clips():
    clips, _ = generate_split("train", 3)
    return clips


def test_forty_seven_eval_clips_load_disjoint_from_train(eval_clips, train_clips):
    assert len(eval_clips) == N_CLIPS["eval"] == 47
    assert len({c.name for c in eval_clips}) == len({c.seed for c in eval_clips}) == 47
    assert all(c.split == "eval" and c.seed >= SEED_BASE["eval"] and split_of_seed(c.seed) == "eval"
               for c in eval_clips)
    assert all(c.split == "train" and split_of_seed(c.seed) == "train" for c in train_clips)
    assert not {c.name for c in eval_clips} & {c.name for c in train_clips}
    assert not {c.seed for c in eval_clips} & {c.seed for c in train_clips}
    assert [c.seed for c in train_clips] == [0, 1, 2]  # the train stream starts at seed 0
    # all 1,000 training clips, without generating them: a clip is a function of its seed, the train stream walks
    # seeds upward from 0 and may not reach 1,000,000 (next test), and every eval seed lies at or above it
    assert min(c.seed for c in eval_clips) >= 1_000_000
    assert all(c.target_spot in range(len(c.site.spots)) for c in eval_clips)
    assert all(np.array_equal(c.target, c.site.spots[c.target_spot].pose) for c in eval_clips)
    assert all(50 <= c.n_frames <= 100 for c in eval_clips)


def test_the_train_seed_stream_stops_before_the_eval_seeds(monkeypatch):
    monkeypatch.setitem(SEED_BASE, "train", 999_999)  # one seed left below the eval stream
    with pytest.raises(ConfigError, match="the train seed stream ran into the eval stream's seeds"):
        generate_split("train", 3)


def test_unknown_split_names_the_valid_ones():
    with pytest.raises(ConfigError, match=r"unknown split 'test'; expected one of 'train', 'eval'"):
        load_clips("test")


def test_every_eval_frame_scene_fits_the_site_observation(eval_clips):
    capacity = SITE_OBSERVATION.capacity()
    for clip in eval_clips:
        for i in range(clip.n_frames):
            scene = clip.frame_scene(i)  # validated inside: target free, capacity
            scene.validate(capacity=capacity)
            assert len(scene.obstacles) <= 10
            assert all(len(o.vertices) == 5 for o in scene.obstacles)
            assert len(scene.boundary) == clip.site.n_edges


def test_nearest_ten_are_the_ten_nearest_by_brute_force(eval_clips):
    rng = np.random.default_rng(0)
    checked = 0
    for clip in eval_clips[::4]:
        for frame in (0, clip.n_frames // 2):
            ids, polygons = clip.detections(clip.detection_frame(frame))
            assert len(polygons) > 10
            for pose in (clip.start, np.array([*rng.uniform([5, 5], [55, 40]), 0.0])):
                scene = clip.frame_scene(frame, pose=pose)
                point = Point(pose[:2])
                exact = np.array([ShapelyPolygon(p).distance(point) for p in polygons])
                np.testing.assert_allclose(polygon_distances(pose[:2], polygons), exact, atol=1e-9)
                kept = {tuple(o.vertices.ravel()) for o in scene.obstacles}
                nearest = {tuple(polygons[j].ravel()) for j in np.argsort(exact, kind="stable")[:10]}
                assert kept == nearest
                assert sorted(exact)[9] < sorted(exact)[10]  # no tie at the cut
                checked += 1
    assert checked >= 40


def test_ground_truth_is_stored_apart_and_detections_differ_by_bounded_jitter(eval_clips):
    config = clips_module.ClipConfig()
    residuals = []
    for clip in eval_clips[::3]:
        bound = config.jitter_truncation_sd * math.sqrt(2) * clip.jitter_sd_m + 0.005
        corner_errors = []
        for frame in range(0, clip.n_frames, 7):
            ids, polygons = clip.detections(frame)
            truth = clip.ground_truth(frame)
            assert len(truth) == len(clip.objects) >= len(ids)
            for oid, det in zip(ids, polygons):
                gt = truth[oid]
                gt_shape = ShapelyPolygon(gt)
                overshoot = 0.0 if len(gt) == 4 else np.max(np.linalg.norm(gt - gt.mean(axis=0), axis=1)) * (
                    1 / math.cos(math.pi / 5) - 1) + 1e-3
                for vertex in det:
                    assert gt_shape.exterior.distance(Point(vertex)) <= bound + overshoot
                if len(gt) == 4:  # rectangle: its four corners are detection vertices, jittered
                    d = np.linalg.norm(det[None, :, :] - gt[:, None, :], axis=2)
                    corner_errors.append(det[d.argmin(axis=1)] - gt)
        sd = np.concatenate(corner_errors).std()
        residuals.append((sd, clip.jitter_sd_m))
        assert 0.7 * clip.jitter_sd_m < sd < 1.15 * clip.jitter_sd_m
    assert 0.05 <= min(j for _, j in residuals) and max(j for _, j in residuals) <= 0.15


def test_dropouts_and_missed_frames_hold_the_last_detections(eval_clips):
    missed = [(c, i) for c in eval_clips for i in np.flatnonzero(c.frame_missed)]
    assert missed and all(not c.frame_missed[0] for c in eval_clips)
    clip, frame = missed[0]
    assert len(clip.detections(frame)[0]) == 0
    held = clip.detection_frame(frame)
    assert held < frame and not clip.frame_missed[held]
    assert clip.frame_scene(frame).tags["detection_frame"] == held
    rows = sum(len(c.det_object) for c in eval_clips)
    possible = sum(len(c.objects) * int((~c.frame_missed).sum()) for c in eval_clips)
    assert 0.01 < 1 - rows / possible < 0.10


def test_target_is_free_in_every_frame_and_start_at_frame_zero(eval_clips, train_clips):
    for clip in eval_clips + train_clips:
        target = ShapelyPolygon(VEHICLE.footprint(clip.target))
        start = ShapelyPolygon(VEHICLE.footprint(clip.start))
        for i in range(clip.n_frames):
            truth = [ShapelyPolygon(p) for p in clip.ground_truth(i)]
            assert not np.any(shapely.intersects(truth, target)), (clip.name, i)
        gt0 = clip.frame_scene(0, ground_truth=True)
        assert path_valid(gt0, clip.start[None, :], convention="footprint")
        assert not np.any(shapely.intersects([ShapelyPolygon(p) for p in clip.ground_truth(0)], start))


def _geodesic_of_start(grid, xy) -> float:
    """The written rule for the start's geodesic distance: its own cell's distance when that cell is free, else
    the free cell of its 3 × 3 block whose centre is nearest, plus the straight distance to that centre."""
    row, col = (int(v) for v in grid.cell_of(np.asarray(xy, float)))
    candidates = []
    for r in range(row - 1, row + 2):
        for c in range(col - 1, col + 2):
            if 0 <= r < grid.free.shape[0] and 0 <= c < grid.free.shape[1] and grid.free[r, c]:
                centre = grid.origin + grid.cell_m * np.array([c, r])
                if (r, c) == (row, col):
                    return float(grid.distance[r, c])
                candidates.append((math.dist(xy, centre), float(grid.distance[r, c])))
    return min(candidates)[0] + min(candidates)[1] if candidates else math.inf


def test_every_eval_clip_satisfies_the_written_difficulty_rule(eval_clips):
    rule = DifficultyRule()
    for clip in eval_clips:
        d = clip_difficulty(clip)
        assert d == clip.difficulty and d.difficult, clip.name
        # independent recomputation of the four criteria
        delta = clip.start[:2] - clip.target[:2]
        straight = float(np.hypot(*delta))
        cos_h = math.cos(clip.start[2] - clip.target[2])
        heading = np.array([math.cos(clip.target[2]), math.sin(clip.target[2])])
        along, lateral = float(delta @ heading), float(delta[0] * -heading[1] + delta[1] * heading[0])
        grid = geodesic_grid(clip.frame_scene(0, ground_truth=True))
        assert d.geodesic_m == pytest.approx(_geodesic_of_start(grid, clip.start[:2]), abs=1e-3)
        detour = straight >= rule.detour_min_straight_m and d.geodesic_m / straight >= rule.detour_ratio
        averse = cos_h < rule.averse_cos and straight <= rule.averse_radius_m
        front = (clip.site.spots[clip.target_spot].kind == "reverse" and 0 < along <= rule.front_depth_m
                 and abs(lateral) <= rule.front_halfwidth_m and cos_h < rule.front_aligned_cos)
        target = ShapelyPolygon(VEHICLE.footprint(clip.target))
        clearance = min([target.exterior.distance(ShapelyPolygon(clip.site.boundary).exterior)]
                        + [target.distance(ShapelyPolygon(p)) for i in range(clip.n_frames)
                           for p, o in zip(clip.ground_truth(i), clip.objects) if o.moving or i == 0])
        tight = clearance < rule.tight_clearance_m
        assert (detour, averse, front, tight) == (d.detour, d.averse_heading, d.front_of_reverse_bay, d.tight)
    reasons = {r for c in eval_clips for r in c.difficulty.reasons}
    assert reasons == {"detour", "averse_heading", "front_of_reverse_bay", "tight"}


def test_eval_clips_are_the_first_difficult_candidates_and_regenerate_exactly(eval_clips):
    seeds = [c.seed for c in eval_clips]
    assert seeds == sorted(seeds)
    for seed in range(SEED_BASE["eval"], seeds[2] + 1):
        candidate = generate_candidate(seed)
        if seed in seeds:
            assert candidate.clip.to_dict() == eval_clips[seeds.index(seed)].to_dict()
        else:
            assert candidate.clip is None or not candidate.clip.difficulty.difficult


def test_train_clips_are_deterministic_in_their_seed(train_clips):
    again = generate_clip(1)
    assert again.to_dict() == train_clips[1].to_dict()
    assert again.to_dict() != train_clips[2].to_dict()
    with pytest.raises(ConfigError, match="expected an integer >= 0"):
        generate_clip(-3)
    assert issubclass(ClipRejected, ValueError)


def test_training_reset_sampler(train_clips):
    rng = np.random.default_rng(7)
    for _ in range(5):
        scene, start = sample_training_scene(rng, train_clips)
        scene.validate(capacity=SITE_OBSERVATION.capacity())
        assert len(scene.obstacles) <= 10 and all(len(o.vertices) == 5 for o in scene.obstacles)
        assert any(np.array_equal(scene.target, s.pose) for s in train_clips[0].site.spots)
        assert path_valid(scene, start[None, :], convention="footprint")
        assert np.isfinite(geodesic_grid(scene).distance_at(start[:2]))
    a = sample_training_scene(np.random.default_rng(3), train_clips)
    b = sample_training_scene(np.random.default_rng(3), train_clips)
    assert a[0].to_dict() == b[0].to_dict() and np.array_equal(a[1], b[1])


def test_recorded_resets_replay_the_clips_own_task_as_the_closed_loop_sees_it(eval_clips):
    clips = eval_clips[:4]
    by_name = {c.name: c for c in clips}
    exact = [sample_recorded_reset(np.random.default_rng(seed), clips, exact_share=1.0) for seed in range(6)]
    for scene, start in exact:
        clip_name, frame, kind = scene.name.split("/")
        clip = by_name[clip_name]
        assert kind == "recorded" and np.array_equal(start, clip.start) and np.array_equal(scene.target, clip.target)
        planned = clip.frame_scene(int(frame[1:]), pose=start)  # the scene the closed loop plans in from there
        assert [o.vertices.tolist() for o in scene.obstacles] == [o.vertices.tolist() for o in planned.obstacles]
    moved = [sample_recorded_reset(np.random.default_rng(seed), clips, exact_share=0.0) for seed in range(12)]
    offsets = []
    for scene, start in moved:
        clip = by_name[scene.name.split("/")[0]]
        offsets.append(np.hypot(*(start[:2] - clip.start[:2])))
        footprint = ShapelyPolygon(VEHICLE.footprint(start))
        assert ShapelyPolygon(clip.site.boundary).contains(footprint)
        assert not any(footprint.intersects(ShapelyPolygon(o.vertices)) for o in scene.obstacles)
        assert path_valid(scene, start[None, :], convention="footprint")
    assert 0.0 < np.median(offsets) < 1.5  # sd 0.5 m per axis: median radius ≈ 0.59 m
    a = sample_recorded_reset(np.random.default_rng(3), clips)
    b = sample_recorded_reset(np.random.default_rng(3), clips)
    assert a[0].to_dict() == b[0].to_dict() and np.array_equal(a[1], b[1])
    with pytest.raises(ConfigError, match="expected at least one clip"):
        sample_recorded_reset(np.random.default_rng(0), [])


def test_recorded_resets_for_a_grown_body_skip_frames_that_crowd_the_target(eval_clips):
    """A training margin grows the body (`VehicleSpec.inflated`): frames whose detections come closer than the
    margin to the target are drawn again, so every reset keeps the margin at the target (shapely distance)."""
    from np_sim.errors import SceneError

    grown = VEHICLE.inflated(0.4)
    clips = eval_clips[:12]

    def crowded(clip, frame):
        try:
            clip.frame_scene(frame, vehicle=grown)
            return False
        except SceneError:
            return True

    assert any(crowded(c, f) for c in clips for f in range(0, c.n_frames, 10))  # the rule has work to do here
    for seed in range(10):
        scene, start = sample_recorded_reset(np.random.default_rng(seed), clips, vehicle=grown)
        body = ShapelyPolygon(VEHICLE.footprint(scene.target))
        assert min(body.distance(ShapelyPolygon(o.vertices)) for o in scene.obstacles) >= 0.4 - 1e-9


def test_a_pool_with_recorded_resets_keeps_its_app_c_part(eval_clips):
    clips = eval_clips[:3]
    plain_scenes, plain_starts = training_pool(4, seed=5, clips=clips)
    scenes, starts = training_pool(4, seed=5, clips=clips, recorded_share=0.5, recorded_clips=eval_clips[3:6])
    assert [s.to_dict() for s in scenes[:2]] == [s.to_dict() for s in plain_scenes[:2]]
    assert np.array_equal(starts[:2], plain_starts[:2])
    assert [s.name.endswith("/reset") for s in scenes] == [True, True, False, False]
    assert {s.name.split("/")[0] for s in scenes[2:]} <= {c.name for c in eval_clips[3:6]}
    with pytest.raises(ConfigError, match="needs recorded_clips"):
        training_pool(4, seed=5, clips=clips, recorded_share=0.5)
    with pytest.raises(ConfigError, match=r"recorded_share must be in \[0, 1\], got 1.5"):
        training_pool(4, seed=5, clips=clips, recorded_share=1.5, recorded_clips=clips)


def test_cli_summary_and_figure(tmp_path, capsys):
    out = clips_module.main(["--summary", "--train-sample", "2", "--figure", load_clips("eval")[0].name,
                             "--out", str(tmp_path / "clip.png")])
    printed = capsys.readouterr().out
    assert "50 boundary edges" in printed and "eval: 47 clips" in printed and "rejected" in printed
    assert out["eval"]["difficult"] == 47
    assert (tmp_path / "clip.png").stat().st_size > 10_000


def test_a_pushed_cart_stops_and_a_pedestrian_turns_back_at_the_path_ends():
    travelled = np.array([0.0, 2.0, 4.0, 6.0, 9.0, 13.0])
    a, phi, length = np.array([1.0, 2.0]), math.pi / 2, 4.0  # a path from (1, 2) straight up to (1, 6)
    cart = mover_poses("cart", a, phi, length, travelled)
    np.testing.assert_allclose(cart[:, :2], [[1, 2], [1, 4], [1, 6], [1, 6], [1, 6], [1, 6]], atol=1e-3)
    np.testing.assert_allclose(cart[:, 2], math.pi / 2, atol=1e-4)
    walker = mover_poses("pedestrian", a, phi, length, travelled)
    # up 4 m, back down 4 m, up again: 6 m walked is 2 m back down, 9 m is 1 m up again, 13 m is 3 m down
    np.testing.assert_allclose(walker[:, :2], [[1, 2], [1, 4], [1, 6], [1, 4], [1, 3], [1, 5]], atol=1e-3)
    np.testing.assert_allclose(np.sin(walker[:, 2]), [1, 1, 1, -1, 1, -1], atol=1e-4)


def test_movers_of_generated_clips_follow_their_straight_paths(eval_clips):
    config = clips_module.ClipConfig()
    for clip in eval_clips[::5]:
        for obj in (o for o in clip.objects if o.moving):
            xy = obj.poses[:, :2]
            speed = np.hypot(*np.diff(xy, axis=0).T).max() / clip.frame_dt_s
            lo, hi = config.cart_speed_range_mps if obj.kind == "cart" else config.pedestrian_speed_range_mps
            assert lo - 0.02 <= speed <= hi + 0.02, (clip.name, obj.id)  # positions are rounded to the millimetre
            far = xy[np.argmax(np.hypot(*(xy - xy[0]).T))]
            line = LineString([xy[0], far])  # a mover's path: from its first pose to its farthest
            assert max(line.distance(Point(p)) for p in xy) < 2e-3, (clip.name, obj.id)


def test_a_frame_scene_takes_given_detections_but_not_with_the_ground_truth(eval_clips):
    clip = eval_clips[1]
    ids, polygons = clip.detections(0)
    given = (ids[:3], polygons[:3])
    scene = clip.frame_scene(0, detections=given)
    assert sorted(tuple(o.vertices.ravel()) for o in scene.obstacles) == sorted(tuple(p.ravel()) for p in polygons[:3])
    with pytest.raises(ConfigError, match="not both"):
        clip.frame_scene(0, ground_truth=True, detections=given)
