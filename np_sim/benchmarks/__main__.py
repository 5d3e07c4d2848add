"""``python -m np_sim.benchmarks --summary [--benchmark NAME] [--figure DIR]``: statistics and overview figures
of the shipped benchmark files (paper §IV-A); see `np_sim.benchmarks.summary`."""

from __future__ import annotations

import argparse
import sys

from np_sim.benchmarks.frozen import BENCHMARK_NAMES
from np_sim.benchmarks.summary import format_summary, summarize, write_figures
from np_sim.cli import cli_boundary, output_folder, positive_int


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m np_sim.benchmarks``."""
    parser = argparse.ArgumentParser(
        prog="python -m np_sim.benchmarks",
        description=(
            "Summarise the shipped Factorial Parking and Topology-Stress benchmarks (scene and per-cell counts, "
            "obstacle and boundary-segment counts, frozen-start geodesic distance per regime, route-blocked "
            "fraction per Topology-Stress family, structural-disjointness floor) and/or draw the held-out scenes "
            "with their frozen starts as PNGs."
        ),
        epilog="example: python -m np_sim.benchmarks --summary --figure docs/figures",
    )
    parser.add_argument("--summary", action="store_true", help="print the statistics")
    parser.add_argument("--benchmark", choices=[*BENCHMARK_NAMES, "all"], default="all",
                        help="benchmark to summarise and/or draw (default: all)")
    parser.add_argument("--figure", type=output_folder, default=None, metavar="DIR",
                        help="write factorial_test_{easy,medium,hard}.png and/or topology_test.png into DIR")
    parser.add_argument("--dpi", type=positive_int, default=110,
                        help="resolution of the PNGs in dots per inch (default 110)")
    return parser


@cli_boundary
def main(argv: list[str] | None = None) -> dict:
    """Run the CLI; returns ``{"summaries": [...], "figures": [paths]}``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.summary and args.figure is None:
        parser.error("nothing to do: give --summary and/or --figure DIR")
    result: dict = {"summaries": [], "figures": []}
    names = list(BENCHMARK_NAMES) if args.benchmark == "all" else [args.benchmark]
    if args.summary:
        for name in names:
            summary = summarize(name)
            result["summaries"].append(summary)
            print(format_summary(summary))
            print()
    if args.figure is not None:
        result["figures"] = write_figures(args.figure, dpi=args.dpi, benchmarks=tuple(names))
        for path in result["figures"]:
            print(f"wrote {path}")
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
