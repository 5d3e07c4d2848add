"""Fixtures of the tracking tests."""

import pytest
from tracking_helpers import plan_from_arcs


@pytest.fixture
def cusp_plan():
    """Forward curve and straight, cusp, reverse curve and straight: the issue's cusp case."""
    return plan_from_arcs([[0.2, 6.0], [0.0, 3.0], [-0.4, -5.0], [0.0, -2.0]])
