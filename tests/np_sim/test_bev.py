"""BEV raster (paper App. B, spec §7): pixel colours against shapely at the sample points, covered area against
shapely's area, ego alignment, the trajectory tail and its colour ramp, argument errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon

from np_sim.bev import BevConfig, _average, render_bev
from np_sim.errors import ConfigError
from np_sim.frames import place
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec

BIG = [[-50.0, -50.0], [50.0, -50.0], [50.0, 50.0], [-50.0, 50.0]]
TARGET_FAR = [-40.0, -40.0, 0.0]  # more than the image's half-diagonal from every test pose
CONFIG = BevConfig()
GREY = 150.0


def scene(obstacles, boundary=BIG, target=TARGET_FAR) -> Scene:
    return Scene.from_dict({"boundary": boundary, "obstacles": obstacles, "target": target})


def footprint_centre_pose(pose, vehicle=VehicleSpec()) -> np.ndarray:
    """World pose of the footprint centre (the image centre), from the vehicle's dimensions."""
    ahead = 0.5 * (vehicle.wheelbase_m + vehicle.front_overhang_m - vehicle.rear_overhang_m)
    return np.array([pose[0] + ahead * math.cos(pose[2]), pose[1] + ahead * math.sin(pose[2]), pose[2]])


def sample_points_world(pose, config=CONFIG) -> np.ndarray:
    """(size, size, ss², 2) world coordinates of every pixel's sample points, from the documented convention:
    pixel (r, c) sample (a, b) at ego-frame x = (c + (b + ½)/ss − W/2)/ppm, y = (H/2 − r − (a + ½)/ss)/ppm."""
    n, ss, ppm = config.size_px, config.supersample, config.pixels_per_m
    offsets = (np.arange(ss) + 0.5) / ss
    r, c, a, b = np.meshgrid(np.arange(n), np.arange(n), offsets, offsets, indexing="ij")
    x = (c + b - n / 2) / ppm
    y = (n / 2 - r - a) / ppm
    local = np.stack([x.ravel(), y.ravel()], axis=1)
    return place(local, footprint_centre_pose(pose)).reshape(n, n, ss * ss, 2)


def star_polygon(rng: np.random.Generator, centre, radius: float, n: int) -> np.ndarray:
    """A simple (star-shaped, usually non-convex) polygon around ``centre``: jittered evenly spaced angles keep every
    gap below π (sorted uniform angles could leave one wider, and the closing edge could then cross another)."""
    angles = 2 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n
    radii = rng.uniform(0.3 * radius, radius, n)
    return np.asarray(centre) + np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


def grey_share(image: np.ndarray) -> np.ndarray:
    """Grey level of each pixel whose three channels are equal (obstacle over black), 0 elsewhere (the ego)."""
    equal = (image[0] == image[1]) & (image[1] == image[2])
    return np.where(equal, image[0], 0.0)


def local_to_world(pose, xy) -> list[float]:
    return place(np.asarray(xy, float).reshape(1, 2), footprint_centre_pose(pose))[0].tolist()


# ---------------------------------------------------------------------------------------------- exact colours
@pytest.mark.parametrize("seed", range(6))
def test_each_pixel_is_the_mean_of_its_sample_points_against_shapely(seed):
    rng = np.random.default_rng(seed)
    pose = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-np.pi, np.pi)])
    polygon = star_polygon(rng, local_to_world(pose, [rng.uniform(4, 7), rng.uniform(-7, -4)]), 2.5, 9)
    circle = [*local_to_world(pose, [rng.uniform(-8, -5), rng.uniform(4, 7)]), rng.uniform(0.3, 2.0)]
    image = render_bev(scene([{"polygon": polygon.tolist()}, {"circle": circle}]), pose)

    points = sample_points_world(pose)
    inside = (shapely.contains_xy(Polygon(polygon), points[..., 0], points[..., 1])
              | (np.hypot(points[..., 0] - circle[0], points[..., 1] - circle[1]) < circle[2]))
    body = Polygon(VehicleSpec().footprint(pose))
    on_ego = shapely.contains_xy(body, points[..., 0], points[..., 1])
    assert not (inside & on_ego).any()  # the obstacles lie clear of the ego
    palette = np.array([CONFIG.background_rgb, CONFIG.obstacle_rgb, CONFIG.ego_rgb], float)
    layer = np.where(on_ego, 2, inside.astype(int))
    expected = np.floor(palette[layer].mean(axis=2) + 0.5).astype(np.uint8)  # (size, size, 3)
    np.testing.assert_array_equal(image.transpose(1, 2, 0), expected)


@pytest.mark.parametrize("seed", range(6))
def test_obstacles_across_and_beyond_every_image_edge_are_drawn_as_shapely_sees_them(seed):
    """Obstacles anywhere around the ego: inside the image, across any of its edges and wholly beyond them (a
    polygon wholly behind the ego once painted a band across its rows)."""
    rng = np.random.default_rng(200 + seed)
    pose = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-np.pi, np.pi)])
    half = CONFIG.extent_m / 2

    def away_from_the_ego():
        while True:
            xy = rng.uniform(-2 * half, 2 * half, 2)
            if np.abs(xy).max() > 6.0:
                return xy

    polygons = [star_polygon(rng, local_to_world(pose, away_from_the_ego()), 2.5, 9) for _ in range(8)]
    circles = [[*local_to_world(pose, away_from_the_ego()), rng.uniform(0.3, 2.0)] for _ in range(4)]
    obstacles = [{"polygon": p.tolist()} for p in polygons] + [{"circle": c} for c in circles]
    image = render_bev(scene(obstacles), pose)

    points = sample_points_world(pose)
    inside = np.zeros(points.shape[:-1], bool)
    for p in polygons:  # even-odd over the union is the union here: the obstacles are drawn one over another
        inside |= shapely.contains_xy(Polygon(p), points[..., 0], points[..., 1])
    for cx, cy, r in circles:
        inside |= np.hypot(points[..., 0] - cx, points[..., 1] - cy) < r
    on_ego = shapely.contains_xy(Polygon(VehicleSpec().footprint(pose)), points[..., 0], points[..., 1])
    palette = np.array([CONFIG.background_rgb, CONFIG.obstacle_rgb, CONFIG.ego_rgb], float)
    expected = np.floor(palette[np.where(on_ego, 2, inside.astype(int))].mean(axis=2) + 0.5).astype(np.uint8)
    np.testing.assert_array_equal(image.transpose(1, 2, 0), expected)


@pytest.mark.parametrize("seed", range(4))
def test_covered_area_matches_shapely_area_within_a_boundary_band(seed):
    """Σ grey/150 over the pixels, in m², is the polygon's area up to one sample spacing along its perimeter and
    the uint8 rounding of partly covered pixels."""
    rng = np.random.default_rng(100 + seed)
    pose = np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)])
    polygon = star_polygon(rng, local_to_world(pose, [0.0, 5.5]), 4.0, 12)
    image = render_bev(scene([{"polygon": polygon.tolist()}]), pose).astype(float)
    grey = grey_share(image)
    area_px = (grey / GREY).sum()
    ppm, spacing_m = CONFIG.pixels_per_m, 1.0 / (CONFIG.pixels_per_m * CONFIG.supersample)
    shape = Polygon(polygon)
    partial = ((grey > 0) & (grey < GREY)).sum()
    tolerance = shape.length * spacing_m + partial * 0.5 / GREY / ppm**2
    assert abs(area_px / ppm**2 - shape.area) <= tolerance
    assert tolerance < 0.15 * shape.area  # the band is a pixel-boundary tolerance, not a loose one


def test_disc_area_matches_shapely_area():
    pose = np.array([3.0, -2.0, 0.7])
    centre = local_to_world(pose, [-3.0, 6.0])
    image = render_bev(scene([{"circle": [*centre, 2.2]}]), pose).astype(float)
    grey = grey_share(image)
    disc = Point(centre).buffer(2.2, 256)
    spacing_m = 1.0 / (CONFIG.pixels_per_m * CONFIG.supersample)
    partial = ((grey > 0) & (grey < GREY)).sum()
    tolerance = disc.length * spacing_m + partial * 0.5 / GREY / CONFIG.pixels_per_m**2
    assert abs((grey / GREY).sum() / CONFIG.pixels_per_m**2 - disc.area) <= tolerance


def test_outside_the_boundary_is_drawn_as_obstacle():
    boundary = [[-4.0, -40.0], [45.0, -40.0], [45.0, 45.0], [-4.0, 45.0]]  # the wall x = -4 m crosses the view
    target = [30.0, 30.0, 0.0]
    image = render_bev(scene([], boundary, target), [0.0, 0.0, 0.0]).astype(float)
    centre_x = 0.5 * (VehicleSpec().front_m - VehicleSpec().rear_overhang_m)
    wall_col = 32 + (-4.0 - centre_x) * CONFIG.pixels_per_m  # column of x = -4 m
    row = image[:, 5]  # far from the ego's rows
    outside, inside = np.arange(64) + 1 < wall_col, np.arange(64) > wall_col
    assert (row[:, outside].T == CONFIG.obstacle_rgb).all() and outside.sum() >= 10
    assert not row[:, inside].any()


# ---------------------------------------------------------------------------------------------- ego alignment
def test_ego_footprint_is_centred_along_the_columns():
    vehicle = VehicleSpec()
    for theta in (0.0, 1.1, -2.5):
        image = render_bev(scene([]), [1.0, 2.0, theta]).astype(float)
        share = image[2] / CONFIG.ego_rgb[2]  # blue channel: the ego alone
        ppm = CONFIG.pixels_per_m
        band = 2 * (vehicle.length_m + vehicle.width_m) * ppm / CONFIG.supersample  # perimeter × sample spacing
        assert share.sum() == pytest.approx(vehicle.length_m * vehicle.width_m * ppm**2, abs=band)
        rows, cols = np.nonzero(share)
        weights = share[rows, cols]
        assert np.average(rows + 0.5, weights=weights) == pytest.approx(32.0, abs=0.05)
        assert np.average(cols + 0.5, weights=weights) == pytest.approx(32.0, abs=0.05)
        assert (cols.max() - cols.min() + 1) == pytest.approx(vehicle.length_m * ppm, abs=1.0)
        assert (rows.max() - rows.min() + 1) == pytest.approx(vehicle.width_m * ppm, abs=1.0)


def test_ahead_is_right_and_left_is_up():
    pose = np.array([0.0, 0.0, 2.0])
    ahead = local_to_world(pose, [7.0, 0.0])
    left = local_to_world(pose, [0.0, 7.0])
    image = render_bev(scene([{"circle": [*ahead, 1.0]}, {"circle": [*left, 1.0]}]), pose)
    grey = np.argwhere((image[0] == 150) & (image[2] == 150))
    ahead_px = grey[grey[:, 1] > 40]
    left_px = grey[grey[:, 0] < 24]
    assert len(ahead_px) and len(left_px) and len(ahead_px) + len(left_px) == len(grey)
    assert np.mean(ahead_px[:, 0] + 0.5) == pytest.approx(32.0, abs=0.2)  # same row as the ego centre
    assert np.mean(ahead_px[:, 1] + 0.5) == pytest.approx(32.0 + 7.0 * CONFIG.pixels_per_m, abs=0.2)
    assert np.mean(left_px[:, 1] + 0.5) == pytest.approx(32.0, abs=0.2)
    assert np.mean(left_px[:, 0] + 0.5) == pytest.approx(32.0 - 7.0 * CONFIG.pixels_per_m, abs=0.2)


def _moved(points, phi: float, shift) -> list:
    c, s = math.cos(phi), math.sin(phi)
    p = np.asarray(points, float).reshape(-1, 2)
    return np.stack([c * p[:, 0] - s * p[:, 1] + shift[0], s * p[:, 0] + c * p[:, 1] + shift[1]], axis=1).tolist()


@settings(max_examples=25, deadline=None)
@given(st.floats(-math.pi, math.pi), st.floats(-20, 20), st.floats(-20, 20), st.integers(0, 2**31))
def test_rotating_scene_and_ego_together_leaves_the_image_unchanged(phi, sx, sy, seed):
    rng = np.random.default_rng(seed)
    pose = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-np.pi, np.pi)])
    polygon = star_polygon(rng, local_to_world(pose, [5.0, -5.0]), 3.0, 8)
    circle = local_to_world(pose, [-6.0, 5.0])
    boundary = [local_to_world(pose, xy) for xy in ([-10.0, -10.0], [11.0, -10.0], [11.0, 9.5], [-10.0, 9.5])]
    target = footprint_back(local_to_world(pose, [-5.0, -6.0]) + [pose[2] + 0.3])
    first = scene([{"polygon": polygon.tolist()}, {"circle": [*circle, 1.5]}], boundary, target)
    moved = scene([{"polygon": _moved(polygon, phi, (sx, sy))}, {"circle": [*_moved(circle, phi, (sx, sy))[0], 1.5]}],
                  _moved(boundary, phi, (sx, sy)), [*_moved(target[:2], phi, (sx, sy))[0], target[2] + phi])
    moved_pose = [*_moved(pose[:2], phi, (sx, sy))[0], pose[2] + phi]
    a = render_bev(first, pose).astype(int)
    b = render_bev(moved, moved_pose).astype(int)
    differing = np.any(a != b, axis=0)
    assert differing.mean() <= 0.002  # only samples within rounding error of an edge may flip
    assert np.abs(a - b).max() <= 2 * 255 / CONFIG.supersample**2


# ---------------------------------------------------------------------------------------------- trajectory tail
def _ramp_blue(j: int) -> int:
    """HOPE's 20-step ramp from (10, 10, 10) to (10, 10, 200), truncated to integers: blue of step j."""
    return int(10 + 190 * j / 19)


def _pixel(image, pose, xy):
    """Colour of the pixel at ego-frame point ``xy`` (m) of an image centred on ``pose``'s footprint."""
    c = int(32 + xy[0] * CONFIG.pixels_per_m)
    r = int(32 - xy[1] * CONFIG.pixels_per_m)
    return tuple(int(v) for v in image[:, r, c])


def test_tail_is_drawn_only_when_given():
    pose = np.array([0.0, 0.0, 0.4])
    older = [local_to_world(pose, [0.0, 5.0]) + [0.4], local_to_world(pose, [0.0, 2.5]) + [0.4]]
    older = [footprint_back(p) for p in older]
    plain = render_bev(scene([]), pose)
    assert _pixel(plain, pose, (0.0, 0.0)) == CONFIG.ego_rgb
    assert _pixel(plain, pose, (0.0, 5.0)) == (0, 0, 0)
    for empty in (None, np.zeros((0, 3))):
        np.testing.assert_array_equal(render_bev(scene([]), pose, empty), plain)
    tailed = render_bev(scene([]), pose, older)
    assert _pixel(tailed, pose, (0.0, 0.0)) == (10, 10, _ramp_blue(19))  # the newest tail step covers the ego
    assert _pixel(tailed, pose, (0.0, 2.5)) == (10, 10, _ramp_blue(18))
    assert _pixel(tailed, pose, (0.0, 5.0)) == (10, 10, _ramp_blue(17))
    assert _ramp_blue(17) == 180 and _ramp_blue(18) == 190


def footprint_back(centre_pose) -> list[float]:
    """Reference-point pose whose footprint centre is ``centre_pose``."""
    ahead = 0.5 * (VehicleSpec().front_m - VehicleSpec().rear_overhang_m)
    x, y, th = centre_pose
    return [x - ahead * math.cos(th), y - ahead * math.sin(th), th]


def test_tail_keeps_the_last_twenty_poses_with_the_current_one():
    pose = np.array([0.0, 0.0, 0.0])
    far = footprint_back(local_to_world(pose, [0.0, 40.0]) + [0.0])
    tail = np.array([far] * 29)
    tail[9] = footprint_back(local_to_world(pose, [0.0, 2.5]) + [0.0])  # 20 poses back: not drawn
    tail[10] = footprint_back(local_to_world(pose, [0.0, 5.0]) + [0.0])  # 19 back: the oldest drawn
    image = render_bev(scene([]), pose, tail)
    assert _pixel(image, pose, (0.0, 2.5)) == (0, 0, 0)
    assert _pixel(image, pose, (0.0, 5.0)) == (10, 10, _ramp_blue(0)) == CONFIG.tail_oldest_rgb
    assert _pixel(image, pose, (0.0, 0.0)) == (10, 10, _ramp_blue(19)) == CONFIG.tail_newest_rgb


# ---------------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize("field, value", [("size_px", 0), ("supersample", 2.5), ("tail_poses", 300),
                                          ("pixels_per_m", -3.0), ("ego_rgb", (0, 0, 256))])
def test_bad_config_is_one_error_naming_the_field(field, value):
    with pytest.raises(ConfigError, match=rf"BevConfig\.{field}: expected"):
        BevConfig(**{field: value})


def test_bad_tail_shape_is_an_error():
    from np_sim.bev import render_bev_batch
    from np_sim.scene_arrays import pack_scenes

    arrays = pack_scenes([scene([])])
    with pytest.raises(ValueError, match="n_tail must lie in"):
        render_bev_batch(arrays, [0], [[0.0, 0.0, 0.0]], np.zeros((1, 2, 3)), [3])
    with pytest.raises(ValueError, match="scene_index must lie in"):
        render_bev_batch(arrays, [1], [[0.0, 0.0, 0.0]])


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), ss=st.sampled_from([1, 2, 3, 4, 7, 64]), labels=st.integers(1, 24))
def test_pixels_are_the_rounded_mean_colour_of_their_samples_against_numpy(seed, ss, labels):
    """A pixel against numpy's mean over its ss × ss samples, rounded half up, for any integer palette and
    supersampling up to 64."""
    rng = np.random.default_rng(seed)
    size = 2 if ss == 64 else 6
    palette = rng.integers(0, 256, (labels, 3)).astype(float)
    label = rng.integers(0, labels, (size * ss, size * ss)).astype(np.uint8)
    out = np.empty((3, size, size), np.uint8)
    _average(label, palette, ss, out)
    colours = palette[label].reshape(size, ss, size, ss, 3).mean(axis=(1, 3))
    np.testing.assert_array_equal(out, np.floor(colours + 0.5).astype(np.uint8).transpose(2, 0, 1))
