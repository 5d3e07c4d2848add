"""Episode-by-episode progress of a long evaluation, so a killed run continues where it stopped.

An evaluation that takes an hour (the sampled adapted-HOPE episodes of a Topology-Stress backbone) used to lose all
of it to a kill: its records were written at the end only. `EpisodeProgress` appends each finished episode's
record rows to ``progress.jsonl`` in the run folder (one JSON line per episode, flushed) beside
``progress_settings.json``, the settings the run was started with. Resuming reads both: the settings must be the
same (a ConfigError names the ones that differ), the episodes already there are not planned again, and a torn last
line (a kill in the middle of a write) is dropped. NeuralParker and the adapted HOPE seed every random choice per
episode, so their resumed records equal an uninterrupted run's (searches with a wall-time budget, and OMPL's
generator seeded once per run, are as repeatable as a fresh run). Once the run writes its records the two files are
removed (`EpisodeProgress.write_results`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any, Callable

from experiments.common import run_folder, write_records
from np_sim.cli import folder_problem
from np_sim.errors import ConfigError
from np_sim.provenance import provenance

PROGRESS_FILE = "progress.jsonl"
SETTINGS_FILE = "progress_settings.json"


def holds_progress(folder: Path) -> bool:
    """Whether ``folder`` holds an interrupted run's progress (it can be resumed)."""
    return (Path(folder) / SETTINGS_FILE).exists()


def check_out(parser: argparse.ArgumentParser, out: Path | None, resume: bool) -> None:
    """A CLI's ``--out`` must be a new or empty folder, or with ``--resume`` one that holds an interrupted run
    (argparse's usage error otherwise)."""
    if out is None:
        if resume:
            parser.error("argument --resume: needs --out, the folder of the interrupted run")
        return
    problem = folder_problem(out)
    if problem is not None and not (resume and out.is_dir() and holds_progress(out)):
        parser.error(f"argument --out: {problem}" + (" (and it holds no interrupted run to resume)" if resume else ""))


def progress_folder(experiment: str, out: Path | None, resume: bool) -> Path:
    """The run folder: ``out`` when resuming the interrupted run it holds, else a fresh one (`run_folder`)."""
    if resume and out is not None and holds_progress(out):
        return Path(out)
    return run_folder(experiment, out)


class EpisodeProgress:
    """The finished episodes of a run in ``folder`` started with ``settings`` (plain JSON data): their rows by
    episode key, and the file new ones are appended to."""

    def __init__(self, folder: Path, settings: dict[str, Any], resume: bool):
        self.folder = Path(folder)
        self.done: dict[tuple, list[dict[str, Any]]] = {}
        settings = json.loads(json.dumps(settings, default=str))  # as stored, so a resumed run compares equal
        if resume and holds_progress(self.folder):
            stored = json.loads((self.folder / SETTINGS_FILE).read_text())
            differ = sorted(k for k in {*stored, *settings} if stored.get(k) != settings.get(k))
            if differ:
                raise ConfigError(f"--resume: {self.folder} was started with other settings: "
                                  + "; ".join(f"{k}: {stored.get(k)!r}, now {settings.get(k)!r}" for k in differ))
            self.done = self._read()
        else:
            (self.folder / SETTINGS_FILE).write_text(json.dumps(settings, indent=1))
        self._file = (self.folder / PROGRESS_FILE).open("a")

    def _read(self) -> dict[tuple, list[dict[str, Any]]]:
        path = self.folder / PROGRESS_FILE
        lines = path.read_text().splitlines(keepends=True) if path.exists() else []
        if lines and not lines[-1].endswith("\n"):  # torn by a kill mid-write: that episode is planned again
            lines = lines[:-1]
            path.write_text("".join(lines))
        entries = [json.loads(line) for line in lines]
        return {tuple(entry["episode"]): entry["rows"] for entry in entries}

    def add(self, episode: tuple, rows: list[dict[str, Any]]) -> None:
        """Record one finished episode's rows."""
        self._file.write(json.dumps({"episode": list(episode), "rows": rows}) + "\n")
        self._file.flush()
        self.done[tuple(episode)] = rows

    def rows(self, episode: tuple, plan: Callable[[], list[dict[str, Any]]]) -> list[dict[str, Any]]:
        """The rows of ``episode``: kept from before the interruption, else ``plan()``'s, recorded as it returns."""
        kept = self.done.get(tuple(episode))
        if kept is not None:
            return kept
        rows = plan()
        self.add(episode, rows)
        return rows

    def write_results(self, records: list[dict[str, Any]], table: str, config: dict[str, Any]) -> None:
        """The finished run's files — ``records.csv``/``.json``, ``table.md``, and ``config.json`` holding ``config``
        and the code and machine that made them (`provenance`) — then the progress files are removed."""
        write_records(self.folder, records)
        (self.folder / "table.md").write_text(table + "\n")
        (self.folder / "config.json").write_text(json.dumps({**config, **provenance()}, indent=2, default=str))
        self.finish()

    def finish(self) -> None:
        """The run's records are written: remove the progress files."""
        self._file.close()
        for name in (PROGRESS_FILE, SETTINGS_FILE):
            (self.folder / name).unlink(missing_ok=True)
