"""Shared pieces of the experiment CLIs: run folders, records, paper-style aggregation (spec §9)."""

from __future__ import annotations

import csv
import json
import numbers
import time
from pathlib import Path
from typing import Any

import numpy as np

from np_sim.cli import folder_problem
from np_sim.errors import ConfigError


def run_folder(experiment: str, out: Path | None) -> Path:
    """A fresh run folder, created: ``out`` when it does not exist yet or is empty (ConfigError when it is a file
    or holds an earlier run's files), else a new ``results/<experiment>/<timestamp>/`` (``-2``, ``-3`` … appended
    when that second's folder exists). An earlier run's results are never reused or overwritten."""
    if out is not None:
        problem = folder_problem(Path(out))
        if problem is not None:
            raise ConfigError(f"--out: {problem}")
        Path(out).mkdir(parents=True, exist_ok=True)
        return Path(out)
    stamp = Path("results") / experiment / time.strftime("%Y%m%d-%H%M%S")
    stamp.parent.mkdir(parents=True, exist_ok=True)
    folder, n = stamp, 1
    while True:
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            n += 1
            folder = stamp.with_name(f"{stamp.name}-{n}")


def first(items: list, limit: int | None, name: str = "--limit") -> list:
    """The first ``limit`` items (all of them for None); ConfigError for a limit that is not a positive integer (a
    negative slice would silently drop the last items instead)."""
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, numbers.Integral) or limit < 1):
        raise ConfigError(f"{name}: expected a positive integer (or none for all), got {limit!r}")
    return items[:limit]


def write_records(folder: Path, records: list[dict[str, Any]]) -> None:
    """``records.csv`` and ``records.json`` (one row per episode)."""
    if not records:
        raise ValueError("write_records: no records to write")
    with (folder / "records.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(records[0]))
        writer.writeheader()
        writer.writerows(records)
    (folder / "records.json").write_text(json.dumps(records, indent=1))


def mean_sd(values: list[float]) -> str:
    """'m ± s' with the sample SD over seeds ('m' alone for one seed)."""
    v = np.asarray(values, float)
    if len(v) == 0 or np.all(np.isnan(v)):
        return "–"
    if len(v) == 1:
        return f"{v[0]:.3f}"
    return f"{np.nanmean(v):.3f} ± {np.nanstd(v, ddof=1):.3f}"
