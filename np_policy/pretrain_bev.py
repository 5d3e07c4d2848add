"""Pretrain one benchmark's BEV autoencoder (paper App. B; the model, the images and the schedule are in
`np_policy.bev_encoder`):

    python -m np_policy.pretrain_bev --benchmark topology --out checkpoints/bev/topology_ae_v2.pt --seed 0

Collects the tail-enabled random-policy images (seeded, so they are collected again rather than stored), trains
with a progress bar (training and held-out MSE per epoch), snapshots after every epoch (the same command continues
after a kill) and writes ``FILE`` (never over a finished one) and ``FILE.png``: eight held-out images above their
reconstructions.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from np_policy.bev_encoder import PRETRAIN_BENCHMARKS, PretrainConfig, pretrain
from np_policy.threads import use_threads
from np_sim.cli import cli_boundary, non_negative_int, positive_int

DEFAULT_FOLDER = Path("checkpoints/bev")
"""Where ``--out`` defaults to ``<benchmark>_ae.pt`` (the path the BEV configurations read)."""


@cli_boundary
def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Pretrain one benchmark's BEV autoencoder (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.pretrain_bev", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", required=True, choices=PRETRAIN_BENCHMARKS,
                        help="training scenes of the random-policy rollouts")
    parser.add_argument("--out", type=Path, default=None,
                        help="autoencoder file to write, not a finished one (default checkpoints/bev/BENCHMARK_ae.pt)")
    parser.add_argument("--images", type=positive_int, default=PretrainConfig.images, help="images to collect")
    parser.add_argument("--epochs", type=positive_int, default=PretrainConfig.epochs, help="training epochs")
    parser.add_argument("--seed", type=non_negative_int, default=0,
                        help="seed of rollouts, split and training (default 0)")
    parser.add_argument("--threads", type=positive_int,
                        help="threads of torch and of the rollouts' numba loops (default: every core)")
    args = parser.parse_args(argv)
    if args.threads:
        use_threads(args.threads)
    config = PretrainConfig(benchmark=args.benchmark, images=args.images, epochs=args.epochs, seed=args.seed)
    out = args.out or DEFAULT_FOLDER / f"{args.benchmark}_ae.pt"
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = pretrain(config, out)
    print(f"{out}: held-out MSE {rows[-1]['held_out_mse']:.5f} after {len(rows)} epochs; {out.with_suffix('.png')}: "
          f"originals above reconstructions")
    return rows


if __name__ == "__main__":
    main()
