"""tracking.bench: the real-time figures are measured on a workload that succeeds."""

from tracking.bench import GOAL_REALTIME, mj_steps_per_s, realtime_factor


def test_bench_workload_runs_and_reports_positive_rates():
    assert realtime_factor(1) > 1.0
    assert mj_steps_per_s(0.05) > 1000.0
    assert GOAL_REALTIME == 50.0
