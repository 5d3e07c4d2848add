"""experiments.track: a tiny-budget smoke run of the CLI (plan → validate → execute → records)."""

import csv

from experiments.track import main


def test_track_cli_writes_records_table_and_rrd(tmp_path):
    result = main(["--limit", "2", "--controller", "lqr", "--rrd-episodes", "1", "--no-render", "--out",
                   str(tmp_path)])
    rows = list(csv.DictReader((tmp_path / "records.csv").open()))
    assert len(rows) == 2 and {r["controller"] for r in rows} == {"lqr"}
    for key in ("plan_success", "ref_point_valid", "footprint_valid", "exact_footprint_valid", "success", "reason",
                "cross_track_rms_m", "final_position_error_m", "realtime_factor"):
        assert key in rows[0]
    assert "| lqr |" in result["table"] and (tmp_path / "table.md").exists()
    # the default planner (Hybrid A*, footprint convention) claims only exact-valid plans
    assert all(r["exact_footprint_valid"] == r["plan_success"] for r in rows)
    assert len(list((tmp_path / "rrd").glob("*.rrd"))) == 1
