"""checkpoints/MANIFEST.json: the committed manifest against the committed files (hashes recomputed here with
hashlib), and build/check on small checkpoint trees."""

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch

from np_policy.checkpoint import CHECKPOINT_FORMAT, CheckpointError, save_checkpoint
from np_policy.manifest import build_manifest, check_manifest, main

CHECKPOINTS = Path(__file__).resolve().parents[2] / "checkpoints"


def _expected_shipped(root):
    """Every .pt under ``root`` but snapshots and the best.pt of folders that still hold a snapshot."""
    return {p.relative_to(root.parent).as_posix() for p in root.rglob("*.pt")
            if p.name != "snapshot.pt" and not p.name.endswith(".snapshot.pt")
            and not (p.name == "best.pt" and (p.parent / "snapshot.pt").exists())}


def test_the_committed_manifest_matches_the_committed_files():
    manifest = json.loads((CHECKPOINTS / "MANIFEST.json").read_text())
    assert set(manifest["files"]) == _expected_shipped(CHECKPOINTS)
    assert {"checkpoints/factorial_np_seed0.pt", "checkpoints/site_np.pt",
            "checkpoints/site_np_footprint.pt"} <= set(manifest["files"])
    root = CHECKPOINTS.parent
    for name, entry in manifest["files"].items():
        data = (root / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == entry["sha256"], name
        assert len(data) == entry["size_bytes"], name
        raw = torch.load(root / name, map_location="cpu", weights_only=True)
        assert raw["format"] == entry["format"] == CHECKPOINT_FORMAT, name
        if entry.get("kind") == "bev-autoencoder":  # pretrained, from no training run
            assert raw["kind"] == entry["kind"] and len(raw["metrics"]) == entry["epochs"], name
            continue
        assert raw.get("epoch") == entry["epoch"], name
        assert entry["config"] == f"{entry['run']}/config.json" and (root / entry["config"]).is_file()
        source = entry.get("copy_of", name)
        assert source in (f"{entry['run']}/best.pt", f"{entry['run']}/final.pt")  # NeuralParker / adapted HOPE
        assert hashlib.sha256((root / source).read_bytes()).hexdigest() == entry["sha256"], name
    assert sorted(manifest["resumable_runs"]) == sorted(
        p.parent.relative_to(root).as_posix() for p in CHECKPOINTS.rglob("snapshot.pt"))
    check_manifest(CHECKPOINTS)


def _payload(seed, epoch, extra=None):
    torch.manual_seed(seed)
    return {"model": {"w": torch.randn(3, 2)}, "config": {"seed": seed}, "epoch": epoch, **(extra or {})}


def _run(root, name, seed, epoch, snapshot=False):
    run = root / "runs" / name
    run.mkdir(parents=True)
    (run / "config.json").write_text(json.dumps({"seed": seed}))
    (run / "metrics.jsonl").write_text(json.dumps({"epoch": epoch}) + "\n")
    save_checkpoint(run / "best.pt", _payload(seed, epoch))
    if snapshot:
        save_checkpoint(run / "snapshot.pt", _payload(seed, epoch + 1, {"optimizer": {}}))
    return run


@pytest.fixture
def tree(tmp_path):
    """checkpoints/ with a finished run a, a resumable run b, a byte copy of b's best.pt and a re-saved copy of
    a's weights (other bytes: an extra key)."""
    root = tmp_path / "checkpoints"
    _run(root, "a", seed=1, epoch=7)
    _run(root, "b", seed=2, epoch=3, snapshot=True)
    shutil.copy(root / "runs" / "b" / "best.pt", root / "b_copy.pt")
    save_checkpoint(root / "a_resaved.pt", _payload(1, 7, {"note": "re-saved"}))
    return root


def test_build_names_each_files_run_and_leaves_out_snapshots_and_resumable_runs(tree):
    manifest = build_manifest(tree)
    files = manifest["files"]
    assert sorted(files) == ["checkpoints/a_resaved.pt", "checkpoints/b_copy.pt", "checkpoints/runs/a/best.pt"]
    assert manifest["resumable_runs"] == ["checkpoints/runs/b"]
    assert files["checkpoints/b_copy.pt"]["copy_of"] == "checkpoints/runs/b/best.pt"
    assert files["checkpoints/b_copy.pt"]["epoch"] == 3
    assert files["checkpoints/a_resaved.pt"]["copy_of"] == "checkpoints/runs/a/best.pt"  # found by its weights
    assert files["checkpoints/a_resaved.pt"]["sha256"] != files["checkpoints/runs/a/best.pt"]["sha256"]
    best = files["checkpoints/runs/a/best.pt"]
    assert "copy_of" not in best and best["run"] == "checkpoints/runs/a" and best["epoch"] == 7
    assert best["config"] == "checkpoints/runs/a/config.json" and best["format"] == CHECKPOINT_FORMAT
    data = (tree / "runs" / "a" / "best.pt").read_bytes()
    assert best["size_bytes"] == len(data) and best["sha256"] == hashlib.sha256(data).hexdigest()


def test_check_reports_a_replaced_file_a_new_one_and_a_run_that_finished(tree, capsys):
    assert main(["build", "--root", str(tree)])["files"]
    assert main(["check", "--root", str(tree)])["resumable_runs"] == ["checkpoints/runs/b"]
    assert "checked" in capsys.readouterr().out
    save_checkpoint(tree / "b_copy.pt", _payload(2, 3, {"note": "changed"}))  # same weights, other bytes
    (tree / "runs" / "b" / "snapshot.pt").unlink()  # run b finished: its best.pt ships now
    with pytest.raises(CheckpointError) as error:
        check_manifest(tree)
    message = str(error.value)
    assert "checkpoints/b_copy.pt: sha256 is" in message and "checkpoints/runs/b/best.pt: shipped but not listed" \
        in message and "resumable_runs are ['checkpoints/runs/b'] in the manifest, [] in the files" in message
    with pytest.raises(SystemExit) as exit_info:
        main(["check", "--root", str(tree)])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and err.startswith("error: ") and len(err.strip().splitlines()) == 1


def test_a_file_from_no_run_and_a_missing_manifest_are_one_error_line(tree, capsys):
    save_checkpoint(tree / "stray.pt", _payload(9, 1))
    with pytest.raises(CheckpointError, match=r"stray.pt: no run's best.pt has its SHA-256 or its weights"):
        build_manifest(tree)
    for argv in (["build", "--root", str(tree)], ["check", "--root", str(tree)]):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        err = capsys.readouterr().err
        assert exit_info.value.code == 2 and err.startswith("error: ") and len(err.strip().splitlines()) == 1
    assert "MANIFEST.json: not a readable manifest" in err
    assert not (tree / "MANIFEST.json").exists()


def test_a_pretrained_autoencoder_is_listed_with_its_pretraining_not_a_run(tree):
    from np_policy.bev_encoder import PretrainConfig, pretrain

    config = PretrainConfig(images=64, epochs=2, batch_size=32, collect_envs=4)
    images = np.random.default_rng(0).integers(0, 256, (64, 3, 64, 64), dtype=np.uint8)
    (tree / "bev").mkdir()
    rows = pretrain(config, tree / "bev" / "tiny_ae.pt", images=images, log=lambda _: None, progress=False)
    entry = build_manifest(tree)["files"]["checkpoints/bev/tiny_ae.pt"]
    data = (tree / "bev" / "tiny_ae.pt").read_bytes()
    assert entry["kind"] == "bev-autoencoder" and "run" not in entry
    assert entry["pretraining"]["images"] == 64 and entry["epochs"] == 2
    assert entry["held_out_mse"] == rows[-1]["held_out_mse"]
    assert entry["sha256"] == hashlib.sha256(data).hexdigest() and entry["size_bytes"] == len(data)
