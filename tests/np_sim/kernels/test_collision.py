"""Compiled collision kernels (np_sim.kernels.collision) against shapely on seeded random scenes.

Oracles (spec §2):

* reference point valid ⇔ boundary.contains(pt) (a point on the boundary is not contained), no polygon obstacle
  intersects pt (touching counts), and every circle centre is at distance > r;
* footprint valid ⇔ boundary.contains_properly(rect) (the closed rectangle strictly inside: for generic poses the
  same as ``contains``; the exact-touch case below tells them apart), rect disjoint from every polygon, and
  rect.distance(centre) > r for every circle; rect = Polygon(VehicleSpec().footprint(pose)).

Scenes are built with ``Scene.from_dict`` (validated): obstacles keep out of a reserved disc around the target.
Several scenes of different sizes are packed together so that the scene index and the padding are exercised.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon

from np_sim.kernels.collision import (CHUNK_POSES, footprint_valid, point_valid, pose_valid, poses_valid,
                                      rect_inside_boundary)
from np_sim.kernels import swept
from np_sim.kernels.geometry import footprint_corners
from np_sim.scene import PolygonObstacle, Scene
from np_sim.scene_arrays import pack_scenes
from np_sim.vehicle import VehicleSpec

SPEC = VehicleSpec()
LOCAL = SPEC.footprint_local()


def star_polygon(rng, center, r_lo, r_hi, n):
    ang = 2.0 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n + rng.uniform(0, 2 * np.pi)
    rad = rng.uniform(r_lo, r_hi, n)
    return np.stack([center[0] + rad * np.cos(ang), center[1] + rad * np.sin(ang)], axis=1)


def random_scene(rng: np.random.Generator) -> Scene:
    """Star-shaped boundary (4-10 vertices, radius 9-22 m: deep notches), 1-8 star/convex polygon obstacles and
    0-5 circles scattered over (and across) it, none within 5 m of the target at the origin (random heading)."""
    while True:
        boundary = star_polygon(rng, (0.0, 0.0), 9.0, 22.0, int(rng.integers(4, 11)))
        if Polygon(boundary).contains_properly(Point(0.0, 0.0).buffer(5.0)):
            break
    keep_out = Point(0.0, 0.0).buffer(5.0)
    obstacles = []
    while len(obstacles) < int(rng.integers(1, 9)):
        v = star_polygon(rng, rng.uniform(-20, 20, 2), 0.4, 3.5, int(rng.integers(3, 9)))
        if rng.uniform() < 0.3:
            v = np.array(shapely.MultiPoint(v).convex_hull.exterior.coords[:-1])
        if Polygon(v).is_valid and not Polygon(v).intersects(keep_out):
            obstacles.append({"polygon": v.tolist()})
    n_circles = int(rng.integers(0, 6))
    while n_circles:
        c, r = rng.uniform(-20, 20, 2), float(rng.uniform(0.2, 2.5))
        if Point(c).distance(Point(0, 0)) > 5.0 + r:
            obstacles.append({"circle": [float(c[0]), float(c[1]), r]})
            n_circles -= 1
    order = rng.permutation(len(obstacles))
    return Scene.from_dict(
        {
            "boundary": boundary.tolist(),
            "obstacles": [obstacles[i] for i in order],
            "target": [0.0, 0.0, float(rng.uniform(-math.pi, math.pi))],
        }
    )


def oracle_point(scene: Scene, x: float, y: float) -> bool:
    p = Point(x, y)
    if not Polygon(scene.boundary).contains(p):
        return False
    for o in scene.obstacles:
        if isinstance(o, PolygonObstacle):
            if Polygon(o.vertices).intersects(p):
                return False
        elif p.distance(Point(o.center)) <= o.radius:
            return False
    return True


def oracle_footprint(scene: Scene, pose) -> bool:
    rect = Polygon(SPEC.footprint(pose))
    if not Polygon(scene.boundary).contains_properly(rect):
        return False
    for o in scene.obstacles:
        if isinstance(o, PolygonObstacle):
            if not rect.disjoint(Polygon(o.vertices)):
                return False
        elif rect.distance(Point(o.center)) <= o.radius:
            return False
    return True


def query_points(rng, scene: Scene, n: int) -> np.ndarray:
    """Uniform points over (and beyond) the scene plus points near and exactly on obstacle/boundary vertices."""
    pts = [rng.uniform(-24, 24, (n, 2))]
    for o in scene.obstacles:
        if isinstance(o, PolygonObstacle):
            v = o.vertices
            pts.append(v)  # exactly on the obstacle: invalid
            pts.append(v + rng.normal(0, 0.05, v.shape))
        else:
            pts.append(o.center[None, :])
            a = rng.uniform(0, 2 * np.pi, 4)
            rr = o.radius * rng.uniform(0.9, 1.1, 4)
            pts.append(np.stack([o.center[0] + rr * np.cos(a), o.center[1] + rr * np.sin(a)], axis=1))
    pts.append(scene.boundary)  # on the boundary: invalid
    pts.append(scene.boundary * 0.98)
    return np.concatenate(pts)


def _pose_putting(rng, vertex, local_pt) -> np.ndarray:
    """A pose (random heading) whose footprint has the world point ``vertex`` at the vehicle-frame ``local_pt``."""
    th = rng.uniform(-math.pi, math.pi)
    c, s = math.cos(th), math.sin(th)
    return np.array([vertex[0] - (c * local_pt[0] - s * local_pt[1]),
                     vertex[1] - (s * local_pt[0] + c * local_pt[1]), th])


def query_poses(rng, scene: Scene, n: int) -> np.ndarray:
    """Uniform poses, poses with the reference point near obstacles and the boundary, and poses whose rectangle
    has an obstacle or boundary vertex just inside it (corners may all be free: only an edge test sees it) or
    just outside it (within 0.3 m of a side or a corner: exercises the bounding-box prefilter)."""
    near = query_points(rng, scene, 0)
    near = near + rng.normal(0, 1.5, near.shape)
    xy = np.concatenate([rng.uniform(-22, 22, (n, 2)), near])
    th = rng.uniform(-2 * math.pi, 2 * math.pi, len(xy))
    poses = [np.concatenate([xy, th[:, None]], axis=1)]
    verts = [o.vertices for o in scene.obstacles if isinstance(o, PolygonObstacle)] + [scene.boundary]
    lo, hi = LOCAL[0], LOCAL[2]  # rear-right and front-left corners in the vehicle frame
    for v in np.concatenate(verts):
        for _ in range(3):
            inside = rng.uniform(lo, hi)
            outside = rng.uniform(lo - 0.3, hi + 0.3)
            while np.all((outside >= lo) & (outside <= hi)):
                outside = rng.uniform(lo - 0.3, hi + 0.3)
            poses.append(_pose_putting(rng, v, inside)[None, :])
            poses.append(_pose_putting(rng, v, outside)[None, :])
    poses.append(scene.target[None, :])  # the validated target is footprint-free
    return np.concatenate(poses)


@pytest.fixture(scope="module")
def packed():
    rng = np.random.default_rng(2024)
    scenes = [random_scene(rng) for _ in range(8)]
    return scenes, pack_scenes(scenes)


def test_packed_scenes_have_varied_sizes(packed):
    scenes, arrays = packed
    assert len({int(n) for n in arrays.n_boundary}) > 1 and len({int(n) for n in arrays.n_poly}) > 1
    assert any(int(n) == 0 for n in arrays.n_circle) or len({int(n) for n in arrays.n_circle}) > 1


def test_point_valid_matches_shapely(packed):
    scenes, arrays = packed
    geo = arrays.geometry
    rng = np.random.default_rng(7)
    n_valid = n_invalid = 0
    for k, scene in enumerate(scenes):
        for x, y in query_points(rng, scene, 400):
            want = oracle_point(scene, x, y)
            assert bool(point_valid(geo, k, x, y)) == want, (k, x, y)
            n_valid += want
            n_invalid += not want
    assert n_valid > 500 and n_invalid > 500  # both outcomes well represented


def test_footprint_valid_matches_shapely(packed):
    scenes, arrays = packed
    geo = arrays.geometry
    rng = np.random.default_rng(8)
    corners = np.empty((4, 2))
    n_valid = n_invalid = 0
    for k, scene in enumerate(scenes):
        for x, y, th in query_poses(rng, scene, 250):
            want = oracle_footprint(scene, (x, y, th))
            assert bool(footprint_valid(geo, k, x, y, th, LOCAL, corners)) == want, (k, x, y, th)
            assert bool(pose_valid(geo, k, x, y, th, True, LOCAL, corners)) == want
            assert bool(pose_valid(geo, k, x, y, th, False, LOCAL, corners)) == oracle_point(scene, x, y)
            n_valid += want
            n_invalid += not want
    assert n_valid > 300 and n_invalid > 300


def test_poses_valid_is_all_of_the_rows(packed):
    scenes, arrays = packed
    geo = arrays.geometry
    rng = np.random.default_rng(9)
    outcomes = set()
    for k, scene in enumerate(scenes):
        for _ in range(25):
            # a short random path: mostly valid near the target, sometimes wandering into obstacles
            steps = rng.normal(0, float(rng.choice([0.3, 3.0])), (int(rng.integers(1, 31)), 3))
            poses = np.ascontiguousarray(scene.target + np.cumsum(steps, axis=0))
            for footprint in (False, True):
                if footprint:
                    want = all(oracle_footprint(scene, p) for p in poses)
                else:
                    want = all(oracle_point(scene, p[0], p[1]) for p in poses)
                assert bool(poses_valid(geo, k, poses, footprint, LOCAL)) == want, (k, footprint, poses.tolist())
                outcomes.add((footprint, want))
    assert outcomes == {(False, True), (False, False), (True, True), (True, False)}
    assert poses_valid(geo, 0, np.empty((0, 3)), True, LOCAL)  # an empty path is valid


def test_chunked_footprint_paths_match_the_per_pose_rule(packed):
    """``poses_valid`` checks footprint paths in chunks of nearby poses, skipping the edges and obstacles far from a
    chunk: its verdict must equal the per-pose rule (``footprint_valid``, itself checked against shapely above) on
    paths that start anywhere (inside, outside, across the boundary and the obstacles) and run for several chunks,
    and on every one-pose path of them."""
    scenes, arrays = packed
    geo = arrays.geometry
    rng = np.random.default_rng(11)
    corners = np.empty((4, 2))
    outcomes = set()
    for k, scene in enumerate(scenes):
        starts = query_poses(rng, scene, 40)
        for start in starts[rng.permutation(len(starts))[:60]]:
            n = int(rng.integers(1, 81))
            steps = rng.normal(0.0, float(rng.choice([0.05, 0.3, 1.5])), (n, 3)) * [1.0, 1.0, 0.2]
            poses = np.ascontiguousarray(start + np.cumsum(steps, axis=0) - steps[0])
            per_pose = [bool(footprint_valid(geo, k, x, y, th, LOCAL, corners)) for x, y, th in poses]
            assert bool(poses_valid(geo, k, poses, True, LOCAL)) == all(per_pose), (k, poses.tolist())
            assert [bool(poses_valid(geo, k, poses[i:i + 1], True, LOCAL)) for i in range(n)] == per_pose
            outcomes.add((n > CHUNK_POSES, all(per_pose)))
    assert outcomes == {(False, True), (False, False), (True, True), (True, False)}


def _exact_scene(extra_obstacles, boundary=None) -> Scene:
    return Scene.from_dict(
        {
            "boundary": boundary if boundary is not None else [[-30, -30], [30, -30], [30, 30], [-30, 30]],
            "obstacles": extra_obstacles,
            "target": [-20.0, -20.0, 0.0],
        }
    )


def test_exact_touching_is_a_collision():
    """Heading 0 (corner coordinates exact, identical in VehicleSpec.footprint and the kernel): an obstacle
    vertex on the front-left corner, an obstacle edge along the rear edge, a boundary corner on the rear-right
    corner — each touch is a collision; nudged off by 1e-9 m each is free. A point on a circle's rim (exactly
    representable: centre (5, 5), r = 5, point (8, 9)) is a collision."""
    pose = (1.0, 2.0, 0.0)
    fl = SPEC.footprint(pose)[2]
    rr = SPEC.footprint(pose)[0]
    cases = []
    for eps in (0.0, 1e-9):
        tri = [[fl[0] + eps, fl[1] + eps], [fl[0] + 3.0, fl[1] + 1.0], [fl[0] + 1.0, fl[1] + 3.0]]
        rear_x = rr[0] - eps
        wall = [[rear_x, 0.0], [rear_x, 4.0], [rear_x - 1.0, 4.0], [rear_x - 1.0, 0.0]]
        bnd = [[rr[0] - eps, rr[1] - eps], [30, rr[1] - eps], [30, 30], [-30, 30], [-30, -30], [rr[0] - eps, -30]]
        for obstacles, boundary in (([{"polygon": tri}], None), ([{"polygon": wall}], None), ([], bnd)):
            scene = _exact_scene(obstacles, boundary)
            want = oracle_footprint(scene, pose)
            assert want == (eps > 0.0)
            cases.append((scene, want))
    arrays = pack_scenes([c[0] for c in cases])
    corners = np.empty((4, 2))
    for k, (_, want) in enumerate(cases):
        assert bool(footprint_valid(arrays.geometry, k, *pose, LOCAL, corners)) == want, k
    # boundary contains (touching allowed) but not contains_properly: the strict convention says invalid
    touching_boundary = cases[2][0]
    assert Polygon(touching_boundary.boundary).contains(Polygon(SPEC.footprint(pose)))

    circ = _exact_scene([{"circle": [5.0, 5.0, 5.0]}])
    geo = pack_scenes([circ]).geometry
    assert Point(5, 5).distance(Point(8, 9)) == 5.0
    assert not point_valid(geo, 0, 8.0, 9.0) and not oracle_point(circ, 8.0, 9.0)
    assert point_valid(geo, 0, 8.0, 9.0 + 1e-9) and oracle_point(circ, 8.0, 9.0 + 1e-9)
    assert not point_valid(geo, 0, -30.0, 0.0) and not point_valid(geo, 0, -30.0, -30.0)  # on the boundary


# --- the body rectangle against a non-convex lot: the bounding-box shortcut of rect_inside_boundary -----------------

NOTCHED = np.array([[0.0, 0.0], [40.0, 0.0], [46.0, 12.0], [40.0, 24.0], [26.0, 24.0], [26.0, 10.0], [14.0, 10.0],
                    [14.0, 24.0], [0.0, 24.0]])
"""A 46 × 24 m lot with a slanted right side and a 12 × 14 m rectangular notch cut from its top edge (outside the
lot, inside its bounding box)."""
SLANTED = ((1, 2), (2, 3))
"""Vertex pairs of NOTCHED's slanted edges."""


def _corners(pose) -> np.ndarray:
    corners = np.empty((4, 2))
    footprint_corners(float(pose[0]), float(pose[1]), float(pose[2]), LOCAL, corners)
    return corners


def _some_edge_box_meets(corners: np.ndarray, verts: np.ndarray) -> bool:
    """Whether some edge's bounding box meets the rectangle's (numpy): the shortcut is not taken."""
    a, b = verts, np.roll(verts, -1, axis=0)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    return bool(np.any(np.all((hi >= corners.min(axis=0)) & (lo <= corners.max(axis=0)), axis=1)))


@functools.lru_cache(maxsize=1)
def _notched_geometry():
    return pack_scenes([Scene.from_dict({"boundary": NOTCHED.tolist(), "obstacles": [],
                                         "target": [7.0, 6.0, 0.0]})]).geometry


def _check_notched(poses) -> tuple[int, int]:
    """Asserts the kernel (alone and inside ``footprint_valid`` on the obstacle-free lot) equals shapely's
    ``contains_properly`` at every pose; returns how many poses took the shortcut and how many did not."""
    boundary = Polygon(NOTCHED)
    scratch = np.empty((4, 2))
    counts = [0, 0]
    for pose in poses:
        corners = _corners(pose)
        want = boundary.contains_properly(Polygon(SPEC.footprint(pose)))
        assert bool(rect_inside_boundary(corners, NOTCHED, len(NOTCHED))) == want, pose
        assert bool(footprint_valid(_notched_geometry(), 0, *map(float, pose), LOCAL, scratch)) == want, pose
        counts[_some_edge_box_meets(corners, NOTCHED)] += 1
    return counts[0], counts[1]


def _poses_around(rng, centres, n: int) -> np.ndarray:
    xy = np.repeat(np.asarray(centres, float), n, axis=0) + rng.uniform(-0.5, 0.5, (n * len(centres), 2))
    return np.column_stack([xy, rng.uniform(-math.pi, math.pi, len(xy))])


def test_bodies_far_inside_and_far_outside_a_notched_lot_take_the_shortcut_and_match_shapely():
    """Far from every edge (inside the lot, in the notch, beyond the lot) no edge's box meets the body's: one
    corner decides, and the answer is shapely's, both ways."""
    rng = np.random.default_rng(11)
    inside = _poses_around(rng, [(7.0, 5.0), (34.0, 12.0), (20.0, 4.5), (6.0, 18.0)], 25)
    outside = _poses_around(rng, [(20.0, 18.0), (60.0, 12.0), (-10.0, -10.0), (20.0, 40.0)], 25)
    assert _check_notched(inside) == (len(inside), 0)
    assert _check_notched(outside) == (len(outside), 0)
    scratch = np.empty((4, 2))
    assert all(footprint_valid(_notched_geometry(), 0, *p, LOCAL, scratch) for p in inside)
    assert not any(footprint_valid(_notched_geometry(), 0, *p, LOCAL, scratch) for p in outside)  # notch: outside


def test_bodies_near_and_across_slanted_edges_match_shapely():
    """Reference points within 4 m of a slanted edge, on either side, at every heading: the body touches, crosses
    or clears the edge (the full test), and sometimes a corner sticks out while the reference point is inside."""
    rng = np.random.default_rng(12)
    poses = []
    for i, j in SLANTED:
        a, b = NOTCHED[i], NOTCHED[j]
        normal = np.array([b[1] - a[1], a[0] - b[0]]) / np.hypot(*(b - a))  # outward (the ring is anticlockwise)
        t = rng.uniform(0.0, 1.0, 150)
        d = rng.uniform(-4.0, 4.0, 150)
        xy = a + t[:, None] * (b - a) + d[:, None] * normal
        poses.append(np.column_stack([xy, rng.uniform(-math.pi, math.pi, 150)]))
    poses = np.concatenate(poses)
    shortcut, full = _check_notched(poses)
    assert full > 200
    outcomes = [Polygon(NOTCHED).contains_properly(Polygon(SPEC.footprint(p))) for p in poses]
    inside_ref = [Polygon(NOTCHED).contains(Point(p[0], p[1])) for p in poses]
    assert any(outcomes) and not all(outcomes)
    assert any(ref and not ok for ref, ok in zip(inside_ref, outcomes))


@settings(max_examples=400, deadline=None)
@given(st.floats(-10.0, 56.0), st.floats(-10.0, 34.0), st.floats(-math.pi, math.pi))
def test_random_poses_against_a_notched_lot_match_shapely(x, y, th):
    _check_notched([(x, y, th)])


def oracle_body_clear(scene: Scene, body, reach: float) -> bool | None:
    """``swept.body_clear``'s rule from shapely: the body strictly inside the boundary and farther than ``reach``
    from the boundary and from every obstacle; None when a distance lies within 1e-7 m of ``reach`` (rounding)."""
    distances = [shapely.distance(Polygon(scene.boundary).exterior, body)]
    for o in scene.obstacles:
        if isinstance(o, PolygonObstacle):
            distances.append(shapely.distance(Polygon(o.vertices), body))
        else:
            distances.append(shapely.distance(Point(o.center), body) - o.radius)
    if any(abs(d - reach) < 1e-7 for d in distances):
        return None
    return bool(Polygon(scene.boundary).contains_properly(body)) and all(d > reach for d in distances)


def test_body_clear_matches_shapely_for_rectangles_and_points(packed):
    # the kernel skips boundary and obstacle edges whose boxes lie beyond reach of the body's box: every verdict
    # must still equal the distance rule over all edges
    scenes, arrays = packed
    geo = arrays.geometry
    rng = np.random.default_rng(10)
    hit = np.zeros(4)
    seen = set()
    for k, scene in enumerate(scenes):
        for x, y, th in query_poses(rng, scene, 120):
            margin = float(rng.choice([0.0, rng.uniform(0.0, 0.6)]))
            reach = margin + swept.EXACT_TOLERANCE_M
            rect = np.empty((4, 2))
            footprint_corners(x, y, th, LOCAL, rect)
            for body, n_body, shape in ((rect, 4, Polygon(rect)), (np.array([[x, y]] * 4), 1, Point(x, y))):
                want = oracle_body_clear(scene, shape, reach)
                if want is None:
                    continue
                assert bool(swept.body_clear(geo, k, body, n_body, margin, hit)) == want, (k, x, y, th, margin, n_body)
                seen.add((n_body, want))
    assert seen == {(4, True), (4, False), (1, True), (1, False)}
