"""Best-of-N NeuralParker (np_policy.sampling): seeded rollouts that replay in the env's kinematics, and a choice
that equals the brute-force minimum of its cost and prefers steerable, clear, short plans."""

import math

import numpy as np
import pytest

from np_policy.config import NeuralParkerConfig as Config
from np_policy.planner import NeuralParkerPlanner
from np_policy.sampling import (ChoiceWeights, PolicyRollouts, choose, clearance_level, cost_lower_bound, drive_length,
                                plan_cost)
from np_sim.env_core import BatchCore
from np_sim.errors import ConfigError
from np_sim.clips import load_clips
from np_sim.frames import from_target_frame
from np_sim.kernels import step as K
from np_sim.kinematics import arc_step
from np_sim.plan import Plan
from np_sim.scene import PolygonObstacle, Scene
from np_sim.vehicle import VehicleSpec

CHECKPOINT = "checkpoints/site_np_footprint.pt"


@pytest.fixture(scope="module")
def problem():
    """eval-1000024 at frame 0: the mean rollout of the shipped footprint checkpoint fails there."""
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000024")
    start = np.asarray(clip.start, float)
    return clip.frame_scene(0, pose=start), start


@pytest.fixture(scope="module")
def sampled():
    return NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(samples=16, seed=3))


def test_sampling_finds_a_plan_where_the_mean_rollout_fails_and_is_deterministic(problem, sampled):
    scene, start = problem
    mean = NeuralParkerPlanner.from_checkpoint(CHECKPOINT).plan(scene, start)
    assert not mean.success
    first, second = sampled.plan(scene, start), sampled.plan(scene, start)
    assert first.success
    np.testing.assert_array_equal(first.arcs, second.arcs)
    np.testing.assert_array_equal(first.hermite.points, second.hermite.points)


def test_rescue_rounds_run_only_after_a_failure(problem, sampled):
    """Rescue round k samples with seed + 1 + k: seed 2's first round of 16 at scale 1 is ``sampled``'s own set
    (16, seed 3), so where the mean rollout fails the two planners return the same plan; where it succeeds the
    rescue planner returns the mean rollout."""
    scene, start = problem
    rescue = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(seed=2, rescue=((16, 1.0), (8, 3.0))))
    plan = rescue.plan(scene, start)
    assert plan.success
    np.testing.assert_array_equal(plan.arcs, sampled.plan(scene, start).arcs)
    assert [(r.n, r.seed) for r in rescue.rescue] == [(16, 3), (8, 4)]
    np.testing.assert_allclose(rescue.rescue[1].std, 3.0 * rescue.rescue[0].std)
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000009")  # the mean rollout parks here
    easy_scene, easy_start = clip.frame_scene(0, pose=clip.start), np.asarray(clip.start, float)
    mean = NeuralParkerPlanner.from_checkpoint(CHECKPOINT).plan(easy_scene, easy_start)
    assert mean.success
    np.testing.assert_array_equal(rescue.plan(easy_scene, easy_start).arcs, mean.arcs)
    with pytest.raises(ValueError, match=r"rescue rounds must be \(n >= 1, scale > 0\), got \(16, 0.0\)"):
        Config(rescue=((16, 0.0),))


def test_sampled_rollouts_replay_in_the_arc_kinematics(problem, sampled):
    """Each recorded arc is the one the env executed: replaying them from the start reaches the pose the Hermite
    segment starts from (or, without one, a pose within the env's terminal tolerance of the target)."""
    scene, start = problem
    plans = sampled.sampled(scene, start)
    assert len(plans) == 16 and any(p.success for p in plans) and not all(p.success for p in plans)
    for plan in plans:
        assert plan.success == (plan.reason == "")
        assert plan.reason in ("", "collision", "timeout")
        pose = np.asarray(start, float)
        for kappa, length in plan.arcs:
            pose = arc_step(pose, kappa, length)
        if plan.success and plan.hermite is not None:
            np.testing.assert_allclose(plan.hermite.points[0], pose[:2], atol=1e-6)
        elif plan.success:
            assert math.hypot(*(pose[:2] - scene.target[:2])) <= 0.1 + 1e-9


def test_choose_equals_the_brute_force_minimum(problem, sampled):
    scene, start = problem
    vehicle = sampled.env_config.vehicle
    plans = sampled.sampled(scene, start)
    weights = ChoiceWeights()
    costs = [(plan_cost(p, scene, vehicle, weights), i) for i, p in enumerate(plans) if p.success]
    assert choose(plans, scene, vehicle, weights) is plans[min(costs)[1]]
    for (_, cost), i in costs:  # the pruning bound never exceeds the cost
        assert cost_lower_bound(plans[i], weights) <= cost
    failed = [p for p in plans if not p.success]
    assert choose(failed, scene, vehicle, weights) is failed[0]
    with pytest.raises(ValueError, match="at least one plan"):
        choose([], scene, vehicle)


def _corridor() -> Scene:
    """A 40 × 12 m yard with one box whose lower face lies at y = 1.5 (target far to the right)."""
    boundary = np.array([[-5.0, -6.0], [35.0, -6.0], [35.0, 6.0], [-5.0, 6.0]])
    box = np.array([[8.0, 1.5], [12.0, 1.5], [12.0, 4.0], [8.0, 4.0]])
    return Scene(boundary=boundary, obstacles=(PolygonObstacle(box),), target=np.array([30.0, 0.0, 0.0]),
                 start_region=None, name="corridor")


def _straight(y: float, length: float) -> Plan:
    return Plan(start=np.array([0.0, y, 0.0]), arcs=np.array([[0.0, length]]), success=True)


def test_clearance_levels_and_the_cost_terms_by_hand():
    """Half width 0.971 m: a straight run at y = 0.3 keeps 1.5 − 0.3 − 0.971 = 0.229 m from the box (level 0.2);
    at y = 0.45 it keeps 0.079 m (level 0.0, cost +50 × 0.2 = 10 m)."""
    scene, vehicle = _corridor(), VehicleSpec()
    clear, close = _straight(0.3, 20.0), _straight(0.45, 20.0)
    assert clearance_level(scene, clear.sample(0.05)[:, :3], vehicle, (0.3, 0.2, 0.1, 0.0)) == 0.2
    assert clearance_level(scene, close.sample(0.05)[:, :3], vehicle, (0.3, 0.2, 0.1, 0.0)) == 0.0
    weights = ChoiceWeights(heading_penalty=0.0)
    assert plan_cost(clear, scene, vehicle, weights) == (False, pytest.approx(20.0))
    assert plan_cost(close, scene, vehicle, weights) == (False, pytest.approx(30.0))
    # a shorter path that passes close loses to a longer clear one, and wins once the gap is more than 10 m
    assert choose([_straight(0.45, 12.0), clear], scene, vehicle, weights) is clear
    shortcut = _straight(0.45, 9.0)
    assert choose([shortcut, clear], scene, vehicle, weights) is shortcut
    # drive time as a length at 2 m/s: 12 m forward, 2 m reverse at 1.5 m/s (2 × 2 / 1.5), one reversal (2 m)
    back = Plan(start=np.array([0.0, 0.3, 0.0]), arcs=np.array([[0.0, 12.0], [0.0, -2.0]]), success=True)
    assert plan_cost(back, scene, vehicle, weights)[1] == pytest.approx(12.0 + 2.0 * 2.0 / 1.5 + 2.0)
    assert cost_lower_bound(back, weights) == pytest.approx(12.0 + 2.0 * 2.0 / 1.5 + 2.0)
    # a curve of κ = 0.5: v = min(2, √(1 / 0.5)) = √2 m/s, so 6 m of it weigh 6 × 2 / √2
    curve = Plan(start=np.array([0.0, 0.0, 0.0]), arcs=np.array([[0.5, 6.0]]), success=True)
    assert drive_length(curve.sample(0.05), weights) == pytest.approx(6.0 * 2.0 / math.sqrt(2.0))


def test_a_plan_steering_beyond_kappa_max_loses_to_any_steerable_plan():
    scene, vehicle = _corridor(), VehicleSpec()
    sharp = Plan(start=np.array([0.0, 0.3, 0.0]), arcs=np.array([[1.2 * vehicle.kappa_max, 1.0]]), success=True)
    assert plan_cost(sharp, scene, vehicle, ChoiceWeights())[0]
    long_clear = _straight(0.3, 25.0)
    assert choose([sharp, long_clear], scene, vehicle) is long_clear


def test_bad_settings_are_named():
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig.samples: expected an integer >= 0, got -1"):
        Config(samples=-1)
    with pytest.raises(ValueError, match="margins_m"):
        ChoiceWeights(margins_m=(0.1, -0.2))
    with pytest.raises(ValueError, match="reverse_speed_mps: expected > 0"):
        ChoiceWeights(reverse_speed_mps=0.0)


def test_the_steering_check_is_the_trackers():
    """The choice's steerability check uses the tracker's own slack and reference spacing."""
    from tracking.config import ExecutorConfig

    weights, executor = ChoiceWeights(), ExecutorConfig()
    assert weights.curvature_tolerance == executor.curvature_tolerance
    assert weights.sample_ds_m == executor.reference_ds_m


def test_a_planning_margin_keeps_the_grown_footprint_clear_and_costs_see_the_real_body():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000009")
    scene, start = clip.frame_scene(0, pose=clip.start), np.asarray(clip.start, float)
    planner = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(samples=8, margin_m=0.1))
    body = NeuralParkerPlanner.from_checkpoint(CHECKPOINT).env_config.vehicle
    assert planner.body == body and planner.env_config.vehicle == body.inflated(0.1)
    plan = planner.plan(scene, start)
    assert plan.success
    from np_sim.collision import path_valid

    # the env checks its arcs at its own spacing; at 0.05 m the grown body may graze between those samples
    assert path_valid(scene, plan.sample(0.05)[:, :3], "footprint", body.inflated(0.09))
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig.margin_m: expected a finite number >= 0 m, got -0.1"):
        Config(margin_m=-0.1)


def test_sampled_action_planner_draws_its_first_arc_from_the_seeded_gaussian(problem):
    """action='sample': arc 1 is clip(μ(o₀) + σ·ε, −1, 1) × (κ_max, l_max) with ε the first normal draw of the
    query's seed (planner seed + start bits); the same query replays, another start or seed draws other noise."""
    from np_policy.planner import query_seed
    from np_sim.env import ParkingEnv

    scene, start = problem
    planner = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(seed=5, action="sample"))
    plan = planner.plan(scene, start)
    np.testing.assert_array_equal(plan.arcs, planner.plan(scene, start).arcs)
    obs, _ = ParkingEnv(scene, planner.env_config).reset(options={"start": start})
    eps = np.random.default_rng(query_seed(5, start)).standard_normal((1, 2))[0]
    std = planner.model.log_std.detach().exp().numpy()
    expected = np.clip(planner.actor(obs) + std * eps, -1.0, 1.0)
    scale = np.array([planner.env_config.vehicle.kappa_max, planner.env_config.episode.max_length_m])
    np.testing.assert_allclose(plan.arcs[0], expected * scale, rtol=1e-9)
    other = start + np.array([0.0, 0.0, 1e-9])
    assert not np.array_equal(query_seed(5, start).generate_state(4), query_seed(5, other).generate_state(4))
    assert not np.array_equal(query_seed(5, start).generate_state(4), query_seed(6, start).generate_state(4))
    with pytest.raises(ConfigError, match=r"action: expected one of \('mean', 'sample'\), got 'mode'"):
        Config(action="mode")
    with pytest.raises(ConfigError, match=r"action: 'sample' plays one sampled rollout; it does not combine"):
        Config(action="sample", samples=4)


def test_rescue_rounds_also_run_for_a_plan_short_of_the_wanted_clearance(problem):
    """rescue_clearance_m: a successful plan whose clearance level is below it gets the rescue rounds and the
    choice among it and their rollouts; at or above it the rounds do not run and the plan is returned as it is."""
    scene, start = problem
    base = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(samples=16, seed=3))
    plan = base.plan(scene, start)
    assert plan.success
    level = clearance_level(scene, plan.sample(0.05)[:, :3], base.body, base.config.weights.margins_m)
    for threshold, runs in ((level, 0), (level + 0.05, 1)):
        planner = NeuralParkerPlanner.from_checkpoint(
            CHECKPOINT, Config(samples=16, seed=3, rescue=((64, 2.0),), rescue_clearance_m=threshold))
        rounds, calls = planner.rescue[0], []
        planner.rescue = [lambda *args: calls.append(args) or rounds(*args)]
        chosen = planner.plan(scene, start)
        assert len(calls) == runs
        expected = choose([plan, *rounds(scene, start)], scene, base.body, base.config.weights) if runs else plan
        np.testing.assert_array_equal(chosen.arcs, expected.arcs)
    with pytest.raises(ConfigError, match=r"rescue_clearance_m: expected a finite number >= 0 m, got -0.1"):
        Config(rescue_clearance_m=-0.1)


def test_a_uniform_first_arc_round_escapes_a_start_the_policy_steers_into_a_wall():
    """eval-1000097's start is boxed in by the boundary and two objects: the policy's first arc (full left lock in
    reverse) and all its sampled ones up to 3 σ collide, while some first arcs drawn uniformly over the action box
    (the round's own seeded draws, scaled to κ_max and L_max) leave room for the policy to park."""
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000097")
    scene, start = clip.frame_scene(0, pose=clip.start), np.asarray(clip.start, float)
    policy_rounds = ((128, 2.0), (128, 3.0))
    boxed = NeuralParkerPlanner.from_checkpoint(CHECKPOINT, Config(samples=32, rescue=policy_rounds)).plan(scene,
                                                                                                           start)
    assert not boxed.success and boxed.reason == "collision"
    planner = NeuralParkerPlanner.from_checkpoint(CHECKPOINT,
                                                  Config(samples=32, rescue=(*policy_rounds, (128, 1.0, "uniform"))))
    escape = planner.rescue[2]
    assert (escape.n, escape.first_arc, escape.seed) == (128, "uniform", 3)
    np.testing.assert_allclose(escape.std, planner.sampled.std)
    plans = escape(scene, start)
    env = planner.env_config
    draws = np.random.default_rng(escape.seed).uniform(-1.0, 1.0, (128, 2))
    np.testing.assert_allclose([p.arcs[0] for p in plans], draws * [env.vehicle.kappa_max, env.episode.max_length_m])
    plan = planner.plan(scene, start)
    assert plan.success and any(np.array_equal(plan.arcs, p.arcs) for p in plans if p.success)
    assert [r.first_arc for r in planner.rescue] == ["policy", "policy", "uniform"]
    with pytest.raises(ValueError, match=r"first arc must be one of \('policy', 'uniform'\), got \(8, 1.0, 'grid'\)"):
        Config(rescue=((8, 1.0, "grid"),))
    with pytest.raises(ValueError, match=r"a rescue round is \(n, scale\[, first_arc\]\), got \(8,\)"):
        Config(rescue=((8,),))
    with pytest.raises(ValueError, match=r"first_arc must be one of \('policy', 'uniform'\), got 'grid'"):
        PolicyRollouts(planner.actor, escape.std, env, 8, first_arc="grid")


def _env_rollout(planner, scene, start) -> np.ndarray:
    """The mean rollout written as a plain Gymnasium loop: one ``ParkingEnv`` step per compiled mean action."""
    from np_sim.env import ParkingEnv

    env = ParkingEnv(scene, planner.env_config)
    obs, _ = env.reset(options={"start": np.asarray(start, float)})
    scale = np.array([planner.env_config.vehicle.kappa_max, planner.env_config.episode.max_length_m])
    arcs, done = [], False
    while not done:
        action = planner.actor(obs)
        obs, _, terminated, truncated, _ = env.step(action)
        arcs.append(np.asarray(action, np.float64) * scale)
        done = terminated or truncated
    return np.array(arcs)


def test_the_mean_rollout_is_the_batch_of_one_and_matches_a_plain_env_loop(problem, sampled):
    """The paper's planner (zero noise, one row of the batched rollout, played as one compiled loop) plays exactly
    the arcs a step-by-step ``ParkingEnv`` loop of the same compiled policy plays, bit for bit; a zero-noise batch of
    several rows (the per-arc batched loop) repeats it in every row, Hermite segment included, and draws no
    noise."""
    scene, start = problem
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000009")
    cases = [(scene, start), (clip.frame_scene(0, pose=clip.start), np.asarray(clip.start, float))]
    for case_scene, case_start in cases:
        assert sampled.actor.plays_rollout(sampled.mean.core(case_scene))
        plan = sampled._mean_rollout(case_scene, case_start)
        np.testing.assert_array_equal(plan.arcs, _env_rollout(sampled, case_scene, case_start))
        batch = PolicyRollouts(sampled.actor, np.zeros(2), sampled.env_config, 3, seed=11)(case_scene, case_start)
        for row in batch:
            np.testing.assert_array_equal(row.arcs, plan.arcs)
            assert (row.success, row.reason) == (plan.success, plan.reason)
            assert (row.hermite is None) == (plan.hermite is None)
            if plan.hermite is not None:
                np.testing.assert_array_equal(row.hermite.points, plan.hermite.points)
    assert {p.success for p in (sampled._mean_rollout(s, q) for s, q in cases)} == {True, False}


def _rollouts_stepping_every_row(rollouts: PolicyRollouts, scene, start) -> list[tuple]:
    """(arcs, success, reason, Hermite points) per rollout by the loop that steps every env of a fresh batched
    core each step, finished ones with a zero action, drawing the same noise (the live rows' in row order)."""
    core = BatchCore([scene], rollouts.n, rollouts.config, None, nearest=rollouts.nearest)
    rng = np.random.default_rng(rollouts.seed)
    core.reset_envs(np.arange(rollouts.n), rng, 0, start)
    scale = np.array([rollouts.config.vehicle.kappa_max, rollouts.config.episode.max_length_m])
    arcs, ends, alive, first = [[] for _ in range(rollouts.n)], [None] * rollouts.n, np.ones(rollouts.n, bool), True
    while alive.any():
        live = np.flatnonzero(alive)
        actions = np.zeros((rollouts.n, 2))
        actions[live] = rollouts._actions(core.obs[live], rng, first)
        first = False
        core.step(actions)
        for row in live:
            arcs[row].append(actions[row] * scale)
            if core.R[row, K.R_TERMINATED] > 0 or core.R[row, K.R_TRUNCATED] > 0:
                h = int(core.R[row, K.R_HERMITE])
                ends[row] = (bool(core.R[row, K.R_SUCCESS]), None if h < 0 else core.h_pts[row, h].copy())
                alive[row] = False
    return [(np.array(a), *end) for a, end in zip(arcs, ends)]


def test_rollouts_step_only_the_live_rows_and_equal_stepping_every_row(problem, sampled, monkeypatch):
    """A finished rollout is not stepped again (the envs stepped add up to the arcs played), and the plans are
    those of stepping every env every step, bit for bit: arcs, outcomes and Hermite samples."""
    scene, start = problem
    rollouts = sampled.sampled
    stepped = []
    step = BatchCore.step

    def counting_step(core, actions, rows=None):
        stepped.append(core.num_envs if rows is None else len(rows))
        return step(core, actions, rows)

    monkeypatch.setattr(BatchCore, "step", counting_step)
    plans = rollouts(scene, start)
    monkeypatch.undo()
    lengths = [len(p.arcs) for p in plans]
    assert len(set(lengths)) > 1 and sum(stepped) == sum(lengths) < len(stepped) * rollouts.n
    reference = _rollouts_stepping_every_row(rollouts, scene, start)
    for plan, (arcs, success, hermite) in zip(plans, reference):
        np.testing.assert_array_equal(plan.arcs, arcs)
        assert plan.success == success
        if hermite is None:
            assert plan.hermite is None
        else:
            np.testing.assert_array_equal(plan.hermite.points, from_target_frame(hermite.T, scene.target))


def test_a_non_finite_mean_action_is_refused_as_the_env_refuses_it(problem, sampled):
    """The compiled mean-rollout loop checks each action as the env's step does: a policy whose output is NaN
    raises the env's error instead of stepping."""
    import copy

    scene, start = problem
    actor = copy.copy(sampled.actor)
    actor.vecs = type(sampled.actor.vecs)([v.copy() for v in sampled.actor.vecs])
    actor.vecs[len(actor.vecs) - 1][:] = np.nan  # the actor's output bias
    rollouts = PolicyRollouts(actor, np.zeros(2), sampled.env_config)
    with pytest.raises(ValueError, match=r"action\[0\] = \[nan, nan\] lies outside the action space"):
        rollouts(scene, start)
