"""--vehicle on the CLIs: a bad vehicle is one error line, the planners, validators and checkpoints follow it."""

import json
import re

import pytest
from cli_helpers import one_error_line
from shapely.geometry import Polygon

from experiments import closed_loop, evaluate, planners, track
from experiments.registry import PlannerOptions, build_planners
from np_policy import train
from np_policy.checkpoint import CheckpointError
from np_policy.planner import Policy
from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.errors import ConfigError
from np_sim.vehicle import VehicleSpec, load_vehicle

SEDAN_CHECKPOINT = "checkpoints/factorial_np_seed0.pt"
CLIS = [(planners.main, []), (track.main, []), (closed_loop.main, ["--clips"]),
        (evaluate.main, ["--checkpoints", SEDAN_CHECKPOINT]), (train.main, [])]


@pytest.mark.parametrize("main, argv", CLIS)
def test_an_unknown_vehicle_is_one_error_line_with_exit_status_2(capsys, main, argv):
    line = one_error_line(capsys, main, [*argv, "--vehicle", "nonexistent"])
    assert "argument --vehicle: vehicle 'nonexistent': neither a preset (sedan, van) nor a vehicle JSON file" in line


@pytest.mark.parametrize("main, argv", CLIS)
def test_a_vehicle_file_with_the_wheelbase_longer_than_the_body_is_one_error_line(capsys, tmp_path, main, argv):
    path = tmp_path / "long.json"
    path.write_text(json.dumps({"wheelbase_m": 5.0, "front_overhang_m": 0.9, "rear_overhang_m": 0.9, "width_m": 1.8,
                                "kappa_max": 0.2, "length_m": 4.5}))
    line = one_error_line(capsys, main, [*argv, "--vehicle", str(path)])
    assert f"{path}: wheelbase_m: 5 m is not shorter than the body (length_m 4.5 m)" in line


def test_a_sedan_checkpoint_is_refused_for_the_van_naming_both():
    van = load_vehicle("van")
    with pytest.raises(CheckpointError) as error:
        build_planners(["np_guided_astar"], PlannerOptions(checkpoint=SEDAN_CHECKPOINT, vehicle=van))
    message = str(error.value)
    assert message.startswith(f"{SEDAN_CHECKPOINT}: trained for the vehicle 'sedan' (length 4.689 m, width 1.942 m")
    assert "refused for the vehicle 'van' (length 4.75 m, width 1.85 m, wheelbase 2.975 m" in message
    assert Policy.load(SEDAN_CHECKPOINT, vehicle=VehicleSpec()).train.env.vehicle == VehicleSpec()


def test_the_searches_plan_for_the_vehicle_of_the_options():
    van = load_vehicle("van")
    built = build_planners(["hybrid_astar", "ompl_rrtstar"], PlannerOptions(vehicle=van, search_margin_m=0.1))
    assert built["hybrid_astar"].config.vehicle == van.inflated(0.1)
    assert built["ompl_rrtstar"].config.vehicle == van


def test_closed_loop_plans_for_the_vehicle_it_drives(capsys):
    van = load_vehicle("van")
    config = closed_loop.for_vehicle(closed_loop.ClosedLoopConfig(), van)
    assert config.planner.vehicle == van and config.clip_run.tracker.vehicle == van
    with pytest.raises(ConfigError, match=r"planner.vehicle 'van' .* is not clip_run.tracker.vehicle 'sedan'"):
        from experiments.overrides import apply_overrides

        apply_overrides(closed_loop.ClosedLoopConfig(), ["planner.vehicle=van"])
    line = one_error_line(capsys, closed_loop.main, ["--clips", "--vehicle", "van", "--planners", "neuralparker"])
    assert re.search(r"site_np.pt: trained for the vehicle 'sedan' .* refused for the vehicle 'van'", line)


def test_planners_run_for_the_van_records_the_vehicle_and_whether_each_start_is_free(tmp_path):
    van = load_vehicle("van")
    result = planners.run("factorial", ["hybrid_astar"], None, out=tmp_path / "run", limit=1, progress=False,
                          vehicle=van)
    scene, start = load_benchmark("factorial", "test")[0], frozen_starts("factorial")[0, 0]
    record = result["records"][0]
    obstacles = [Polygon(o.polygon) for o in scene.obstacles if hasattr(o, "polygon")]
    free = Polygon(scene.boundary).contains(Polygon(van.footprint(start))) and not any(
        Polygon(van.footprint(start)).intersects(o) for o in obstacles)
    assert record["start_footprint_free"] == int(free)
    assert json.loads((tmp_path / "run" / "config.json").read_text())["vehicle"]["kappa_max"] == 0.24


def test_train_for_the_van_stores_it_and_its_curvature_bound(tmp_path):
    van = load_vehicle("van")
    data = train.with_vehicle({"env": {"connector": {"mode": "fixed"}}}, van)
    config = train.TrainConfig.from_dict(data)
    assert config.env.vehicle == van and config.env.connector.kappa_max == 0.24 and config.env.connector.mode == "fixed"
    explicit = train.with_vehicle({"env": {"connector": {"kappa_max": 0.2}}}, van)
    assert train.TrainConfig.from_dict(explicit).env.connector.kappa_max == 0.2
    with pytest.raises(ConfigError, match="--vehicle and the --config file's env.vehicle both name a vehicle"):
        train.with_vehicle({"env": {"vehicle": {"width_m": 2.0}}}, van)


def test_an_adapted_hope_checkpoint_for_the_sedan_is_refused_for_the_van(tmp_path):
    from hope_policy.ppo import HopePPOConfig
    from hope_policy.train import HopeTrainConfig
    from hope_policy.train import train as train_hope

    config = HopeTrainConfig(num_envs=2, episodes=1, ppo=HopePPOConfig(batch_size=16, minibatch_size=8, epochs=1))
    train_hope(config, tmp_path, progress=False)
    with pytest.raises(CheckpointError, match=r"final.pt: trained for the vehicle 'sedan' .* refused for the "
                                              r"vehicle 'van'"):
        build_planners(["hope"], PlannerOptions(hope_checkpoint=tmp_path / "final.pt", vehicle=load_vehicle("van")))
    assert build_planners(["hope"], PlannerOptions(hope_checkpoint=tmp_path / "final.pt"))["hope"].name == "hope"
