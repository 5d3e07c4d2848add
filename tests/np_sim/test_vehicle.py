"""VehicleSpec: the HOPE rectangle and the derived steering limit."""

import math

import numpy as np
import pytest

from np_sim.errors import ConfigError
from np_sim.vehicle import VehicleSpec


def test_hope_rectangle_and_steering_limit():
    v = VehicleSpec()
    assert v.length_m == pytest.approx(4.689)
    assert v.width_m == pytest.approx(1.942)
    assert math.degrees(v.max_steer_rad) == pytest.approx(math.degrees(math.atan(0.68 * 2.8)))
    assert 62.0 < math.degrees(v.max_steer_rad) < 62.5


def test_footprint_corners_rotate_about_the_rear_axle():
    v = VehicleSpec()
    corners = v.footprint([1.0, 2.0, math.pi / 2])
    # heading +y: front edge at y = 2 + 3.76, rear edge at y = 2 − 0.929, sides at x = 1 ± 0.971
    np.testing.assert_allclose(sorted(set(np.round(corners[:, 1], 9))), [2 - 0.929, 2 + 3.76])
    np.testing.assert_allclose(sorted(set(np.round(corners[:, 0], 9))), [1 - 0.971, 1 + 0.971])


def test_bad_spec_is_an_error():
    with pytest.raises(ConfigError, match=r"VehicleSpec.width_m: expected a finite positive number, got -1"):
        VehicleSpec(width_m=-1)


def test_inflated_footprint_contains_the_vehicle_with_the_margin_on_every_side():
    from shapely.geometry import Polygon

    v = VehicleSpec()
    pose = (3.0, -2.0, 0.7)
    grown = Polygon(v.inflated(0.15).footprint(pose))
    body = Polygon(v.footprint(pose))
    assert grown.contains(body.buffer(0.149, join_style="mitre"))
    assert not grown.contains(body.buffer(0.151, join_style="mitre"))
    assert v.inflated(0.15).wheelbase_m == v.wheelbase_m and v.inflated(0.15).kappa_max == v.kappa_max
    with pytest.raises(ConfigError, match="margin must be"):
        v.inflated(-0.1)
