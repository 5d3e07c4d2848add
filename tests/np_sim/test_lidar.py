"""LiDAR (paper eq:lidar-clearance, App. A): footprint ranges b_i, beam order, range cap, circle rings, clearance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import LinearRing, LineString, Point, Polygon

from np_sim.config import EnvConfig
from np_sim.env import ParkingEnv
from np_sim.lidar import cast_rays, footprint_ranges
from np_sim.observation import observation_sections
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec

BIG = [[-50.0, -50.0], [50.0, -50.0], [50.0, 50.0], [-50.0, 50.0]]
TARGET_FAR = [-40.0, -40.0, 0.0]  # the validated target sits in a free corner, away from every test pose


def scene(obstacles, boundary=BIG, target=TARGET_FAR) -> Scene:
    return Scene.from_dict({"boundary": boundary, "obstacles": obstacles, "target": target})


def ray_distance_to(geom, origin, phi, length=100.0) -> float:
    """Distance from ``origin`` to the nearest intersection of the ray at angle ``phi`` with ``geom`` (inf if none)."""
    ray = LineString([origin, (origin[0] + length * math.cos(phi), origin[1] + length * math.sin(phi))])
    inter = ray.intersection(geom)
    return math.inf if inter.is_empty else Point(origin).distance(inter)


# ---------------------------------------------------------------------------------------------- footprint ranges


@pytest.mark.parametrize(
    "spec", [VehicleSpec(), VehicleSpec(wheelbase_m=1.5, front_overhang_m=0.4, rear_overhang_m=0.6, width_m=1.2)]
)
@pytest.mark.parametrize("n_beams", [120, 7, 64])
def test_footprint_ranges_match_shapely(spec, n_beams):
    b = footprint_ranges(spec, n_beams)
    assert b.shape == (n_beams,)
    ring = LinearRing(spec.footprint_local())
    for i in range(n_beams):
        want = ray_distance_to(ring, (0.0, 0.0), 2 * math.pi * i / n_beams)
        assert b[i] == pytest.approx(want, rel=1e-9, abs=1e-12), i


def test_footprint_ranges_named_beams():
    b = footprint_ranges()
    assert b[0] == pytest.approx(2.8 + 0.96, abs=1e-12)  # beam 0: front bumper
    assert b[30] == pytest.approx(1.942 / 2, abs=1e-12)  # 90°: left side
    assert b[60] == pytest.approx(0.929, abs=1e-12)  # 180°: rear bumper
    assert b[90] == pytest.approx(1.942 / 2, abs=1e-12)  # 270°: right side
    np.testing.assert_allclose(b[1:60], b[119:60:-1], rtol=0, atol=1e-12)  # left/right symmetric
    assert footprint_ranges(None, 120) == pytest.approx(footprint_ranges(VehicleSpec(), 120))


# ---------------------------------------------------------------------------------------------- cast_rays


def test_cast_rays_beam_order_is_counter_clockwise_from_the_heading():
    # wall 5 m ahead (x = 5), another 3 m to the left (y = 3) of a pose at the origin heading +x
    s = scene([{"polygon": [[5, -0.5], [6, -0.5], [6, 0.5], [5, 0.5]]},
               {"polygon": [[-0.5, 3], [0.5, 3], [0.5, 4], [-0.5, 4]]}])
    d = cast_rays(s, (0.0, 0.0, 0.0))
    assert d.shape == (120,)
    assert d[0] == pytest.approx(5.0, abs=1e-12)
    assert d[30] == pytest.approx(3.0, abs=1e-12)  # beam 30 = +90° = left
    assert d[90] == 10.0 and d[60] == 10.0  # right and behind: nothing within 10 m
    # rotate the pose by +90°: the left obstacle is now straight ahead, the front one on the right (beam 90)
    d = cast_rays(s, (0.0, 0.0, math.pi / 2))
    assert d[0] == pytest.approx(3.0, abs=1e-12) and d[90] == pytest.approx(5.0, abs=1e-12)
    assert d[30] == 10.0


def test_cast_rays_cap_and_boundary():
    s = scene([])
    d = cast_rays(s, (0.0, 0.0, 0.3))
    np.testing.assert_array_equal(d, np.full(120, 10.0))  # the boundary is 50 m away: every beam capped
    np.testing.assert_array_equal(cast_rays(s, (0.0, 0.0, 0.3), max_range=20.0), np.full(120, 20.0))
    d = cast_rays(s, (46.0, 0.0, 0.0))  # 4 m from the x = 50 wall
    assert d[0] == pytest.approx(4.0, abs=1e-12)
    assert d[60] == 10.0
    d = cast_rays(s, (46.0, 0.0, 0.0), n_beams=4, max_range=100.0)
    np.testing.assert_allclose(d, [4.0, 50.0, 96.0, 50.0], rtol=0, atol=1e-9)
    with pytest.raises(ValueError):
        cast_rays(s, (0.0, 0.0, 0.0), n_beams=0)
    with pytest.raises(ValueError):
        cast_rays(s, (0.0, 0.0, 0.0), max_range=0.0)


@pytest.mark.parametrize("seed", range(6))
def test_cast_rays_matches_shapely_on_random_scenes(seed):
    """Each beam = nearest crossing of the ray (length 10 m) with every polygon ring, the 16-gon of every circle
    and the boundary ring, to 1e-6 m."""
    rng = np.random.default_rng(seed)
    obstacles = []
    for _ in range(4):
        c = rng.uniform(-12, 12, 2)
        n = int(rng.integers(3, 9))
        ang = 2 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n
        rad = rng.uniform(0.4, 2.5, n)
        obstacles.append({"polygon": np.stack([c[0] + rad * np.cos(ang), c[1] + rad * np.sin(ang)], 1).tolist()})
    for _ in range(3):
        c = rng.uniform(-12, 12, 2)
        obstacles.append({"circle": [float(c[0]), float(c[1]), float(rng.uniform(0.3, 2.0))]})
    boundary = [[-16.0, -15.0], [15.0, -16.0], [17.0, 14.0], [-3.0, 19.0], [-15.0, 15.0]]
    s = scene(obstacles, boundary=boundary, target=[0.0, 0.0, 0.0]) if _target_free(obstacles) else None
    if s is None:  # keep the seed meaningful: drop obstacles that block the target and retry
        obstacles = [o for o in obstacles if _obstacle_clear_of_target(o)]
        s = scene(obstacles, boundary=boundary, target=[0.0, 0.0, 0.0])
    rings = [LinearRing(v) for v in s.polygons_for_rays()] + [LinearRing(s.boundary)]
    for _ in range(8):
        pose = (*rng.uniform(-12, 12, 2), rng.uniform(-math.pi, math.pi))
        d = cast_rays(s, pose)
        for i in range(120):
            phi = pose[2] + 2 * math.pi * i / 120
            want = min([ray_distance_to(r, pose[:2], phi, 10.0) for r in rings] + [10.0])
            assert d[i] == pytest.approx(want, abs=1e-6), (seed, pose, i)


def _obstacle_clear_of_target(o) -> bool:
    rect = Polygon(VehicleSpec().footprint((0.0, 0.0, 0.0)))
    if "polygon" in o:
        return rect.disjoint(Polygon(o["polygon"]))
    return rect.distance(Point(o["circle"][:2])) > o["circle"][2]


def _target_free(obstacles) -> bool:
    return all(_obstacle_clear_of_target(o) for o in obstacles)


@pytest.mark.parametrize("seed", range(4))
def test_circles_are_seen_as_16_gons(seed):
    """A beam meets the 16-segment ring of the circle (App. A), never the exact disc: its distance equals the ray's
    crossing with the ring (1e-9) and is at least the exact circle distance (the ring is inscribed). Beams whose
    line passes closer to the centre than the ring's inradius r·cos(π/16) always hit; beams that clip the disc
    outside the ring miss it. Besides random poses, one pose per ring edge aims beam 0 through the sliver between
    that edge and the circle (the line at distance r(1 + cos(π/16))/2 from the centre), so clips always occur."""
    rng = np.random.default_rng(100 + seed)
    c = rng.uniform(-3, 3, 2) + np.array([0.0, 8.0])
    r = float(rng.uniform(1.0, 2.5))
    s = scene([{"circle": [float(c[0]), float(c[1]), r]}], target=[0.0, -20.0, 0.0])
    ring = LinearRing(s.obstacles[0].ring(16))
    n_hit = n_clip = 0
    poses = [(*rng.uniform(-3, 3, 2), rng.uniform(-math.pi, math.pi)) for _ in range(6)]
    h = r * (1.0 + math.cos(math.pi / 16)) / 2.0
    for k in range(16):
        a = 2 * math.pi * (k + 0.5) / 16  # outward normal of ring edge k
        q = c + h * np.array([math.cos(a), math.sin(a)])
        poses.append((q[0] + 4.0 * math.sin(a), q[1] - 4.0 * math.cos(a), a + math.pi / 2))
    for pose in poses:
        o = np.array(pose[:2])
        d = cast_rays(s, pose)
        for i in range(120):
            phi = pose[2] + 2 * math.pi * i / 120
            u = np.array([math.cos(phi), math.sin(phi)])
            # exact circle: |o + t u − c| = r
            w = o - c
            bq = float(w @ u)
            disc = bq * bq - (float(w @ w) - r * r)
            t_circle = -bq - math.sqrt(disc) if disc >= 0 and -bq - math.sqrt(disc) > 0 else math.inf
            t_ring = ray_distance_to(ring, pose[:2], phi, 10.0)
            want = min(t_ring, 10.0)
            assert d[i] == pytest.approx(want, abs=1e-9), (pose, i)
            if t_circle < 10.0:
                assert d[i] >= t_circle - 1e-12
            miss_dist = abs(w[0] * u[1] - w[1] * u[0])  # distance from the centre to the ray's line
            if bq < 0 and miss_dist < r * math.cos(math.pi / 16) - 1e-9 and t_ring < 10.0:
                assert d[i] < 10.0
                n_hit += 1
            if t_circle < 10.0 and math.isinf(t_ring):
                assert d[i] == 10.0  # clipped the exact disc between the ring and the circle: not seen
                n_clip += 1
    assert n_hit > 0 and n_clip >= 16


def test_circle_ring_hand_case():
    """Circle (6, 0.3), r = 1, pose at the origin heading +x: beam 0 (y = 0) crosses the ring edge between the
    vertices at angles π and 9π/8 (k = 8: (5, 0.3), k = 9: (5.076, −0.083)), not the circle at x = 6 − √(1 − 0.09)."""
    s = scene([{"circle": [6.0, 0.3, 1.0]}])
    d = cast_rays(s, (0.0, 0.0, 0.0))
    a0, a1 = math.pi, 9 * math.pi / 8
    p0 = np.array([6 + math.cos(a0), 0.3 + math.sin(a0)])
    p1 = np.array([6 + math.cos(a1), 0.3 + math.sin(a1)])
    x_ring = p0[0] + (0 - p0[1]) * (p1[0] - p0[0]) / (p1[1] - p0[1])
    assert d[0] == pytest.approx(x_ring, abs=1e-12)
    assert d[0] > 6 - math.sqrt(1 - 0.09)


# ---------------------------------------------------------------------------------------------- clearance


def test_observed_clearance_is_the_rectified_shapely_distance():
    """The env's LiDAR observation (the kernel the policy sees, eq:lidar-clearance) against max(d − b, 0) with d
    and b measured by shapely rays: d to the boundary ring capped at 10 m, b to the footprint ring. A pose 2 m
    behind the x = 50 wall: the front beams see d < b (clipped to 0), the rear and side beams 10 − b."""
    s = scene([])
    pose = np.array([48.0, 0.0, 0.0])
    config = EnvConfig()
    obs, _ = ParkingEnv(s, config).reset(options={"start": pose})
    lidar = obs[slice(*observation_sections(config.observation)["lidar"])]
    wall, body = LinearRing(s.boundary), LinearRing(VehicleSpec().footprint(pose))
    want = []
    for i in range(120):
        phi = 2 * math.pi * i / 120
        d = min(ray_distance_to(wall, pose[:2], phi, 10.0), 10.0)
        want.append(max(d - ray_distance_to(body, pose[:2], phi), 0.0))
    np.testing.assert_allclose(lidar, want, rtol=0, atol=1e-5)  # float32 observation
    assert lidar[0] == 0.0  # d = 2 < b = 3.76
    assert lidar[60] == pytest.approx(10.0 - 0.929, abs=1e-5) and lidar[30] == pytest.approx(10.0 - 0.971, abs=1e-5)
    assert np.any(lidar == 0) and np.any(lidar > 0)
