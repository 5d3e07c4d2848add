"""Throughput of the BEV raster (`np_sim.bev.render_bev_batch`): ``python -m np_sim.bench_bev [--benchmark topology]
[--repeats 5] [--json]``.

Renders one image per validation start of the benchmark's training scenes (`validation_starts`), without a
trajectory tail (the NeuralParker BEV observation) and with a random tail of up to 25 earlier poses (the HOPE-style
BEV row draws up to 20 footprints of it), on one numba thread, and prints images per second beside the figure to
beat: the raster before its spans were written by an insertion-sorted scanline loop, measured on this 2-core
machine with nothing else running (`BEFORE_IMAGES_PER_S`). Run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from np_sim.benchmarks import load_benchmark, validation_starts
from np_sim.bev import render_bev_batch
from np_sim.cli import cli_boundary, positive_int
from np_sim.scene_arrays import pack_scenes

BEFORE_IMAGES_PER_S = {("topology", False): 7600.0, ("topology", True): 4800.0,
                       ("factorial", False): 5100.0, ("factorial", True): 3200.0}
"""Images per second of the raster at commit 9de3745 (crossings sorted by ``ndarray.sort``, spans written as
slices), one thread, this machine idle (training runs stopped), 2026-12-08: the figure to beat, per (benchmark,
with a tail). The insertion-sorted loop measured 10,600 / 10,600 (Topology-Stress, without / with a tail) and
12,100 / 10,000 (Factorial) images/s in the same minute, bit for bit the same images."""


def measure(benchmark: str = "topology", repeats: int = 5, seed: int = 0) -> list[dict]:
    """Images per second of ``render_bev_batch`` on the validation starts of ``benchmark``, without and with a
    random trajectory tail (module docstring); the best of ``repeats`` batches after one warm-up batch."""
    import numba

    numba.set_num_threads(1)
    arrays = pack_scenes(load_benchmark(benchmark, "train"))
    starts = validation_starts(benchmark)
    index = np.repeat(np.arange(starts.shape[0]), starts.shape[1])
    poses = starts.reshape(-1, 3)
    rng = np.random.default_rng(seed)
    tails = poses[:, None, :] + np.cumsum(rng.normal(0.0, [0.5, 0.5, 0.1], (len(poses), 25, 3)), axis=1)
    n_tail = rng.integers(0, 26, len(poses))
    rows = []
    for tail in (False, True):
        args = (arrays, index, poses) + ((tails, n_tail) if tail else ())
        render_bev_batch(*args)
        best = float("inf")
        for _ in range(repeats):
            start = time.perf_counter()
            render_bev_batch(*args)
            best = min(best, time.perf_counter() - start)
        rows.append({"benchmark": benchmark, "tail": tail, "images": len(poses), "images_per_s": len(poses) / best,
                     "to_beat": BEFORE_IMAGES_PER_S[(benchmark, tail)]})
    return rows


@cli_boundary
def main(argv=None) -> list[dict]:
    """CLI entry point (module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m np_sim.bench_bev", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=("topology", "factorial"), default="topology",
                        help="whose training scenes and validation starts to render")
    parser.add_argument("--repeats", type=positive_int, default=5, help="timed batches; the best counts")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON instead of a table")
    args = parser.parse_args(argv)
    rows = measure(args.benchmark, args.repeats)
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"BEV raster, {rows[0]['images']} images of {args.benchmark} validation starts, one thread")
        for row in rows:
            print(f"  {'with' if row['tail'] else 'no'} tail: {row['images_per_s']:8.0f} images/s   "
                  f"(to beat: {row['to_beat']:.0f}, {row['images_per_s'] / row['to_beat']:.1f}×)")
    return rows


if __name__ == "__main__":
    main()
