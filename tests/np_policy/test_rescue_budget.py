"""Bounds on the footprint planner's worst calls: the rollouts' arc budget (``rollout_max_arcs``) and the rescue
rounds' stop rule (``rescue_stop_m``), each against an expectation built without it, on training clips only."""

import dataclasses

import numpy as np
import pytest

from clip_frames import first_frame  # tests/clip_frames.py
from np_policy.config import FOOTPRINT_ANYTIME, NeuralParkerConfig
from np_policy.inference import CompiledActor
from np_policy.planner import NeuralParkerPlanner, Policy, planning_env, rollout_env
from np_policy.sampling import PolicyRollouts, clearance_level
from np_sim.errors import ConfigError

CHECKPOINT = "checkpoints/site_np_footprint.pt"


@pytest.fixture(scope="module")
def policy():
    return Policy.load(CHECKPOINT)


def test_an_arc_budget_cuts_only_the_rollouts_that_run_past_it(policy):
    """Under a budget of K arcs every rollout that ends within K arcs is the rollout of the full budget, arc for
    arc; every longer one ends after its first K arcs as a timeout. Training clip 60 at 2 σ, seed 7: rollouts of 1
    to 8 arcs, successes on both sides of K = 4."""
    scene, start = first_frame(60)
    env = planning_env(policy, FOOTPRINT_ANYTIME)
    actor, std = CompiledActor(policy.model.eval()), 2.0 * policy.model.log_std.detach().exp().numpy()
    full = PolicyRollouts(actor, std, env, 16, 7)(scene, start)
    cut = PolicyRollouts(actor, std, rollout_env(env, 4), 16, 7)(scene, start)
    assert {len(p.arcs) <= 4 for p in full if p.success} == {True, False}
    for whole, capped in zip(full, cut, strict=True):
        if len(whole.arcs) <= 4:
            assert (capped.success, capped.reason) == (whole.success, whole.reason)
            np.testing.assert_array_equal(capped.arcs, whole.arcs)
        else:
            assert (capped.success, capped.reason, len(capped.arcs)) == (False, "timeout", 4)
            np.testing.assert_array_equal(capped.arcs, whole.arcs[:4])


def test_the_arc_budget_reaches_the_sampled_and_rescue_rollouts_only(policy):
    planner = NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rollout_max_arcs=50))
    assert planner.mean.config.episode.max_arcs == policy.train.env.episode.max_arcs == 200
    assert {r.config.episode.max_arcs for r in [planner.sampled, *planner.rescue]} == {50}
    env = planning_env(policy, FOOTPRINT_ANYTIME)
    assert rollout_env(env, None) is env
    with pytest.raises(ConfigError, match=r"rollout_max_arcs: expected at most the policy env's arc budget "
                                          r"\(episode.max_arcs = 200\), got 201"):
        NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rollout_max_arcs=201))
    with pytest.raises(ConfigError, match=r"rollout_max_arcs: expected an integer >= 1 or None, got 0"):
        NeuralParkerConfig(rollout_max_arcs=0)


def test_mean_capped_gives_the_plain_mean_rollout_the_arc_budget_too(policy):
    """With ``mean_capped`` the plain mean rollout ends as a timeout at ``rollout_max_arcs`` like the other rounds:
    training clip 60's mean rollout takes more than 2 arcs, so under a budget of 2 it is its first 2 arcs, a
    timeout; the preset without the flag keeps the env's 200. The flag needs anytime play and a budget."""
    scene, start = first_frame(60)
    free = NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rollout_max_arcs=2))
    capped = NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rollout_max_arcs=2, mean_capped=True))
    assert (free.mean.config.episode.max_arcs, capped.mean.config.episode.max_arcs) == (200, 2)
    whole, cut = free._mean_rollout(scene, start), capped._mean_rollout(scene, start)
    assert len(whole.arcs) > 2
    assert (cut.success, cut.reason) == (False, "timeout")
    np.testing.assert_array_equal(cut.arcs, whole.arcs[:2])
    with pytest.raises(ConfigError, match=r"mean_capped: capping the plain mean rollout needs anytime play "
                                          r"\(accept_mean_m, got None\)"):
        NeuralParkerConfig(rollout_max_arcs=50, mean_capped=True)
    with pytest.raises(ConfigError, match=r"an arc budget \(rollout_max_arcs, got None\)"):
        dataclasses.replace(FOOTPRINT_ANYTIME, rollout_max_arcs=None, mean_capped=True)
    with pytest.raises(ConfigError, match=r"mean_capped: expected true or false, got 1"):
        dataclasses.replace(FOOTPRINT_ANYTIME, mean_capped=1)


def _rounds_run(policy, config: NeuralParkerConfig, scene, start):
    """The plan of a planner of ``config`` and the indices of the rescue rounds it ran."""
    planner, ran = NeuralParkerPlanner(policy, config), []

    def logged(k, rounds):
        return lambda *args: ran.append(k) or rounds(*args)

    planner.rescue = [logged(k, rounds) for k, rounds in enumerate(planner.rescue)]
    return planner.plan(scene, start), ran


def _rounds(n: int) -> NeuralParkerConfig:
    """The preset with its first ``n`` rescue rounds only (the rounds cut by hand)."""
    return dataclasses.replace(FOOTPRINT_ANYTIME, rescue=FOOTPRINT_ANYTIME.rescue[:n])


def test_the_rescue_rounds_stop_after_the_first_round_whose_plan_keeps_the_stop_clearance(policy):
    """With ``rescue_stop_m`` the first rescue round runs on ``rescue_clearance_m``'s rule and a later one only
    while the plan fails or keeps less than ``rescue_stop_m``; expected answers from the preset with its rounds cut
    by hand. Training clip 60's first frame: the sampled round keeps no 0.2 m, the first rescue round finds a plan
    at 0.1 m and the preset runs all three rounds, to 0.2 m; with the stop at 0 or 0.1 m one round runs and the
    answer is the one-round preset's. Training clip 37's: the first two rescue rounds find no plan, so with the stop
    at 0 all three run and the answer is the preset's."""
    scene, start = first_frame(60)
    full, ran = _rounds_run(policy, FOOTPRINT_ANYTIME, scene, start)
    expected = NeuralParkerPlanner(policy, _rounds(1)).plan(scene, start)
    body = policy.train.env.vehicle
    levels = [clearance_level(scene, p.sample(0.05)[:, :3], body, (0.2, 0.1, 0.0)) for p in (expected, full)]
    assert ran == [0, 1, 2] and expected.success and levels == [0.1, 0.2]
    for stop in (0.0, 0.1):
        plan, ran = _rounds_run(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rescue_stop_m=stop), scene, start)
        assert ran == [0] and plan.stage == "rescue"
        np.testing.assert_array_equal(plan.arcs, expected.arcs)
    scene, start = first_frame(37)
    assert not NeuralParkerPlanner(policy, _rounds(2)).plan(scene, start).success
    plan, ran = _rounds_run(policy, dataclasses.replace(FOOTPRINT_ANYTIME, rescue_stop_m=0.0), scene, start)
    reference = NeuralParkerPlanner(policy, FOOTPRINT_ANYTIME).plan(scene, start)
    assert ran == [0, 1, 2] and plan.success
    np.testing.assert_array_equal(plan.arcs, reference.arcs)


def test_a_stop_clearance_above_the_rescue_clearance_is_named():
    with pytest.raises(ConfigError, match=r"rescue_stop_m: expected at most rescue_clearance_m \(0.2 m\), got 0.3"):
        dataclasses.replace(FOOTPRINT_ANYTIME, rescue_stop_m=0.3)
    with pytest.raises(ConfigError, match=r"rescue_stop_m: expected a finite number >= 0 m, got -0.1"):
        dataclasses.replace(FOOTPRINT_ANYTIME, rescue_stop_m=-0.1)
    assert NeuralParkerConfig.from_dict(dataclasses.replace(FOOTPRINT_ANYTIME, rescue_stop_m=0.0).to_dict()
                                        ).rescue_stop_m == 0.0
