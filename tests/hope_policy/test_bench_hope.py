"""hope_policy.bench: the training figures summed from a run's metrics, the variants it times."""

import json

import pytest

from hope_policy.bench import env_variants, main, training_runs


def test_training_figures_sum_collect_and_update_seconds_of_finished_runs_only(tmp_path):
    finished, running = tmp_path / "factorial_hope_seed7", tmp_path / "factorial_hope_seed8"
    for run in (finished, running):
        run.mkdir()
        rows = [{"collect_s": 10.0, "update_s": 50.0, "env_steps": 8192, "episodes": 300},
                {"collect_s": 20.0, "update_s": 100.0, "env_steps": 16384, "episodes": 650}]
        (run / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    (finished / "final.pt").write_bytes(b"")
    (running / "snapshot.pt").write_bytes(b"")
    [figure] = training_runs(tmp_path)
    assert figure["run"] == finished.name and figure["updates"] == 2 and figure["episodes"] == 650
    assert figure["hours"] == pytest.approx(180.0 / 3600.0) and figure["env_steps_per_s"] == pytest.approx(16384 / 180)


def test_the_bev_backbone_is_timed_only_with_an_encoder(tmp_path):
    assert len(env_variants(None)) == 3
    with_bev = env_variants(tmp_path / "ae.pt")
    assert with_bev["backbone: BEV (raster + frozen encoder)"][0].added_input == "bev"
    assert with_bev["complete baseline (mask + RS takeover)"][0].action_mask


def test_a_missing_checkpoint_is_one_error_line(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--checkpoint", "/nonexistent.pt"])
    assert exit_.value.code == 2 and "error:" in capsys.readouterr().err
