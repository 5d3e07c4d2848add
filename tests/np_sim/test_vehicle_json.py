"""np_sim.vehicle: the vehicle JSON file, its errors, the shipped presets and what follows a vehicle in the env."""

import argparse
import json
import math

import numpy as np
import pytest
from shapely.geometry import LineString, Polygon

from np_sim.cli import vehicle_spec
from np_sim.config import EnvConfig
from np_sim.errors import ConfigError
from np_sim.vehicle import PRESETS, VehicleSpec, load_vehicle

VAN = {"wheelbase_m": 2.975, "front_overhang_m": 0.9, "rear_overhang_m": 0.875, "width_m": 1.85, "kappa_max": 0.24}


def _write(tmp_path, data, name="vehicle.json"):
    path = tmp_path / name
    path.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return path


@pytest.mark.parametrize("data, message", [
    ({**VAN, "length_m": 2.5}, r"wheelbase_m: 2.975 m is not shorter than the body \(length_m 2.5 m\)"),
    ({k: v for k, v in VAN.items() if k != "front_overhang_m"} | {"length_m": 3.5},
     r"wheelbase_m: the wheelbase 2.975 m and rear_overhang_m 0.875 m leave no front_overhang_m in length_m 3.5 m"),
    ({**VAN, "length_m": 4.8}, r"length_m: 4.8 m, but rear overhang \+ wheelbase \+ front overhang = 4.75 m"),
    ({**VAN, "colour": "white"}, r"unknown key\(s\) \['colour'\]"),
    ({**VAN, "width_m": -1.85}, r"width_m: expected a finite positive number .*got -1.85"),
    ({**VAN, "kappa_max": 0}, r"kappa_max: expected a finite positive number .*got 0"),
    ({**VAN, "wheelbase_m": "2.975"}, r"wheelbase_m: expected a finite positive number .*got '2.975'"),
    ({**VAN, "width_m": True}, r"width_m: expected a finite positive number .*got True"),
    ({k: v for k, v in VAN.items() if k != "width_m"}, r"missing field\(s\) \['width_m'\]"),
    ({**VAN, "description": 3}, r"description: expected a string, got 3"),
    ([1, 2], r"expected a JSON object of vehicle fields, got list"),
    ("{not json", r"not a JSON vehicle file"),
])
def test_a_bad_vehicle_file_is_one_error_naming_the_file_and_the_field(tmp_path, data, message):
    path = _write(tmp_path, data)
    with pytest.raises(ConfigError, match=message) as error:
        VehicleSpec.from_json(path)
    assert str(error.value).startswith(f"{path}: ")


def test_length_may_stand_in_for_one_overhang():
    spec = VehicleSpec.from_dict({k: v for k, v in VAN.items() if k != "rear_overhang_m"} | {"length_m": 4.75})
    assert spec.rear_overhang_m == pytest.approx(4.75 - 2.975 - 0.9)
    assert spec.length_m == pytest.approx(4.75)


def test_a_spec_round_trips_through_its_file(tmp_path):
    spec = VehicleSpec(wheelbase_m=2.5, front_overhang_m=0.7, rear_overhang_m=0.6, width_m=1.7, kappa_max=0.3)
    path = _write(tmp_path, spec.to_dict())
    assert VehicleSpec.from_json(path) == spec
    assert json.loads(path.read_text())["length_m"] == pytest.approx(3.8)


def test_the_presets_are_the_default_car_and_the_van():
    assert set(PRESETS) >= {"sedan", "van"}
    assert load_vehicle("sedan") == VehicleSpec()
    van = load_vehicle("van")
    assert (van.length_m, van.width_m, van.wheelbase_m, van.kappa_max) == pytest.approx((4.75, 1.85, 2.975, 0.24))
    # an 11.5 m kerb-to-kerb turning circle: the outer front wheel on radius 5.75 m, the rear-axle centre on
    # sqrt(5.75² − L²) − track/2 with a 1.55 m track (docs/vehicles.md)
    assert 1 / van.kappa_max == pytest.approx(math.sqrt(5.75**2 - 2.975**2) - 1.55 / 2, abs=0.05)
    assert "'van'" in van.describe() and "kappa_max 0.24" in van.describe()


def test_load_vehicle_takes_a_file_path_and_refuses_other_names(tmp_path):
    assert load_vehicle(_write(tmp_path, VAN)) == load_vehicle("van")
    with pytest.raises(ConfigError, match=r"vehicle 'nonexistent': neither a preset \(sedan, van\) nor a vehicle"):
        load_vehicle("nonexistent")


def test_the_cli_type_turns_a_bad_vehicle_into_an_argparse_error(tmp_path):
    assert vehicle_spec("van") == load_vehicle("van")
    path = _write(tmp_path, {**VAN, "length_m": 2.0})
    with pytest.raises(argparse.ArgumentTypeError, match=rf"{path}: wheelbase_m: .*not shorter than the body"):
        vehicle_spec(str(path))


def test_the_env_for_a_vehicle_takes_its_footprint_ranges_and_curvature_bound():
    from np_sim.benchmarks import load_benchmark
    from np_sim.env import ParkingEnv
    from np_sim.kernels import step as K

    van = load_vehicle("van")
    config = EnvConfig().for_vehicle(van)
    assert config.vehicle == van and config.connector.kappa_max == van.kappa_max
    scene = load_benchmark("factorial", "train")[0]
    env = ParkingEnv([scene], config=config)
    # b_i: where each beam from the rear-axle centre leaves the van's rectangle, measured by shapely
    body = Polygon(van.footprint_local())
    phi = 2 * np.pi * np.arange(len(env.core.b_ranges)) / len(env.core.b_ranges)
    expected = [LineString([(0, 0), (10 * math.cos(a), 10 * math.sin(a))]).intersection(body).length for a in phi]
    np.testing.assert_allclose(env.core.b_ranges, expected, atol=1e-9)
    # the full-scale action is the van's κ_max: a 1 m forward arc at κ = 0.24 turns the heading by −0.24 rad (eq:arc)
    env.reset(seed=0)
    start = env.core.S[0, K.S_X:K.S_TH + 1].copy()
    env.step(np.array([1.0, 1.0 / config.episode.max_length_m]))
    turn = (env.core.S[0, K.S_TH] - start[2] + math.pi) % (2 * math.pi) - math.pi
    assert turn == pytest.approx(-0.24)
