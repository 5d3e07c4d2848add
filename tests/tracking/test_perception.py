"""tracking.perception: detections filtered over several frames, and the scene the closed-loop planner gets."""

import numpy as np
import pytest
from shapely.geometry import Point
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips import load_clips
from np_sim.errors import ConfigError
from tracking.perception import perceived_scene, tracked_detections


@pytest.fixture(scope="module")
def eval_clips():
    return load_clips("eval")


def test_tracked_detections_average_the_jitter_and_hold_dropouts(eval_clips):
    clip = max(eval_clips, key=lambda c: c.jitter_sd_m)
    static = {o.id for o in clip.objects if not o.moving}
    raw_err, tracked_err, held = [], [], 0
    for frame in range(10, clip.n_frames, 5):
        ids, polygons = clip.detections(clip.detection_frame(frame))
        one_ids, one = tracked_detections(clip, frame, 1)
        assert np.array_equal(np.sort(ids), one_ids)  # window 1 is the raw frame
        assert np.allclose(one, polygons[np.argsort(ids)])
        t_ids, tracked = tracked_detections(clip, frame, 8)
        assert set(ids) <= set(t_ids.tolist())
        held += len(set(t_ids.tolist()) - set(ids.tolist()))
        truth = clip.ground_truth(frame)
        for oid, det in zip(ids, polygons):
            if oid in static and len(truth[oid]) == 4:
                raw_err.append(np.linalg.norm(det[None] - truth[oid][:, None], axis=2).min(axis=1).mean())
        for oid, det in zip(t_ids, tracked):
            if oid in static and len(truth[oid]) == 4:
                tracked_err.append(np.linalg.norm(det[None] - truth[oid][:, None], axis=2).min(axis=1).mean())
    # the mean of up to 8 jittered detections is about √8 ≈ 2.8 times closer to the truth than one
    assert np.mean(tracked_err) < 0.6 * np.mean(raw_err)
    assert held > 0  # objects dropped out of the current frame are still there
    with pytest.raises(ConfigError, match="window must be >= 1"):
        tracked_detections(clip, 5, 0)
    assert perceived_scene(clip, 20, track_window=8).tags["track_window"] == 8
    for other in eval_clips:  # filtered frames are valid scenes with a free target (folded outlines fall back)
        for frame in range(0, other.n_frames, 4):
            perceived_scene(other, frame, track_window=5)


def test_the_filtered_scene_keeps_the_ten_tracked_detections_nearest_to_the_pose(eval_clips):
    clip = eval_clips[5]
    frame, pose = 30, np.array([*clip.start[:2] + 3.0, 0.0])
    ids, polygons = tracked_detections(clip, frame, 4)
    scene = perceived_scene(clip, frame, pose=pose, track_window=4)
    assert len(ids) > 10
    exact = np.array([ShapelyPolygon(p).distance(Point(pose[:2])) for p in polygons])
    nearest = {tuple(polygons[j].ravel()) for j in np.lexsort((ids, exact))[:10]}
    assert {tuple(o.vertices.ravel()) for o in scene.obstacles} == nearest
    assert scene.tags["detection_frame"] == clip.detection_frame(frame) and scene.tags["track_window"] == 4


def test_a_window_of_one_is_the_clips_own_frame_scene(eval_clips):
    clip = eval_clips[0]
    pose = np.array([20.0, 15.0, 0.3])
    for frame in (0, 17, clip.n_frames - 1):
        assert perceived_scene(clip, frame, pose=pose).to_dict() == clip.frame_scene(frame, pose=pose).to_dict()
        assert "track_window" not in perceived_scene(clip, frame).tags
