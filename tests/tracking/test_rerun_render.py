"""tracking.rerun_log and tracking.render: an .rrd with the expected entities, non-blank off-screen frames."""

import dataclasses

from rerun.chunk import RrdReader
from tracking_helpers import open_scene, plan_end, plan_from_arcs

from tracking.config import ExecutorConfig, TrackerConfig
from tracking.executor import execute
from tracking.render import CAMERAS, FrameRenderer
from tracking.world import build_world


def _entities(path) -> set[str]:
    return {line.split()[0] for line in RrdReader(str(path)).store().summary().splitlines()}


def test_rrd_holds_scene_plan_trajectory_footprint_and_scalars(tmp_path, cusp_plan):
    path = tmp_path / "run.rrd"
    record = execute(open_scene(plan_end(cusp_plan), obstacles=[{"circle": [15.0, 15.0, 1.0]}]), cusp_plan,
                     rerun_path=path)
    assert record.success and path.stat().st_size > 0
    expected = {"/world/scene/boundary", "/world/scene/obstacles", "/world/scene/target", "/world/plan",
                "/world/executed", "/world/vehicle/footprint", "/world/vehicle/reference_point", "/run/outcome",
                *(f"/controller/{n}" for n in ("cross_track_m", "heading_error_rad", "steer_curvature_cmd",
                                                "steer_curvature_ref", "speed_mps", "speed_target_mps"))}
    assert expected <= _entities(path)


def test_rendering_gives_non_blank_frames_and_logs_them(tmp_path):
    plan = plan_from_arcs([[0.0, 3.0]], start=(0.0, 0.0, 0.0))
    scene = open_scene(plan_end(plan), obstacles=[{"polygon": [[9, -1], [10, -1], [10, 1], [9, 1]]}], half=14.0)
    renderer = FrameRenderer(build_world(scene, plan.start).model, 160, 120)
    world = build_world(scene, plan.start)
    for camera in CAMERAS:
        frame = renderer.render(world.data, camera)
        assert frame.shape == (120, 160, 3) and frame.std() > 5.0
    renderer.close()
    config = dataclasses.replace(TrackerConfig(), executor=ExecutorConfig(render_fps=2.0, render_width=160,
                                                                          render_height=120))
    path = tmp_path / "render.rrd"
    record = execute(scene, plan, render=True, rerun_path=path, config=config)
    assert record.success and record.frames_rendered >= 2 * len(CAMERAS)
    assert {"/camera/topdown", "/camera/chase"} <= _entities(path)
