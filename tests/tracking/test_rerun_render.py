"""tracking.rerun_log and tracking.render: an .rrd with the expected entities, non-blank off-screen frames, the
viewer layout in every recording, merged recordings optimised."""

import dataclasses
from collections import Counter

import pytest
from rerun.chunk import OptimizationProfile, RrdReader
from tracking_helpers import open_scene, plan_end, plan_from_arcs

from np_sim.clips import load_clips
from np_sim.planners import HybridAStar, HybridAStarConfig
from tracking.clip_run import ClipRunConfig, clip_tracker_config, run_clip
from tracking.config import ExecutorConfig, TrackerConfig
from tracking.executor import execute
from tracking.render import CAMERAS, FrameRenderer
from tracking.rerun_log import merge_recordings
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


VIEW_OF_ARCHETYPE = {"LineStrips2D": "2D", "Points2D": "2D", "EncodedImage": "2D", "Scalars": "TimeSeries",
                     "TextLog": "TextLog"}
"""The view class that draws each archetype the run logs (a 2-D view draws nothing of a time series and so on)."""


def _views(path) -> dict[str, tuple[str, str, list[str]]]:
    """Display name -> (view class, origin, contents queries) of the one blueprint stored in the .rrd at ``path``."""
    reader = RrdReader(str(path))
    (entry,) = reader.blueprints()
    rows: dict[str, dict] = {}
    for chunk in reader.store(store=entry).stream().to_chunks():
        batch = chunk.to_record_batch()
        values = {name: batch.column(name).to_pylist()[-1] for name in batch.schema.names if ":" in name}
        rows.setdefault(chunk.entity_path.removesuffix("/ViewContents"), {}).update(values)
    return {row["ViewBlueprint:display_name"][0]: (row["ViewBlueprint:class_identifier"][0],
                                                   row["ViewBlueprint:space_origin"][0], row["ViewContents:query"])
            for row in rows.values() if "ViewBlueprint:class_identifier" in row}


def _logged(path) -> dict[str, str]:
    """Entity path -> short archetype name of everything the recording in ``path`` logged."""
    columns = RrdReader(str(path)).store().schema().component_columns()
    return {c.entity_path: c.archetype.rsplit(".", 1)[-1] for c in columns if not c.is_property}


def _chunks(path) -> dict[tuple[str, str], list]:
    """(store kind, recording id) -> the chunks of that store in ``path``."""
    reader = RrdReader(str(path))
    return {(e.kind, e.recording_id): reader.store(store=e).stream().to_chunks()
            for e in reader.recordings() + reader.blueprints()}


@pytest.fixture(scope="module")
def clip_recording(tmp_path_factory):
    """A short clip run with replans (Hybrid A*, footprint, a search budget no load can reach) written with small
    camera frames, as the closed-loop job writes it."""
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000009")
    tracker = clip_tracker_config()
    tracker = dataclasses.replace(tracker, executor=dataclasses.replace(tracker.executor, render_fps=2.0,
                                                                        render_width=160, render_height=120))
    path = tmp_path_factory.mktemp("clip") / f"{clip.name}_hybrid_astar.rrd"
    planner = HybridAStar(HybridAStarConfig(time_budget_s=60.0), convention="footprint")
    run = run_clip(clip, planner, config=ClipRunConfig(tracker=tracker), rerun_path=path, render=True)
    assert run.record.plans_used >= 2, run.record.detail
    return path


def test_a_clip_recording_opens_on_the_world_the_cameras_the_scalars_and_the_outcome(clip_recording):
    views = _views(clip_recording)
    assert {name: view[:2] for name, view in views.items()} == {
        "World": ("2D", "world"), "Top-down camera": ("2D", "camera/topdown"), "Chase camera": ("2D", "camera/chase"),
        "Controller": ("TimeSeries", "controller"), "Outcome": ("TextLog", "run")}
    assert all(view[2] == ["$origin/**"] for view in views.values())
    logged = _logged(clip_recording)
    assert {"/world/detections", "/world/plan", "/world/executed", "/world/vehicle/footprint", "/camera/chase",
            "/camera/topdown", "/controller/speed_mps", "/run/outcome"} <= set(logged)
    for entity, archetype in logged.items():
        if archetype not in VIEW_OF_ARCHETYPE:
            continue  # run/clip, a text document: the clip is also the recording's name
        showing = [name for name, (kind, origin, _) in views.items() if entity.startswith(f"/{origin}/")
                   or entity == f"/{origin}"]
        assert len(showing) == 1 and views[showing[0]][0] == VIEW_OF_ARCHETYPE[archetype], (entity, showing)
    two_d = [e for e, a in logged.items() if a in ("LineStrips2D", "Points2D")]
    assert two_d and all(e.startswith("/world/") for e in two_d)
    (store,) = [chunks for (kind, _), chunks in _chunks(clip_recording).items() if kind == "recording"]
    static, temporal = set(), set()
    for chunk in store:
        (static if chunk.is_static else temporal).update(
            (chunk.entity_path, name) for name in chunk.to_record_batch().schema.names if ":" in name)
    assert not static & temporal  # static data would hide every value logged on the timeline (the replans)
    assert "/run/outcome" not in {entity for entity, _ in static}  # the text-log view lists no static rows
    assert sum(c.num_rows for c in store if c.entity_path == "/world/plan") >= 2  # the first plan and replans
    names = [c.to_record_batch().column("RecordingInfo:name").to_pylist() for c in store
             if "RecordingInfo:name" in c.to_record_batch().schema.names]
    assert names == [[[clip_recording.stem]]]


def test_merged_recordings_keep_every_row_with_at_most_one_chunk_per_entity(clip_recording, tmp_path, cusp_plan):
    short = tmp_path / "short.rrd"
    execute(open_scene(plan_end(cusp_plan)), cusp_plan, rerun_path=short)
    merged = merge_recordings([clip_recording, short], tmp_path / "merged.rrd")
    inputs = {**_chunks(clip_recording), **_chunks(short)}
    output = _chunks(merged)
    recordings = {key for key in inputs if key[0] == "recording"}
    assert {key for key in output if key[0] == "recording"} == recordings
    assert sum(key[0] == "blueprint" for key in output) == 1  # one layout, not one per run
    assert set(_views(merged)) == set(_views(clip_recording))
    # Optimisation merges the chunks of an entity of one recording while the merged chunk stays under the
    # profile's size and row limits; it never mixes static with temporal rows, and static rows of different
    # components (the recording's name and start time) stay apart. With every entity's data well under the limits,
    # a recording ends with one chunk per entity's temporal rows and per static component set, the blueprint with
    # one per blueprint entity.
    profile = OptimizationProfile.OBJECT_STORE
    bound = 0
    for key in recordings:
        rows, size, kinds = Counter(), Counter(), set()
        for chunk in inputs[key]:
            columns = tuple(sorted(chunk.to_record_batch().schema.names)) if chunk.is_static else ()
            kinds.add((chunk.entity_path, chunk.is_static, columns))
            rows[chunk.entity_path, chunk.is_static] += chunk.num_rows
            size[chunk.entity_path, chunk.is_static] += chunk.to_record_batch().nbytes
        assert max(size.values()) < profile.max_bytes / 2 and max(rows.values()) < profile.max_rows_if_unsorted / 2
        bound += len(kinds)
        out_rows = Counter()
        for chunk in output[key]:
            out_rows[chunk.entity_path, chunk.is_static] += chunk.num_rows
        assert out_rows == rows  # nothing lost or duplicated
    (layout,) = [chunks for (kind, _), chunks in output.items() if kind == "blueprint"]
    bound += len({chunk.entity_path for chunk in layout})
    chunks_in, chunks_out = sum(len(inputs[k]) for k in recordings), sum(len(c) for c in output.values())
    assert chunks_out <= bound, (chunks_in, chunks_out, bound)
