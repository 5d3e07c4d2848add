"""Regenerate the shipped benchmark files from their fixed seeds (paper §IV-A, spec §4.1–4.3).

``python -m np_sim.benchmarks.generate [--benchmark factorial|topology|all] [--out DIR] [--check]``

Writes ``<name>_v1.json`` (default: into the package's ``data/`` folder) and prints the generation time and the
rejection counts per check. ``--check`` writes nothing: it regenerates in memory and compares the text byte for
byte with the shipped file, exiting with status 1 on any difference.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable

from tqdm import tqdm

from np_sim.benchmarks.factorial import FactorialConfig, generate_factorial
from np_sim.benchmarks.frozen import BENCHMARK_NAMES, DATA_DIR, BenchmarkBuild, benchmark_json, benchmark_path
from np_sim.benchmarks.topology import TopologyConfig, generate_topology
from np_sim.cli import cli_boundary, output_folder
from np_sim.errors import ConfigError
from np_sim.scene import Scene


def scene_count(name: str) -> int:
    """Total scenes (train + test) benchmark ``name`` generates with its default config."""
    if name == "factorial":
        cfg = FactorialConfig()
        return 27 * (cfg.n_train_per_cell + cfg.n_test_per_cell)
    if name == "topology":
        cfg_t = TopologyConfig()
        return 6 * (cfg_t.n_train_per_cell + cfg_t.n_test_per_cell)
    raise ConfigError(f"scene_count: unknown benchmark {name!r}; expected one of {', '.join(BENCHMARK_NAMES)}")


def generate(name: str, on_scene: Callable[[Scene], None] | None = None) -> BenchmarkBuild:
    """Generate benchmark ``name`` ("factorial" | "topology") with its default (shipped) configuration."""
    if name == "factorial":
        return generate_factorial(on_scene=on_scene)
    if name == "topology":
        return generate_topology(on_scene=on_scene)
    raise ConfigError(f"generate: unknown benchmark {name!r}; expected one of {', '.join(BENCHMARK_NAMES)}")


def format_rejections(build: BenchmarkBuild) -> str:
    """One line per rejection counter, e.g. ``  connected_start        3``."""
    return "\n".join(f"  {key:<22} {count:>5}" for key, count in sorted(build.rejections.items()))


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m np_sim.benchmarks.generate``."""
    parser = argparse.ArgumentParser(
        prog="python -m np_sim.benchmarks.generate",
        description=(
            "Regenerate the Factorial Parking and Topology-Stress benchmark files (scenes + 40 frozen starts per "
            "test scene) from their fixed seeds, with a progress bar; prints the time and the number of rejected "
            "draws per validity check. --check compares with the shipped files instead of writing."
        ),
    )
    parser.add_argument("--benchmark", choices=[*BENCHMARK_NAMES, "all"], default="all",
                        help="which benchmark to generate (default: all)")
    parser.add_argument("--out", type=output_folder, default=None, metavar="DIR",
                        help=f"folder to write <name>_v1.json into (default: the shipped data folder {DATA_DIR})")
    parser.add_argument("--check", action="store_true",
                        help="regenerate in memory and verify byte equality with the shipped files (exit 1 if not)")
    return parser


@cli_boundary
def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit status (0, or 1 when ``--check`` finds a difference)."""
    args = build_parser().parse_args(argv)
    names = list(BENCHMARK_NAMES) if args.benchmark == "all" else [args.benchmark]
    status = 0
    for name in names:
        start = time.perf_counter()
        with tqdm(total=scene_count(name), desc=name, unit="scene") as bar:
            build = generate(name, on_scene=lambda _scene: bar.update())
        text = benchmark_json(build)
        elapsed = time.perf_counter() - start
        print(f"{name}: {len(build.train)} train + {len(build.test)} test scenes, "
              f"{build.frozen_starts.shape[0] * build.frozen_starts.shape[1]} frozen starts in {elapsed:.1f} s")
        print(f"{name}: rejected draws per check:\n{format_rejections(build)}")
        print(f"{name}: min test-to-train layout distance {build.nearest_train_m.min():.2f} m "
              f"(floor {build.floor_m:.2f} m)")
        if args.check:
            shipped = benchmark_path(name)
            if shipped.exists() and shipped.read_bytes() == text.encode("utf-8"):
                print(f"{name}: OK, identical to {shipped}")
            else:
                print(f"{name}: DIFFERS from {shipped} (regenerate with python -m np_sim.benchmarks.generate)")
                status = 1
        else:
            path = benchmark_path(name, args.out)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(text.encode("utf-8"))
            print(f"{name}: wrote {path}")
    return status


if __name__ == "__main__":
    sys.exit(main())
