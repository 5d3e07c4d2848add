"""``BatchCore.step`` on a subset of its envs (``rows``): each stepped row equals the full step of the same action on
that row (state, observation, results, Hermite scratch), and every other row keeps its bits.

The oracle is a second core stepped in full from the same state; the scenes include an over-capacity lot (obstacle
slots re-selected per row, `np_sim.nearest`), LiDAR is on and the convention is the footprint's."""

from __future__ import annotations

import numpy as np
import pytest

from np_sim.config import EnvConfig
from np_sim.env_core import BatchCore
from np_sim.examples import example_scenes
from np_sim.kernels import step as K
from np_sim.lots import LotConfig, generate_lot

CONFIG = EnvConfig(collision="footprint")
STATE = ("S", "R", "obs", "h_pts", "h_kbar_max", "h_dk", "h_len", "h_cost")
"""Every per-env array a step writes."""


def _twin_cores(n: int) -> tuple[BatchCore, BatchCore]:
    """Two cores in the same state: every scene in turn, the same sampled starts, zeroed Hermite scratch."""
    scenes = [*example_scenes(), generate_lot(LotConfig(bays_per_row=24), seed=3)]
    cores = []
    for _ in range(2):
        core = BatchCore(scenes, n, CONFIG, None, nearest=True)
        core.reset_envs(np.arange(n), np.random.default_rng(4), np.arange(n) % len(scenes))
        for name in STATE[3:]:
            getattr(core, name)[:] = 0.0
        cores.append(core)
    assert core.selectors  # the lot is observed by the nearest rule
    return cores[0], cores[1]


def test_a_subset_step_equals_the_full_step_on_its_rows_and_leaves_the_others():
    n = 24
    full, part = _twin_cores(n)
    rng = np.random.default_rng(5)
    outcomes = set()
    for _ in range(15):
        actions = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-0.4, 0.4, n)])
        rows = rng.permutation(n)[: int(rng.integers(1, n))]  # any size, any order
        others = np.setdiff1d(np.arange(n), rows)
        before = {name: getattr(part, name).copy() for name in STATE}
        full.step(actions)
        part.step(actions[rows], rows)
        for name in STATE:
            np.testing.assert_array_equal(getattr(part, name)[rows], getattr(full, name)[rows], err_msg=name)
            np.testing.assert_array_equal(getattr(part, name)[others], before[name][others], err_msg=name)
            getattr(part, name)[:] = getattr(full, name)  # the next round starts from the same state again
        outcomes |= {("collision", bool(c)) for c in full.R[rows, K.R_COLLISION]}
        outcomes |= {("hermite", bool(h >= 0)) for h in full.R[rows, K.R_HERMITE]}
    assert outcomes == {("collision", True), ("collision", False), ("hermite", True), ("hermite", False)}


def test_an_empty_subset_changes_nothing_and_bad_rows_are_named():
    full, part = _twin_cores(4)
    part.step(np.zeros((0, 2)), np.array([], np.int64))
    for name in STATE:
        np.testing.assert_array_equal(getattr(part, name), getattr(full, name), err_msg=name)
    with pytest.raises(ValueError, match=r"distinct"):
        part.step(np.zeros((2, 2)), np.array([1, 1]))
    with pytest.raises(ValueError, match=r"rows must lie in \[0, 4\), got 0..4"):
        part.step(np.zeros((2, 2)), np.array([0, 4]))
    with pytest.raises(ValueError, match=r"1-D array of env indices"):
        part.step(np.zeros((2, 2)), np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        part.step(np.zeros((4, 2)), np.array([0, 1]))


def test_a_copied_env_steps_like_its_source_and_only_its_rows_change():
    """``copy_env``: after copying env 0's state into envs 2 and 5, stepping all three with one action gives
    the same results and states as env 0, stepped twice over (a twin core that never copied)."""
    n = 8
    core, twin = _twin_cores(n)
    rng = np.random.default_rng(11)
    for _ in range(3):  # move the envs apart first
        actions = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-0.4, 0.4, n)])
        core.step(actions)
        twin.step(actions)
    untouched = np.setdiff1d(np.arange(n), [2, 5])
    before = core.S[untouched].copy()
    core.copy_env(0, [2, 5])
    np.testing.assert_array_equal(core.S[untouched], before)
    action = np.array([[0.3, 0.2]])
    core.step(np.repeat(action, 3, axis=0), [0, 2, 5])
    twin.step(action, [0])
    for row in (0, 2, 5):
        np.testing.assert_array_equal(core.S[row], twin.S[0])
        np.testing.assert_array_equal(core.R[row], twin.R[0])
        np.testing.assert_array_equal(core.obs[row], twin.obs[0])
    with pytest.raises(ValueError, match=r"rows must lie in \[0, 8\)"):
        core.copy_env(8, [1])
