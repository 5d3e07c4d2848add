"""Arc kinematics (paper eq:arc, spec §2): hand-derived poses, sign conventions, retracing, sampling, wrapping.

eq:arc, with r = 1/|κ|, α = |lκ|, δ_l = sgn(l), δ_κ = sgn(κ):
    x' = x + δ_l [ r(1 − cos α) δ_κ sin θ + r sin α cos θ ]
    y' = y + δ_l [ −r(1 − cos α) δ_κ cos θ + r sin α sin θ ]
    θ' = θ − δ_κ α
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from np_sim.kinematics import arc_step, sample_arc, steer_curvature, wrap_angle

PROPS = settings(max_examples=300, deadline=None, derandomize=True)
PI = math.pi

poses = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-PI, PI))
# subnormal |κ| (< 2.2e-308) is pinned on its own (test_arc_step_subnormal_curvature); the properties use normal floats
kappas = st.floats(-0.68, 0.68, allow_subnormal=False)
# plus deliberately tiny curvatures, log-uniform 1e-12 .. 1e-2 (nearly straight arcs, where 1 − cos α cancels)
tiny_kappas = st.tuples(st.floats(-12, -2), st.sampled_from([-1.0, 1.0])).map(lambda t: t[1] * 10.0 ** t[0])
all_kappas = kappas | tiny_kappas
lengths = st.floats(-10, 10)


def assert_pose(got, want, tol=1e-12):
    got, want = np.asarray(got, float), np.asarray(want, float)
    np.testing.assert_allclose(got[:2], want[:2], rtol=0, atol=tol)
    assert abs(wrap_angle(got[2] - want[2])) <= tol, (got, want)


# ---------------------------------------------------------------------------------------------- hand values


@pytest.mark.parametrize(
    "pose, kappa, length, expected",
    [
        # κ = +0.5, l = +π: r = 2, α = π/2, δ_l = +1, δ_κ = +1, θ = 0 (sin 0, cos 1):
        #   x' = 0 + [2·1·1·0 + 2·1·1] = 2, y' = 0 + [−2·1·1·1 + 2·1·0] = −2, θ' = 0 − π/2   (forward, right turn)
        ((0.0, 0.0, 0.0), 0.5, PI, (2.0, -2.0, -PI / 2)),
        # κ = −0.5, l = +π: δ_κ = −1: x' = [2·1·(−1)·0 + 2] = 2, y' = [−2·1·(−1)·1 + 0] = 2, θ' = +π/2 (fwd, left)
        ((0.0, 0.0, 0.0), -0.5, PI, (2.0, 2.0, PI / 2)),
        # κ = +0.5, l = −π: δ_l = −1, δ_κ = +1: x' = −[0 + 2] = −2, y' = −[−2 + 0] = 2, θ' = −π/2 (reverse)
        ((0.0, 0.0, 0.0), 0.5, -PI, (-2.0, 2.0, -PI / 2)),
        # κ = −0.5, l = −π: δ_l = −1, δ_κ = −1: x' = −[0 + 2] = −2, y' = −[+2 + 0] = −2, θ' = +π/2 (reverse)
        ((0.0, 0.0, 0.0), -0.5, -PI, (-2.0, -2.0, PI / 2)),
        # κ = 0: straight, x' = x + l cos θ, y' = y + l sin θ, θ' = θ
        ((0.0, 0.0, 0.0), 0.0, 3.0, (3.0, 0.0, 0.0)),
        ((0.0, 0.0, 0.0), 0.0, -3.0, (-3.0, 0.0, 0.0)),
        ((1.0, 2.0, PI / 2), 0.0, 3.0, (1.0, 5.0, PI / 2)),
        ((1.0, 2.0, PI / 2), 0.0, -3.0, (1.0, -1.0, PI / 2)),
        # from (1, 2, π/2) (sin 1, cos 0), κ = +0.5, l = +π: x' = 1 + [2·1·1·1 + 0] = 3, y' = 2 + [0 + 2·1·1] = 4,
        # θ' = π/2 − π/2 = 0  (heading north, forward right turn: ends 2 m east and 2 m north, heading east)
        ((1.0, 2.0, PI / 2), 0.5, PI, (3.0, 4.0, 0.0)),
        # same start, κ = +0.5, l = −π: x' = 1 − [2 + 0] = −1, y' = 2 − [0 + 2] = 0, θ' = 0
        ((1.0, 2.0, PI / 2), 0.5, -PI, (-1.0, 0.0, 0.0)),
        # from (1, 2, π/2), κ = −0.25, l = +2π: r = 4, α = π/2, δ_κ = −1:
        #   x' = 1 + [4·1·(−1)·1 + 0] = −3, y' = 2 + [−4·1·(−1)·0 + 4·1·1] = 6, θ' = π/2 + π/2 = π
        ((1.0, 2.0, PI / 2), -0.25, 2 * PI, (-3.0, 6.0, PI)),
        # half turn κ = +0.5, l = 2π: α = π, 1 − cos α = 2: x' = [2·2·1·0 + 0] = 0, y' = [−2·2·1·1 + 0] = −4,
        # θ' = −π, wrapped to +π
        ((0.0, 0.0, 0.0), 0.5, 2 * PI, (0.0, -4.0, PI)),
        # κ = +0.68, l = +10 (the action bounds): r = 1/0.68, α = 6.8;
        #   x' = r sin 6.8, y' = −r(1 − cos 6.8), θ' = −6.8 wrapped = 2π − 6.8
        ((0.0, 0.0, 0.0), 0.68, 10.0, (math.sin(6.8) / 0.68, -(1 - math.cos(6.8)) / 0.68, 2 * PI - 6.8)),
    ],
)
def test_arc_step_hand_values(pose, kappa, length, expected):
    got = arc_step(pose, kappa, length)
    assert_pose(got, expected)
    assert -PI < got[2] <= PI


def test_arc_step_zero_length_and_input_checks():
    assert_pose(arc_step((1.0, -2.0, 0.3), 0.4, 0.0), (1.0, -2.0, 0.3), tol=0.0)
    with pytest.raises(ValueError):
        arc_step((0.0, 0.0), 0.1, 1.0)
    with pytest.raises(ValueError):
        arc_step((0.0, math.nan, 0.0), 0.1, 1.0)
    with pytest.raises(ValueError):
        sample_arc((0.0, 0.0, 0.0), 0.1, 1.0, n=0)


# ---------------------------------------------------------------------------------------------- properties


@PROPS
@given(poses, kappas, lengths)
def test_heading_change_is_minus_sign_kappa_times_abs_l_kappa_whatever_the_gear(pose, kappa, length):
    end = arc_step(pose, kappa, length)
    dth = -np.sign(kappa) * abs(length * kappa)
    assert abs(wrap_angle(end[2] - (pose[2] + dth))) <= 1e-9
    # the gear does not enter: (κ, l) and (κ, −l) turn the heading the same way
    assert abs(wrap_angle(arc_step(pose, kappa, -length)[2] - end[2])) <= 1e-9


# |κ| ≥ 1e-4 or 0: below, the float form r·(1 − cos α) of the oracle itself cancels (error ≈ ε/|κ|); tiny κ is
# pinned by test_arc_step_matches_eq_arc_in_high_precision
closed_form_kappas = kappas.filter(lambda k: k == 0.0 or abs(k) >= 1e-4)


@PROPS
@given(poses, closed_form_kappas, lengths)
def test_arc_matches_closed_form(pose, kappa, length):
    """eq:arc evaluated here in plain Python, term by term."""
    x, y, th = pose
    if kappa == 0.0:
        want = (x + length * math.cos(th), y + length * math.sin(th), th)
    else:
        r, a = 1 / abs(kappa), abs(length * kappa)
        dl, dk = float(np.sign(length)), float(np.sign(kappa))
        want = (
            x + dl * (r * (1 - math.cos(a)) * dk * math.sin(th) + r * math.sin(a) * math.cos(th)),
            y + dl * (-r * (1 - math.cos(a)) * dk * math.cos(th) + r * math.sin(a) * math.sin(th)),
            th - dk * a,
        )
    assert_pose(arc_step(pose, kappa, length), want, tol=1e-9)


@PROPS
@example(pose=(0.0, 0.0, 0.0), kappa=9.060309449890941e-08, length=1.083984375)  # found by hypothesis
@given(poses, all_kappas, lengths)
def test_minus_kappa_minus_l_retraces_exactly(pose, kappa, length):
    back = arc_step(arc_step(pose, kappa, length), -kappa, -length)
    assert_pose(back, pose, tol=1e-9)


@PROPS
@given(poses, st.floats(0.05, 0.68), st.floats(0.5, 10), st.booleans(), st.booleans())
def test_kappa_minus_l_does_not_retrace(pose, kmag, lmag, neg_k, neg_l):
    """(κ, −l) keeps turning the heading the same way: it ends 2|lκ| off in heading (mod 2π) and elsewhere."""
    kappa = -kmag if neg_k else kmag
    length = -lmag if neg_l else lmag
    alpha = abs(kappa * length)
    back = arc_step(arc_step(pose, kappa, length), kappa, -length)
    assert abs(wrap_angle(back[2] - (pose[2] - 2 * np.sign(kappa) * alpha))) <= 1e-9
    # position: (κ, −l) follows a different circle (the physical curvature flips sign with the gear), so it does
    # not come back; the displacement vanishes only when α is a multiple of π (hand case below: α = π/2 → 4 m)
    if min(alpha % PI, PI - alpha % PI) > 0.05:
        assert math.dist(back[:2], pose[:2]) > 1e-3


@PROPS
@example(pose=(0.0, 0.0, 0.0), kappa=1e-8, length=5.0)
@example(pose=(0.0, 0.0, 0.0), kappa=9.060309449890941e-08, length=1.083984375)
@given(poses, all_kappas, lengths)
def test_arc_step_matches_eq_arc_in_high_precision(pose, kappa, length):
    """eq:arc evaluated in 50-digit arithmetic from the same float inputs: arc_step within 1e-9 m / rad.

    (The float form r·(1 − cos α) loses all of 1 − cos α's digits to cancellation when α² ≈ 1e-16, i.e. an
    absolute error up to ~r·ε = ε/|κ| — about 3e-9 m at κ = 1e-8, l = 5. 2·sin²(α/2) is the cancellation-free
    form of the same quantity.)"""
    mp = pytest.importorskip("mpmath")
    with mp.workdps(50):
        x, y, th, k, ln = (mp.mpf(v) for v in (*pose, kappa, length))
        if kappa == 0.0:
            want = (x + ln * mp.cos(th), y + ln * mp.sin(th), th)
        else:
            r, a = 1 / abs(k), abs(ln * k)
            dl, dk = mp.sign(ln), mp.sign(k)
            want = (
                x + dl * (r * (1 - mp.cos(a)) * dk * mp.sin(th) + r * mp.sin(a) * mp.cos(th)),
                y + dl * (-r * (1 - mp.cos(a)) * dk * mp.cos(th) + r * mp.sin(a) * mp.sin(th)),
                th - dk * a,
            )
        want = tuple(float(v) for v in want)
    assert_pose(arc_step(pose, kappa, length), want, tol=1e-9)


def test_kappa_minus_l_hand_case():
    # κ = 0.5, l = π to (2, −2, −π/2); then (0.5, −π) from θ = −π/2 (sin −1, cos 0):
    #   x'' = 2 − [2·1·1·(−1) + 0] = 4, y'' = −2 − [0 + 2·1·(−1)] = 0, θ'' = −π/2 − π/2 = −π → π
    mid = arc_step((0.0, 0.0, 0.0), 0.5, PI)
    assert_pose(arc_step(mid, 0.5, -PI), (4.0, 0.0, PI))
    assert_pose(arc_step(mid, -0.5, -PI), (0.0, 0.0, 0.0))


# ---------------------------------------------------------------------------------------------- sampling


@PROPS
@given(poses, kappas, lengths, st.integers(1, 60))
def test_sample_arc_rows_lie_on_the_arc(pose, kappa, length, n):
    pts = sample_arc(pose, kappa, length, n)
    assert pts.shape == (n, 3)
    np.testing.assert_allclose(pts[-1, :2], arc_step(pose, kappa, length)[:2], rtol=0, atol=1e-12)
    assert abs(wrap_angle(pts[-1, 2] - arc_step(pose, kappa, length)[2])) <= 1e-12
    for j in range(n):  # row j is the arc of length l·(j+1)/n
        assert_pose(pts[j], arc_step(pose, kappa, length * (j + 1) / n), tol=1e-12)
    x, y, th = pose
    if kappa != 0.0 and length != 0.0:
        # eq:arc's turning centre: p' − c = δ_l r (−δ_κ cos α sin θ + sin α cos θ, δ_κ cos α cos θ + sin α sin θ)
        # has norm r for c = p + r·δ_l·δ_κ·(sin θ, −cos θ): right of the heading for forward κ > 0, LEFT of it
        # for reverse κ > 0 (physical curvature −δ_l κ > 0). The forward-only form p + r·δ_κ·(sin θ, −cos θ) is
        # off the arc in reverse: (0, 0, 0), κ = 0.5, l = −1 ends 2.441 m from (0, −2), not r = 2.
        r = 1 / abs(kappa)
        centre = np.array([x, y]) + r * np.sign(length) * np.sign(kappa) * np.array([math.sin(th), -math.cos(th)])
        np.testing.assert_allclose(np.hypot(*(pts[:, :2] - centre).T), r, rtol=1e-12, atol=1e-9)
    else:  # on the straight line through the pose along the heading, at signed distance l·(j+1)/n
        along = (pts[:, 0] - x) * math.cos(th) + (pts[:, 1] - y) * math.sin(th)
        across = -(pts[:, 0] - x) * math.sin(th) + (pts[:, 1] - y) * math.cos(th)
        np.testing.assert_allclose(along, length * np.arange(1, n + 1) / n, rtol=0, atol=1e-9)
        np.testing.assert_allclose(across, 0.0, atol=1e-9)
    assert np.all((pts[:, 2] > -PI) & (pts[:, 2] <= PI))
    # each sample's heading: θ − sgn(κ)·|l_j κ|
    lj = length * np.arange(1, n + 1) / n
    dth = np.array([wrap_angle(pts[j, 2] - (th - np.sign(kappa) * abs(lj[j] * kappa))) for j in range(n)])
    np.testing.assert_allclose(dth, 0.0, atol=1e-9)


def test_sample_arc_centre_hand_case():
    # forward κ = 0.5 from the origin heading +x: centre (0, −2); the quarter arc passes (2, −2)
    assert math.dist(arc_step((0, 0, 0), 0.5, PI)[:2], (0.0, -2.0)) == pytest.approx(2.0, abs=1e-12)
    # reverse κ = 0.5: x' = −2 sin 0.5, y' = +2(1 − cos 0.5): on the circle about (0, +2), the left side
    end = arc_step((0, 0, 0), 0.5, -1.0)
    assert_pose(end, (-2 * math.sin(0.5), 2 * (1 - math.cos(0.5)), -0.5))
    assert math.dist(end[:2], (0.0, 2.0)) == pytest.approx(2.0, abs=1e-12)


def test_arc_step_subnormal_curvature():
    """eq:arc as κ → 0 is the straight segment; for |κ| below 1/DBL_MAX ≈ 5.6e-309, r = 1/|κ| overflows.

    (0, 0, 0), κ = 5e-324, l = 1: exact eq:arc gives x' = r sin α = 1 (to 1e-300), y' = −r(1 − cos α) ≈ −1e-324,
    θ' = −5e-324, i.e. (1, 0, 0) to any tolerance."""
    for kappa in (5e-324, -5e-324, 1e-310, 2.0**-1030):
        assert_pose(arc_step((0.0, 0.0, 0.0), kappa, 1.0), (1.0, 0.0, 0.0), tol=1e-12)
        assert np.all(np.isfinite(sample_arc((0.0, 0.0, 0.0), kappa, 1.0)))


def test_sample_arc_default_is_30_rows():
    assert sample_arc((0.0, 0.0, 0.0), 0.3, 5.0).shape == (30, 3)


@PROPS
@given(poses, kappas, lengths)
def test_polyline_length_of_samples(pose, kappa, length):
    """Chords from the start through the samples: n·2r·sin(α/2n) exactly (|l| on a straight), → |l| as n grows."""

    def polyline(n):
        pts = np.vstack([np.array(pose)[None, :2], sample_arc(pose, kappa, length, n)[:, :2]])
        return float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))

    alpha = abs(length * kappa)
    for n in (30, 2000):
        # n·2r·sin(α/2n) written as |l|·sin(x)/x, x = α/2n, so tiny |κ| cannot overflow r = 1/|κ|
        x = alpha / (2 * n)
        chords = abs(length) if x == 0.0 else abs(length) * math.sin(x) / x
        assert polyline(n) == pytest.approx(chords, rel=1e-9, abs=1e-9)
    assert polyline(2000) == pytest.approx(abs(length), abs=1e-4)
    assert polyline(30) <= abs(length) + 1e-9  # chords never exceed the arc


# ---------------------------------------------------------------------------------------------- steer curvature


def test_steer_curvature_signs():
    assert steer_curvature(0.5, 3.0) == -0.5  # forward, κ > 0: right turn, physical curvature negative
    assert steer_curvature(-0.5, 3.0) == 0.5  # forward, κ < 0: left turn
    assert steer_curvature(0.5, -3.0) == 0.5  # reverse, κ > 0: physical curvature positive
    assert steer_curvature(-0.5, -3.0) == -0.5
    np.testing.assert_array_equal(steer_curvature(np.array([0.2, 0.2]), np.array([1.0, -1.0])), [-0.2, 0.2])
    # geometry of the sign: forward κ > 0 from heading +x ends on the right (y < 0); a left turn would end y > 0
    assert arc_step((0.0, 0.0, 0.0), 0.5, 1.0)[1] < 0.0
    # reverse κ > 0 from heading +x: backing up with positive (left) curvature swings the car to y > 0 while the
    # heading decreases (a reversing left-steered car turns clockwise)
    end = arc_step((0.0, 0.0, 0.0), 0.5, -1.0)
    assert end[0] < 0.0 and end[1] > 0.0 and end[2] < 0.0


@PROPS
@given(poses, kappas, lengths)
def test_heading_change_equals_steer_curvature_times_signed_length(pose, kappa, length):
    c = steer_curvature(kappa, length)
    end = arc_step(pose, kappa, length)
    assert abs(wrap_angle(end[2] - (pose[2] + c * length))) <= 1e-9
    # and the path's signed curvature (turn rate per signed distance) is c: compare a short step numerically
    if length != 0.0 and kappa != 0.0:
        h = 1e-4 * np.sign(length)
        p1 = arc_step(pose, kappa, h)
        p2 = arc_step(pose, kappa, 2 * h)
        d1 = (p1[:2] - np.array(pose[:2])) / h  # signed-distance derivative (direction of motion × gear)
        d2 = (p2[:2] - 2 * p1[:2] + np.array(pose[:2])) / h**2
        signed_curv = (d1[0] * d2[1] - d1[1] * d2[0]) / np.hypot(*d1) ** 3
        assert signed_curv == pytest.approx(c, abs=1e-3)


# ---------------------------------------------------------------------------------------------- wrap


@pytest.mark.parametrize(
    "a, want",
    [(0.0, 0.0), (PI, PI), (-PI, PI), (3 * PI, PI), (-3 * PI, PI), (2 * PI, 0.0), (PI / 2, PI / 2),
     (-PI / 2, -PI / 2), (3 * PI / 2, -PI / 2), (-3 * PI / 2, PI / 2), (7.0, 7.0 - 2 * PI)],
)
def test_wrap_angle_values(a, want):
    assert wrap_angle(a) == pytest.approx(want, abs=1e-12)


@PROPS
@given(st.floats(-1e4, 1e4))
def test_wrap_angle_range_and_congruence(a):
    w = wrap_angle(a)
    assert -PI < w <= PI
    k = (a - w) / (2 * PI)
    assert abs(k - round(k)) <= 1e-9 * max(1.0, abs(a))


def test_the_heading_gap_is_the_shorter_way_round():
    from np_sim.kinematics import heading_gap

    assert heading_gap(3.1, -3.1) == pytest.approx(2 * math.pi - 6.2)  # across ±π: 0.083 rad, not 6.2
    assert heading_gap(-0.5, 0.25) == pytest.approx(0.75)
    assert heading_gap(math.radians(370.0), math.radians(-10.0)) == pytest.approx(math.radians(20.0))
    assert heading_gap(0.0, math.pi) == pytest.approx(math.pi)
