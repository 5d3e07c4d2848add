"""Reeds–Shepp shortest paths (np_sim.reeds_shepp) against the OMPL oracle on seeded random pose pairs.

Oracle: ``ompl.base.ReedsSheppStateSpace(1/κ_max).distance`` (OMPL's independent C++ implementation of the same
48-word solution). Lengths must agree to 1e-6 m; our path, integrated arc by arc with ``arc_step`` (paper eq:arc),
must end at the goal within 1e-6 (m and rad).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from np_sim.kernels.reeds_shepp import MAX_PIECES, relative_goal, shortest_word
from np_sim.kinematics import arc_step, wrap_angle
from np_sim.reeds_shepp import shortest_length, shortest_path

ob = pytest.importorskip("ompl.base")

KAPPA = 0.68


def _pose_pairs(seed: int, n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Seeded pairs: far goals (±15 m) and, for every third pair, close goals (±2 m) where CCCC/CCSC words win."""
    rng = np.random.default_rng(seed)
    pairs = []
    for i in range(n):
        start = np.r_[rng.uniform(-15, 15, 2), rng.uniform(-math.pi, math.pi)]
        spread = 2.0 if i % 3 == 0 else 15.0
        goal = np.r_[start[:2] + rng.uniform(-spread, spread, 2), rng.uniform(-math.pi, math.pi)]
        pairs.append((start, goal))
    return pairs


def _ompl_distance(space, start, goal) -> float:
    a, b = space.allocState(), space.allocState()
    a.setX(start[0]), a.setY(start[1]), a.setYaw(start[2])
    b.setX(goal[0]), b.setY(goal[1]), b.setYaw(goal[2])
    return space.distance(a, b)


def _endpoint(start, arcs) -> np.ndarray:
    pose = np.asarray(start, float)
    for kappa, length in arcs:
        pose = arc_step(pose, kappa, length)
    return pose


@pytest.mark.parametrize("kappa_max", [KAPPA, 0.2])
def test_length_matches_ompl(kappa_max):
    space = ob.ReedsSheppStateSpace(1.0 / kappa_max)
    for start, goal in _pose_pairs(seed=0, n=3000):
        assert shortest_length(start, goal, kappa_max) == pytest.approx(_ompl_distance(space, start, goal), abs=1e-6)


def test_path_reaches_goal_and_has_the_shortest_length():
    for start, goal in _pose_pairs(seed=1, n=3000):
        arcs = shortest_path(start, goal, KAPPA)
        assert 1 <= len(arcs) <= MAX_PIECES
        end = _endpoint(start, arcs)
        assert np.hypot(*(end[:2] - goal[:2])) < 1e-6
        assert abs(wrap_angle(end[2] - goal[2])) < 1e-6
        assert np.abs(arcs[:, 1]).sum() == pytest.approx(shortest_length(start, goal, KAPPA), abs=1e-9)


def test_pieces_are_extremal_arcs_and_straights():
    """Every piece is a full-lock turn (|κ| = κ_max) or a straight (κ = 0); no zero-length pieces are returned."""
    for start, goal in _pose_pairs(seed=2, n=500):
        arcs = shortest_path(start, goal, KAPPA)
        assert np.all(np.isclose(np.abs(arcs[:, 0]), KAPPA) | (arcs[:, 0] == 0.0))
        assert np.all(np.abs(arcs[:, 1]) > 0)


def test_many_distinct_words_are_used():
    """Seeded close-range queries exercise the families: CSC, CCC, CCCC, CCSC and CCSCC all win somewhere."""
    rng = np.random.default_rng(3)
    letters, lengths = np.empty(MAX_PIECES, np.int64), np.empty(MAX_PIECES)
    words, families = set(), set()
    for _ in range(20000):
        x, y, phi = relative_goal(0.0, 0.0, 0.0, *rng.uniform(-4, 4, 2), rng.uniform(-math.pi, math.pi), 1.0)
        n = shortest_word(x, y, phi, letters, lengths)
        word = tuple((int(c), bool(t > 0)) for c, t in zip(letters[:n], lengths[:n]))
        words.add(word)
        families.add("".join("S" if c == 0 else "C" for c, _ in word))
    assert {"CSC", "CCC", "CCCC", "CCSC", "CSCC", "CCSCC"} <= families
    assert len(words) >= 40


def test_symmetry_and_identity():
    """d(a, b) = d(b, a) (a path driven backwards in time is a path), d(a, a) = 0, and a straight is its length."""
    for start, goal in _pose_pairs(seed=4, n=200):
        assert shortest_length(start, goal, KAPPA) == pytest.approx(shortest_length(goal, start, KAPPA), abs=1e-9)
    assert shortest_length([1.0, 2.0, 0.3], [1.0, 2.0, 0.3], KAPPA) == pytest.approx(0.0, abs=1e-12)
    assert shortest_length([0.0, 0.0, 0.0], [-3.0, 0.0, 0.0], KAPPA) == pytest.approx(3.0, abs=1e-12)
    np.testing.assert_allclose(shortest_path([0.0, 0.0, 0.0], [-3.0, 0.0, 0.0], KAPPA), [[0.0, -3.0]], atol=1e-12)


def test_quarter_turn_is_a_full_lock_arc():
    """Forward left quarter turn of radius r: goal (r, r, π/2), length πr/2, arc κ = −κ_max (eq:arc left = κ < 0)."""
    r = 1.0 / KAPPA
    arcs = shortest_path([0.0, 0.0, 0.0], [r, r, math.pi / 2], KAPPA)
    np.testing.assert_allclose(arcs, [[-KAPPA, math.pi * r / 2]], atol=1e-9)


@pytest.mark.parametrize(
    "start, goal, kappa_max, match",
    [
        ([0, 0], [1, 1, 0], KAPPA, "start must be a finite"),
        ([0, 0, 0], [1, np.nan, 0], KAPPA, "goal must be a finite"),
        ([0, 0, 0], [1, 1, 0], 0.0, "kappa_max must be a finite positive"),
        ([0, 0, 0], [1, 1, 0], -1.0, "kappa_max must be a finite positive"),
    ],
)
def test_bad_input_is_named(start, goal, kappa_max, match):
    with pytest.raises(ValueError, match=match):
        shortest_length(start, goal, kappa_max)
    with pytest.raises(ValueError, match=match):
        shortest_path(start, goal, kappa_max)
