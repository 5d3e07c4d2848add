"""The delivery site: edge count, spots, JSON round trip, byte-exact regeneration, errors."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from shapely.geometry import LinearRing
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.errors import SceneError
from np_sim.geodesic import geodesic_grid
from np_sim.site import (
    SITE_OBSERVATION,
    SITE_PATH,
    SPOT_KINDS,
    Site,
    generate_site,
    load_site,
    site_json,
)
from np_sim.vehicle import VehicleSpec


def test_site_boundary_has_about_fifty_edges_and_fits_the_site_observation():
    site = load_site()
    assert site.n_edges == 50
    assert site.n_edges <= SITE_OBSERVATION.max_boundary_segments
    assert SITE_OBSERVATION.max_boundary_segments == 10 * math.ceil(site.n_edges / 10)
    assert (SITE_OBSERVATION.use_lidar, SITE_OBSERVATION.max_obstacles, SITE_OBSERVATION.vertices_per_obstacle) == (
        False, 10, 5)
    polygon = ShapelyPolygon(site.boundary)
    assert polygon.is_valid and polygon.exterior.is_ccw
    width, height = np.ptp(site.boundary, axis=0)
    assert 55 <= width <= 65 and 45 <= height <= 60


def test_site_file_round_trips_and_regenerates_byte_for_byte():
    shipped = SITE_PATH.read_bytes()
    site = load_site()
    assert site_json(site).encode("utf-8") == shipped
    assert Site.from_dict(site.to_dict()).to_dict() == site.to_dict()
    assert site_json(generate_site(site.seed)).encode("utf-8") == shipped


def test_another_seed_moves_only_the_kerb_vertices():
    a, b = generate_site(0), generate_site(1)
    assert a.n_edges == b.n_edges == 50
    assert not np.array_equal(a.boundary, b.boundary)
    assert np.array_equal(a.boundary.min(axis=0), b.boundary.min(axis=0))


def test_spots_are_free_varied_and_on_the_geodesic_lattice():
    site = load_site()
    vehicle = VehicleSpec()
    ring = LinearRing(site.boundary)
    footprints = [ShapelyPolygon(vehicle.footprint(s.pose)) for s in site.spots]
    assert {s.kind for s in site.spots} == set(SPOT_KINDS)
    assert len({s.name for s in site.spots}) == len(site.spots) >= 40
    for spot, footprint in zip(site.spots, footprints):
        assert ShapelyPolygon(site.boundary).contains_properly(footprint)
        assert footprint.distance(ring) >= 0.55 - 1e-9, spot.name
    for i in range(len(footprints)):
        for j in range(i + 1, len(footprints)):
            assert footprints[i].distance(footprints[j]) >= 0.8 - 1e-9
    grid = geodesic_grid(site.scene(site.spots[0].pose))
    offsets = (site.spot_poses()[:, :2] - grid.origin) / grid.cell_m
    np.testing.assert_allclose(offsets, np.round(offsets), atol=1e-6)
    # with no objects every spot reaches every other on the grid
    assert all(np.isfinite(grid.distance_at(s.pose[:2])) for s in site.spots)


def test_site_errors_name_the_field():
    data = load_site().to_dict()
    bad = copy.deepcopy(data)
    bad["spots"][2]["kind"] = "diagonal"
    with pytest.raises(SceneError, match=r"spots\[2\]\.kind: expected one of reverse, forward"):
        Site.from_dict(bad, source="site.json")
    bad = copy.deepcopy(data)
    bad["colour"] = "grey"
    with pytest.raises(SceneError, match="colour: unknown field"):
        Site.from_dict(bad)
    bad = copy.deepcopy(data)
    bad["spots"][0]["pose"] = [0.0, 0.0, 0.0]  # outside the lot: footprint crosses the boundary
    with pytest.raises(SceneError, match=r"spots\[0\] \(N01\): target: the vehicle footprint"):
        Site.from_dict(bad)
