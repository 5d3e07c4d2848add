"""Tiny-budget smoke tests of the planning-core CLIs (bench, demo)."""

import json

from np_sim import bench, demo


def test_bench_json_has_the_spec_keys(capsys):
    result = bench.main(["--json", "--seconds", "0.05", "--num-envs", "8"])
    printed = json.loads(capsys.readouterr().out)
    for key in ("vector_env_steps_per_s", "single_env_steps_per_s", "ensemble_connect_us", "cast_120_us",
                "arc_check_us"):
        assert printed[key] > 0 and result[key] == printed[key]


def test_demo_writes_pngs(tmp_path, capsys):
    out = demo.main(["--out", str(tmp_path), "--steps", "40"])
    assert out["counts"]["episodes"] > 0
    assert all(p.exists() and p.stat().st_size > 0 for p in out["written"])
    assert "steps/s" in capsys.readouterr().out
