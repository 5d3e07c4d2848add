"""Float32 accuracy of the geometry branch's gradient in trained Factorial and Topology-Stress vertex runs.

    python docs/results/2026-12-06-gradient-noise-topology/measure.py > docs/results/2026-12-06-gradient-noise-topology/measure.txt

For each run: its training config with the curriculum at full range, its ``best.pt``, one collect of its own
(16,384 transitions of its training scenes; no test start is used), cut into eight update chunks of 1,024 with
random advantages and returns (seed 0); per chunk, the per-sample float32 PPO gradient against the same in float64,
as relative error per parameter (the protocol of ``../2026-12-06-shared-geometry/gradient_accuracy.py``); printed:
the median over the chunks and, in brackets, their range. Also the share of the collect's obstacle and boundary slot
values that hold the −1e4 sentinel (unused slots).
"""

import copy
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "docs/results/2026-12-06-shared-geometry"))
from gradient_accuracy import PARAMETERS, chunk_batch, chunk_gradients  # noqa: E402

from np_policy.checkpoint import load_checkpoint, load_weights  # noqa: E402
from np_policy.config import TrainConfig  # noqa: E402
from np_policy.train import Trainer, benchmark_defaults, merge_config  # noqa: E402
from np_sim.observation import observation_sections  # noqa: E402

CHUNKS = 8
RUNS = [f"factorial_np_seed{s}_lot" for s in (0, 1, 2)] + [f"topology_np_vertices_seed{s}_lot" for s in (0, 1, 2)]


def trained_collect(run: str) -> tuple[Trainer, torch.Tensor]:
    """The run's trainer (curriculum at full range) with its best.pt loaded, and the observations it collected."""
    folder = ROOT / "checkpoints/runs" / run
    config = json.loads((folder / "config.json").read_text())
    data = merge_config(benchmark_defaults(config["benchmark"]), config)
    trainer = Trainer(TrainConfig.from_dict(data), Path("/tmp/gradient_noise_run"))
    trainer.sampler.set_fraction(1.0)
    load_weights(trainer.model, load_checkpoint(folder / "best.pt")["model"], folder / "best.pt", "policy")
    obs = trainer.collect()["obs"].reshape(-1, trainer.model.encoder.obs_size)
    return trainer, torch.from_numpy(obs.copy())


def sentinel_share(trainer: Trainer, obs: torch.Tensor) -> dict[str, float]:
    """Share of the slot coordinates at the sentinel, per slot kind."""
    config = trainer.config.env.observation
    sections = observation_sections(config)
    return {kind: (obs[:, a:b] == config.sentinel).double().mean().item()
            for kind, (a, b) in sections.items() if kind in ("obstacles", "boundary")}


def chunk_errors(model, obs: torch.Tensor) -> list[float]:
    """Relative error of the per-sample float32 gradient against float64, per parameter of `PARAMETERS`."""
    batch = chunk_batch(model, obs)
    reference = chunk_gradients(copy.deepcopy(model).double(), {k: v.double() for k, v in batch.items()}, False)
    single = chunk_gradients(copy.deepcopy(model), batch, False)
    return [((single[n] - reference[n]).norm() / reference[n].norm()).item() for n in PARAMETERS]


def main() -> None:
    torch.set_num_threads(1)
    torch.manual_seed(0)
    print("| run | unused obstacle / boundary slot values | " + " | ".join(f"`{p}`" for p in PARAMETERS) + " |")
    print("|---|---|" + "---|" * len(PARAMETERS))
    for run in RUNS:
        trainer, obs = trained_collect(run)
        errors = torch.tensor([chunk_errors(trainer.model, obs[i * 1024:(i + 1) * 1024]) for i in range(CHUNKS)])
        share = sentinel_share(trainer, obs)
        cells = [f"{e.median():.1e} [{e.min():.1e}–{e.max():.1e}]" for e in errors.T]
        print(f"| `{run}` | {share['obstacles']:.2f} / {share['boundary']:.2f} | " + " | ".join(cells) + " |",
              flush=True)


if __name__ == "__main__":
    main()
