"""Does a trained NeuralParker policy use its geometry token? Replace the token by a constant and re-plan.

    python docs/results/2026-12-06-geometry-ablation/ablate.py RUN [RUN ...]

For each run folder (``checkpoints/runs/RUN``) its ``best.pt`` is copied with the geometry summary layer set to a
constant (weights zero, bias the mean geometry token over the distinct slot rows of one collect of its own
training recipe, so each scene gets the average scene's token) and plans the validation starts of the training
scenes (`experiments.evaluate --split validation`), beside the run's own validation records of ``best.pt``. A policy that reads the scene through its
geometry branch loses success when the token no longer carries the scene; one that steers by its ego and LiDAR
inputs alone does not. Training-scene starts only: no test start is used.
"""

import copy
import csv
import json
import sys
from pathlib import Path

import torch

from experiments.evaluate import evaluate
from np_policy.checkpoint import load_checkpoint, load_weights, save_checkpoint
from np_policy.train import Trainer, TrainConfig

ROOT = Path(__file__).resolve().parents[3]
OUT = Path(__file__).resolve().parent


def constant_geometry_checkpoint(run: Path, path: Path) -> None:
    """Write ``run/best.pt`` with a constant geometry token to ``path``."""
    payload = load_checkpoint(run / "best.pt")
    config = TrainConfig.from_dict(json.loads((run / "config.json").read_text()))
    trainer = Trainer(config, Path("/tmp/geometry_ablation_run"))
    load_weights(trainer.model, payload["model"], run / "best.pt", "policy")
    trainer.sampler.set_fraction(1.0)
    encoder = trainer.model.encoder
    obs = torch.from_numpy(trainer.collect()["obs"].reshape(-1, encoder.obs_size))
    rows = torch.unique(obs[:, encoder.slot_span[0]:encoder.slot_span[1]], dim=0)
    with torch.no_grad():
        mean_token = encoder.geometry_token(rows).mean(dim=0)
        encoder.geometry_summary.weight.zero_()
        encoder.geometry_summary.bias.copy_(mean_token)
    ablated = copy.deepcopy(payload)
    ablated["model"] = {k: v.detach().clone() for k, v in trainer.model.state_dict().items()}
    save_checkpoint(path, ablated)
    print(f"{run.name}: mean token over {len(rows)} distinct slot rows")


def main(runs: list[str]) -> None:
    torch.set_num_threads(1)
    for name in runs:
        run = ROOT / "checkpoints/runs" / name
        benchmark = json.loads((run / "config.json").read_text())["benchmark"]
        ablated = Path("/tmp") / f"{name}_constant_geometry.pt"
        constant_geometry_checkpoint(run, ablated)
        with (run / f"eval_{benchmark}_validation" / "records.csv").open() as f:
            trained = [int(row["success"]) for row in csv.DictReader(f)]
        print(f"{name} as trained (its eval_{benchmark}_validation records): validation success "
              f"{sum(trained) / len(trained):.3f} ({len(trained)} starts)")
        records = evaluate(benchmark, [ablated], split="validation", progress=False,
                           out=OUT / f"{name}_constant_geometry")["records"]
        success = sum(r["success"] for r in records) / len(records)
        print(f"{name} constant geometry token: validation success {success:.3f} ({len(records)} starts)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
