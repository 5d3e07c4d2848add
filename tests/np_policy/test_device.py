"""Training on a device: the choice of device, its errors, the record of it, and (where a CUDA GPU exists) a run on
it whose checkpoint plans on the CPU."""

from __future__ import annotations

import json

import pytest
import torch

from cli_helpers import one_error_line
from np_policy.checkpoint import load_checkpoint
from np_policy.device import device_label, training_device
from np_policy.train import TrainConfig, main, train
from np_sim.errors import ConfigError

from test_train import TINY

no_gpu = pytest.mark.skipif(torch.cuda.is_available(), reason="this machine has a CUDA GPU")
needs_gpu = pytest.mark.skipif(not torch.cuda.is_available(), reason="no CUDA GPU on this machine")


def test_cpu_and_auto_without_a_gpu_train_on_the_cpu():
    assert training_device("cpu") == torch.device("cpu")
    assert device_label(training_device("cpu")) == "cpu"
    assert training_device("auto").type == ("cuda" if torch.cuda.is_available() else "cpu")


@pytest.mark.parametrize("text", ["gpu", "tpu", "mps", "cuda:x", ""])
def test_other_device_names_are_one_config_error_naming_the_flag(text):
    with pytest.raises(ConfigError, match="--device"):
        training_device(text)


@no_gpu
def test_asking_for_a_gpu_this_torch_cannot_see_is_an_error_not_a_quiet_cpu_run(tmp_path, capsys):
    with pytest.raises(ConfigError, match="sees no CUDA GPU"):
        training_device("cuda:0")
    cfg = tmp_path / "tiny.json"
    cfg.write_text(json.dumps({k: v for k, v in TINY.items() if k not in ("benchmark", "seed")}))
    line = one_error_line(capsys, main, ["--benchmark", "examples", "--config", str(cfg), "--epochs", "1",
                                         "--out", str(tmp_path / "run"), "--device", "cuda"])
    assert "--device cuda" in line and not (tmp_path / "run").exists()


def test_rows_name_the_device_and_a_resume_on_another_device_warns(tmp_path, capsys):
    config = TrainConfig.from_dict(TINY)
    run = tmp_path / "run"
    train(config, run, epochs=2, progress=False)
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert [r["device"] for r in rows] == ["cpu", "cpu"]
    provenance = [json.loads(line) for line in (run / "provenance.jsonl").read_text().splitlines()]
    assert provenance[-1]["device"] == "cpu"
    train(config, run, epochs=3, resume=True, progress=False)
    assert "device" not in capsys.readouterr().err  # same device: no warning
    # as if epochs 1-3 had trained on a GPU: resuming them on the CPU continues another curve, and says so
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    (run / "metrics.jsonl").write_text("".join(json.dumps(r | {"device": "cuda:0 (some GPU)"}) + "\n" for r in rows))
    train(config, run, resume=True, progress=False)
    err = capsys.readouterr().err
    assert "resuming on cpu where the run so far trained on cuda:0 (some GPU)" in err


@needs_gpu
def test_a_run_on_the_gpu_resumes_there_and_its_checkpoint_loads_on_the_cpu(tmp_path):
    config = TrainConfig.from_dict(TINY)
    straight, killed = tmp_path / "straight", tmp_path / "killed"
    train(config, straight, epochs=3, progress=False, device="cuda")
    train(config, killed, epochs=2, progress=False, device="cuda")
    train(config, killed, epochs=3, resume=True, progress=False, device="cuda")
    rows = [[json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()] for run in (straight,
                                                                                                        killed)]
    assert all(r["device"].startswith("cuda:") for r in rows[0] + rows[1])
    # the same kernels and generator states: the resumed curve follows the uninterrupted one closely
    for a, b in zip(*rows):
        assert a["train_return"] == pytest.approx(b["train_return"], rel=1e-3, abs=1e-3)
    weights = load_checkpoint(straight / "best.pt")["model"]
    assert all(t.device.type == "cpu" for t in weights.values())
