"""Which code and machine made a result: the git commit of this checkout, the Python files edited since it and the
CPU and numeric libraries it ran on; for a long run that is resumed, one line per start (``provenance.jsonl``)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any

PROVENANCE_FILE = "provenance.jsonl"
"""A training run's log of its starts and resumes (`record_start`)."""

REPO_ROOT = Path(__file__).resolve().parents[1]
"""The checkout this package runs from (git is asked about it, whatever the working directory)."""


def _git(*args: str) -> str | None:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, check=True, cwd=REPO_ROOT).stdout
    except (OSError, subprocess.CalledProcessError):
        return None


def git_commit() -> str:
    """The current git commit, or 'unknown' outside a checkout."""
    out = _git("rev-parse", "HEAD")
    return out.strip() if out else "unknown"


def git_state() -> dict[str, Any]:
    """Which code made a result, for its ``config.json``: ``git_commit`` and ``git_modified``, the Python files of
    the working tree that are not as in that commit (edited, or new and not ignored): a result made from edited code
    cannot be reproduced from the commit alone; an empty list says it can. Outside a checkout: 'unknown' and None."""
    commit = git_commit()
    edited = _git("diff", "HEAD", "--name-only", "--", "*.py") if commit != "unknown" else None
    new = _git("ls-files", "--others", "--exclude-standard", "--", "*.py") if edited is not None else None
    modified = None if edited is None or new is None else sorted({*edited.splitlines(), *new.splitlines()})
    return {"git_commit": commit, "git_modified": modified}


NUMERIC_PACKAGES = ("numpy", "numba", "torch", "mujoco")
"""Libraries whose floating point a result depends on (`machine_state` records their versions)."""


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def machine_state() -> dict[str, Any]:
    """The machine a result was made on: CPU model, the CPU numba's kernels are compiled for (``llvm_cpu``), core
    count, Python and the numeric libraries' versions. Float results (numba, MuJoCo, torch) can differ in their last
    digits between CPUs, and a closed-loop run that grazes a clearance margin can then end otherwise (one held-out
    clip did: ``docs/results/2026-12-07-lazy-heuristic``)."""
    import llvmlite.binding

    return {"cpu": _cpu_model(), "llvm_cpu": llvmlite.binding.get_host_cpu_name(), "cores": os.cpu_count(),
            "python": platform.python_version(), "packages": {name: _version(name) for name in NUMERIC_PACKAGES}}


def provenance() -> dict[str, Any]:
    """What a result's ``config.json`` records of its making: `git_state` and ``machine`` (`machine_state`)."""
    return {**git_state(), "machine": machine_state()}


def record_start(folder: Path, **fields: Any) -> None:
    """Append to ``folder/provenance.jsonl`` one line for this start or resume of a long run: the UTC time, the
    command line, ``fields`` (where the run starts, the threads it runs on), the code and the machine (`provenance`).
    A run resumed under other code, thread counts or machine shows it here."""
    line = {"started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "argv": sys.argv, **fields,
            **provenance()}
    with (Path(folder) / PROVENANCE_FILE).open("a", encoding="utf-8") as fh:
        fh.write(json.dumps(line) + "\n")
