"""Path metrics (paper eq:metrics) on hand-computed plans."""

import pytest

from np_sim.metrics import plan_metrics


def test_metrics_without_hermite():
    L, rev, dk = plan_metrics([[0.2, 3.0], [-0.4, -2.0], [0.0, 1.5]])
    assert L == pytest.approx(6.5)
    assert rev == 2
    assert dk == pytest.approx(0.6 + 0.4)


def test_metrics_with_hermite_adds_length_curvature_and_final_gear_change():
    L, rev, dk = plan_metrics([[0.2, 3.0], [0.1, 2.0]], hermite_length=4.0, hermite_delta_kappa=0.3,
                              hermite_forward=False)
    assert (L, rev) == (pytest.approx(9.0), 1)  # reverse Hermite after a forward arc: one more reversal
    assert dk == pytest.approx(0.1 + 0.3)
    assert plan_metrics([[0.2, 3.0]], 1.0, 0.0, True)[1] == 0


def test_metrics_need_all_hermite_terms():
    with pytest.raises(ValueError, match="needs hermite_length, hermite_delta_kappa and hermite_forward"):
        plan_metrics([[0.1, 1.0]], hermite_length=2.0)
