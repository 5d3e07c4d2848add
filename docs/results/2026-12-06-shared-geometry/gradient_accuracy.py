"""Accuracy of the geometry branch's gradient in float32, per sample and shared, against float64.

    python docs/results/2026-12-06-shared-geometry/gradient_accuracy.py > docs/results/2026-12-06-shared-geometry/gradient_accuracy.txt

One real collect of the Factorial recipe (seed 0, the curriculum at full range, an untrained network), its first
1,024 transitions as one update chunk with random advantages and returns; the chunk's PPO gradient in float64 (the
reference: per-sample and shared agree to about 1e-10 there) against float32 per sample and float32 shared. Then the
origin: the per-sample float32 error of two geometry tensors on 1,024 synthetic observations with the unused slots at
the −1e4 sentinel (`np_policy.bench_update.synthetic_obs`) and with every slot used (no sentinel). Last, the same
errors for the trained network (the shipped seed 0, ``checkpoints/runs/factorial_np_seed0_lot/best.pt``) on a
collect it plays itself.
"""

import copy
import json
from pathlib import Path

import torch

from np_policy.bench_update import synthetic_obs
from np_policy.checkpoint import load_checkpoint, load_weights
from np_policy.config import PPOConfig, TrainConfig
from np_policy.ppo import accumulate_minibatch_gradient
from np_policy.train import Trainer, benchmark_defaults, merge_config

ROOT = Path(__file__).resolve().parents[3]
PARAMETERS = ("encoder.obstacle.0.weight", "encoder.boundary.0.weight", "encoder.geometry_attention.qkv.weight",
              "encoder.slot_position", "encoder.geometry_summary.weight", "encoder.ego.0.weight", "actor.0.weight",
              "critic.0.weight")


def chunk_gradients(model, batch, shared: bool) -> dict[str, torch.Tensor]:
    n = len(batch["obs"])
    model.zero_grad()
    accumulate_minibatch_gradient(model, batch, torch.arange(n), PPOConfig(batch_size=n, update_chunk=n), shared)
    return {name: p.grad.double().clone() for name, p in model.named_parameters()}


def chunk_batch(model, obs: torch.Tensor) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(0)
    batch = {"obs": obs}
    batch["actions"], batch["log_probs"], batch["values"] = model.act(obs)
    batch["advantages"], batch["returns"] = torch.randn(len(obs), generator=g), torch.randn(len(obs), generator=g)
    return batch


def float32_error(model, batch, names: tuple[str, ...]) -> list[float]:
    """Relative error of the per-sample float32 gradient against float64, per parameter of ``names``."""
    reference = chunk_gradients(copy.deepcopy(model).double(), {k: v.double() for k, v in batch.items()}, False)
    single = chunk_gradients(copy.deepcopy(model), batch, False)
    return [((single[n] - reference[n]).norm() / reference[n].norm()).item() for n in names]


def factorial_trainer() -> Trainer:
    """A trainer of the shipped seed 0's recipe with the curriculum at full range (an untrained network)."""
    overrides = json.loads((ROOT / "checkpoints/runs/factorial_np_seed0_lot/config.json").read_text())
    data = merge_config(benchmark_defaults("factorial"), overrides)
    data.update(benchmark="factorial", seed=0)
    trainer = Trainer(TrainConfig.from_dict(data), Path("/tmp/gradient_accuracy_run"))
    trainer.sampler.set_fraction(1.0)
    return trainer


def collect_obs():
    """(untrained network, the 16,384 observations of its trainer's first collect)."""
    trainer = factorial_trainer()
    return trainer.model, torch.from_numpy(trainer.collect()["obs"].reshape(-1, trainer.model.encoder.obs_size).copy())


def main() -> None:
    torch.set_num_threads(1)
    trainer = factorial_trainer()
    obs = torch.from_numpy(trainer.collect()["obs"].reshape(-1, trainer.model.encoder.obs_size)[:1024].copy())
    batch = chunk_batch(trainer.model, obs)
    wide = {k: v.double() for k, v in batch.items()}
    reference = chunk_gradients(copy.deepcopy(trainer.model).double(), wide, False)
    shared64 = chunk_gradients(copy.deepcopy(trainer.model).double(), wide, True)
    per_sample = chunk_gradients(copy.deepcopy(trainer.model), batch, False)
    shared = chunk_gradients(copy.deepcopy(trainer.model), batch, True)
    a, b = trainer.model.encoder.slot_span
    print(f"chunk of {len(obs)} transitions, {len(torch.unique(obs[:, a:b], dim=0))} distinct slot rows")
    print("| parameter | gradient norm (float64) | float32 per sample: relative error | float32 shared | "
          "float64 shared |")
    print("|---|---|---|---|---|")
    for name in PARAMETERS:
        ref = reference[name].norm().item()
        errors = [(grad[name] - reference[name]).norm().item() / ref for grad in (per_sample, shared, shared64)]
        print(f"| `{name}` | {ref:.3e} | {errors[0]:.1e} | {errors[1]:.1e} | {errors[2]:.1e} |")
    names = ("encoder.obstacle.0.weight", "encoder.geometry_attention.qkv.weight")
    g = torch.Generator().manual_seed(1)
    config = trainer.config.env.observation
    with_sentinel = synthetic_obs(config, 1024, g)
    every_slot = torch.randn(with_sentinel.shape, generator=g) * 5.0
    print(f"\nper-sample float32 relative error of {names} on synthetic observations:")
    for label, synthetic in (("unused slots at the -1e4 sentinel", with_sentinel), ("every slot used", every_slot)):
        errors = float32_error(trainer.model, chunk_batch(trainer.model, synthetic), names)
        print(f"- {label}: " + ", ".join(f"{e:.1e}" for e in errors))
    trained = ROOT / "checkpoints/runs/factorial_np_seed0_lot/best.pt"
    load_weights(trainer.model, load_checkpoint(trained)["model"], trained, "policy")
    obs = torch.from_numpy(trainer.collect()["obs"].reshape(-1, trainer.model.encoder.obs_size)[:1024].copy())
    errors = float32_error(trainer.model, chunk_batch(trainer.model, obs), PARAMETERS)
    print(f"\ntrained network ({trained.relative_to(ROOT)}), a chunk of its own collect, per-sample float32 relative "
          "error:\n" + "\n".join(f"- `{name}`: {e:.1e}" for name, e in zip(PARAMETERS, errors)))


if __name__ == "__main__":
    main()
