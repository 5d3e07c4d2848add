"""Start sampler: inside the start region, footprint-free (shapely oracle), deterministic per seed."""

import numpy as np
from shapely.geometry import Point, Polygon

from np_sim.examples import example_scenes
from np_sim.starts import UniformStartSampler
from np_sim.vehicle import VehicleSpec


def test_starts_are_footprint_free_inside_the_region_and_seeded():
    scenes = [s for s in example_scenes() if s.start_region is not None]
    sampler = UniformStartSampler(scenes)
    vehicle = VehicleSpec()
    ks = np.arange(len(scenes)).repeat(3)
    np.testing.assert_array_equal(sampler(np.random.default_rng(4), ks), sampler(np.random.default_rng(4), ks))
    assert sampler(np.random.default_rng(4), ks).shape == (len(ks), 3)
    rng = np.random.default_rng(0)
    for k, scene in enumerate(scenes):
        region, boundary = Polygon(scene.start_region), Polygon(scene.boundary)
        obstacles = [Polygon(o.vertices) if hasattr(o, "vertices") else Point(o.center).buffer(o.radius, 64)
                     for o in scene.obstacles]
        headings = []
        for pose in sampler(rng, np.full(50, k)):
            rect = Polygon(vehicle.footprint(pose))
            assert region.contains(Point(pose[:2]))
            assert boundary.contains(rect)
            assert not any(o.intersects(rect) for o in obstacles)
            headings.append(pose[2])
        assert np.ptp(headings) > 4.0  # headings spread over the circle
