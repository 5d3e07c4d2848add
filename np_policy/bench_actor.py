"""Time the actor on batches: ``CompiledActor.batch`` against the two ways it chooses between.

``python -m np_policy.bench_actor [--checkpoint checkpoints/site_np_footprint.pt] [--batches 1 8 32 128]
[--repeats 20] [--json]``

For each batch size B this prints the rows per second of ``CompiledActor.batch`` beside its two paths: the
compiled kernel over the batch (``_mean_actions``: the single-observation network per row, how every batch ran
before ``TORCH_BATCH``) and the torch model's ``mean_action`` on the whole batch, one thread as in a closed-loop
worker. ``batch`` should match the faster of the two at every size. The footprint planner's sampled round starts
as a batch of 32 rollouts and its rescue rounds as 128, shrinking as rollouts end. Observations are synthetic flat
vectors of the checkpoint's layout (`np_policy.bench_update.synthetic_obs`); the time does not depend on their
values. Run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import torch

from np_policy.bench_update import _seconds, synthetic_obs
from np_policy.inference import TORCH_BATCH, CompiledActor, _mean_actions
from np_policy.planner import Policy
from np_sim.cli import cli_boundary, positive_int


def _best_seconds(fn, repeats: int) -> float:
    """The fastest of ``repeats`` calls of ``fn`` after one warm-up call (s)."""
    fn()
    return min(_seconds(fn) for _ in range(repeats))


def measure(checkpoint: str | Path, batches=(1, 8, 32, 128), repeats: int = 20) -> list[dict]:
    """Rows per second of the three ways to act on a batch (module docstring), per batch size."""
    torch.set_num_threads(1)
    model = Policy.load(checkpoint).model.eval()
    actor = CompiledActor(model)
    obs = synthetic_obs(model.encoder.obs_config, max(batches), torch.Generator().manual_seed(0))
    rows = []
    for b in batches:
        x = obs[:b].numpy()
        batched = _best_seconds(lambda: actor.batch(x), repeats)
        compiled = _best_seconds(lambda: _mean_actions(x, actor.mats, actor.vecs, actor.sections, actor.shape,
                                                       actor.eps), repeats)
        with torch.no_grad():
            library = _best_seconds(lambda: model.mean_action(obs[:b]), repeats)
        rows.append({"batch": b, "batch_rows_per_s": b / batched, "compiled_kernel_rows_per_s": b / compiled,
                     "torch_rows_per_s": b / library, "speedup_vs_compiled_kernel": compiled / batched})
    return rows


@cli_boundary
def main(argv=None) -> list[dict]:
    """Command-line entry point (usage in the module docstring); returns the figures of `measure`."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.bench_actor", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--checkpoint", type=Path, default=Path("checkpoints/site_np_footprint.pt"))
    parser.add_argument("--batches", type=positive_int, nargs="+", default=[1, 8, 32, 128])
    parser.add_argument("--repeats", type=positive_int, default=20, help="timed calls per figure (best kept)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)
    rows = measure(args.checkpoint, tuple(args.batches), args.repeats)
    if args.json:
        print(json.dumps(rows))
        return rows
    print(f"actor of {args.checkpoint}, rows per second (best of {args.repeats}); batches of {TORCH_BATCH} or "
          f"more go to torch:")
    print(f"{'batch':>6} {'CompiledActor.batch':>20} {'compiled kernel':>16} {'torch, 1 thread':>16} "
          f"{'batch / compiled':>17}")
    for r in rows:
        print(f"{r['batch']:>6} {r['batch_rows_per_s']:>20,.0f} {r['compiled_kernel_rows_per_s']:>16,.0f} "
              f"{r['torch_rows_per_s']:>16,.0f} {r['speedup_vs_compiled_kernel']:>16.2f}x")
    return rows


if __name__ == "__main__":
    main()
