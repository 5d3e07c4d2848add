"""The guarded mean rollout (`np_policy.guarded`): its rule replayed arc by arc in single envs, its place in the
anytime footprint planner, shapely's clearance of the plans it answers with, and its settings' errors."""

import dataclasses

import numpy as np
import pytest

from clearance_oracle import shapely_clearance  # tests/clearance_oracle.py
from clip_frames import first_frame  # tests/clip_frames.py
from np_policy.config import FOOTPRINT_ANYTIME, NeuralParkerConfig
from np_policy.guarded import GUARD_DIRECTIONS, guard_choice, guard_offsets
from np_policy.planner import NeuralParkerPlanner, Policy
from np_policy.sampling import hermite_of
from np_sim.env_core import BatchCore
from np_sim.errors import ConfigError
from np_sim.kernels import step as K
from np_sim.plan import hermite_coefficients
from np_sim.validate import validation_failure

CHECKPOINT = "checkpoints/site_np_footprint.pt"
GUARDED_SEEDS = (10, 23, 73)
"""Training-stream clips (never held-out ones) whose first frame the grown-body mean rollout of the shipped
footprint checkpoint does not answer (clip 10: it collides at arc 8; 23: it runs out of arcs; 73: it collides on
its first arc) and the guarded rollout does (found by playing clips 0–79)."""


GUARDED = dataclasses.replace(FOOTPRINT_ANYTIME, guard_sigmas=(1.0, 2.0, 3.0))
"""The anytime preset with the guarded rollout at 1, 2 and 3 σ (measured on training clips, not adopted:
docs/best_of_n.md, 2026-12-06)."""


@pytest.fixture(scope="module")
def planner():
    return NeuralParkerPlanner(Policy.load(CHECKPOINT), GUARDED)


def test_the_offsets_are_the_mean_then_the_star_at_each_multiple_in_order():
    offsets = guard_offsets([1.0, 2.5])
    assert offsets.shape == (17, 2)
    np.testing.assert_array_equal(offsets[0], [0.0, 0.0])
    np.testing.assert_array_equal(offsets[1:5], [[1, 0], [-1, 0], [0, 1], [0, -1]])
    np.testing.assert_array_equal(offsets[5:9], [[1, 1], [1, -1], [-1, 1], [-1, -1]])
    np.testing.assert_array_equal(offsets[9:], 2.5 * np.array(GUARD_DIRECTIONS))


def _results(rows):
    """Result rows with (success, collision) flags per row."""
    R = np.zeros((len(rows), K.R_SIZE))
    for i, (success, collision) in enumerate(rows):
        R[i, K.R_SUCCESS], R[i, K.R_COLLISION] = success, collision
        R[i, K.R_TERMINATED] = success or collision
    return R


def test_the_choice_takes_an_aligned_park_else_a_free_row_else_any_park():
    no = np.zeros(4, bool)
    assert guard_choice(_results([(0, 0), (0, 1), (1, 0), (1, 0)]), np.array([0, 0, 0, 1], bool)) == 3
    assert guard_choice(_results([(0, 1), (0, 0), (1, 0), (1, 0)]), no) == 1  # a park at the edge is passed over
    assert guard_choice(_results([(0, 1), (1, 0), (0, 1), (1, 0)]), no) == 1  # … unless nothing else is free
    assert guard_choice(_results([(0, 0), (0, 0)]), no[:2]) == 0
    assert guard_choice(_results([(0, 1), (0, 1)]), no[:2]) is None


def _single_step(scene, config, state, action):
    """One arc from ``state`` (a state row of ``BatchCore.S``) in a fresh one-env core: 'collision', 'free',
    'aligned' (parks within 5° of the target's heading: the Hermite cubic's end tangent) or 'edge' (parks beyond)."""
    core = BatchCore([scene], 1, config, None, nearest=True)
    core.reset_envs([0], np.random.default_rng(0), 0, state[K.S_X: K.S_TH + 1])
    core.S[0] = state  # counters too; the observation is refreshed by the step itself
    core.step(np.asarray(action, float)[None])
    if core.R[0, K.R_SUCCESS] == 0:
        return "collision" if core.R[0, K.R_COLLISION] > 0 else "free"
    hermite = hermite_of(core, 0, scene)
    c = hermite_coefficients(hermite.points)
    tangent = c[1] + 2.0 * c[2] + 3.0 * c[3]  # dr/dt of the cubic at its end, t = 1
    heading = np.arctan2(tangent[1], tangent[0]) + (0.0 if hermite.forward else np.pi)
    return "aligned" if abs(np.remainder(heading - scene.target[2] + np.pi, 2 * np.pi) - np.pi) <= np.radians(5.0) \
        else "edge"


@pytest.mark.parametrize("seed", GUARDED_SEEDS)
def test_every_arc_of_the_guarded_rollout_follows_its_rule_replayed_in_single_envs(planner, seed):
    """Each taken arc, replayed with every row of the star stepped alone: it is the first aligned park, else the
    first free row, else the first park; the mean is the compiled actor's at the replayed state. Independent of the
    batched branching and of ``BatchCore.copy_env``."""
    scene, start = first_frame(seed)
    guarded = planner.guarded
    config = guarded.config
    plan = guarded(scene, start)
    assert plan.success
    scale = np.array([config.vehicle.kappa_max, config.episode.max_length_m])
    core = BatchCore([scene], 1, config, None, nearest=True)
    core.reset_envs([0], np.random.default_rng(0), 0, start)
    offsets = guard_offsets(planner.config.guard_sigmas) * guarded.std
    for arc in plan.arcs:
        mean = np.asarray(planner.actor.batch(core.obs[:1].copy()), np.float64)[0]
        candidates = np.clip(mean + offsets, -1.0, 1.0)
        outcomes = [_single_step(scene, config, core.S[0].copy(), a) for a in candidates]
        expected = next(outcomes.index(kind) for kind in ("aligned", "free", "edge") if kind in outcomes)
        np.testing.assert_allclose(candidates[expected] * scale, arc, rtol=0, atol=1e-4)
        core.step(candidates[expected][None])
    assert core.R[0, K.R_SUCCESS] > 0  # the replay parks where the plan does


@pytest.mark.parametrize("seed", GUARDED_SEEDS)
def test_the_planner_answers_with_the_guarded_rollout_where_the_grown_mean_rollout_fails(planner, seed):
    scene, start = first_frame(seed)
    assert not planner.grown_answer(scene, start)[1]
    plan = planner.plan(scene, start)
    assert plan.stage == "guarded" and plan.success
    np.testing.assert_array_equal(plan.arcs, planner.guarded(scene, start).arcs)
    assert shapely_clearance(scene, plan.sample(0.05), planner.body) >= FOOTPRINT_ANYTIME.accept_mean_m - 1e-9
    assert validation_failure(scene, plan, "footprint", planner.body) == ""


def test_without_guard_sigmas_the_planner_is_the_anytime_planner_before(planner):
    """A frame the guarded rollout answers goes to the sampled rounds without it (the preset's default)."""
    plain = NeuralParkerPlanner(planner.policy, FOOTPRINT_ANYTIME)
    assert plain.guarded is None
    scene, start = first_frame(GUARDED_SEEDS[0])
    assert plain.plan(scene, start).stage in ("sampled", "rescue")


def test_bad_guard_settings_are_one_error_naming_the_field():
    with pytest.raises(ConfigError, match=r"guard_sigmas: expected a list of finite numbers > 0"):
        dataclasses.replace(FOOTPRINT_ANYTIME, guard_sigmas=(1.0, -2.0))
    with pytest.raises(ConfigError, match=r"guard_sigmas: expected a list of finite numbers > 0"):
        dataclasses.replace(FOOTPRINT_ANYTIME, guard_sigmas=(float("nan"),))
    with pytest.raises(ConfigError, match=r"guard_sigmas: .* needs accept_mean_m"):
        NeuralParkerConfig(guard_sigmas=(1.0,))
    loaded = NeuralParkerConfig.from_dict({**FOOTPRINT_ANYTIME.to_dict(), "guard_sigmas": [1, 2]})
    assert loaded.guard_sigmas == (1.0, 2.0)
