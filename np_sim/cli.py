"""What every ``python -m`` CLI of the project shares: argument types that reject out-of-range values at parse time,
the check that an output folder is fresh, and the error boundary that turns a user's mistake into one line.

Argument types raise ``argparse.ArgumentTypeError``, so argparse prints
``<prog>: error: argument --limit: must be a positive integer, got -2`` and exits with status 2. The boundary
(`cli_boundary`, a decorator of a CLI's ``main(argv)``) does the same for what goes wrong after parsing because of
the user's input: the project's own errors (`np_sim.errors.NPSimError` and its subclasses: ``SceneError``,
``ConfigError``, ``CheckpointError``, ``TrackingError`` …) and an input file that is missing, a folder, or
unreadable print ``error: <message>`` to stderr and exit with status 2, without a traceback. Any other exception
is a bug and propagates with its traceback.
"""

from __future__ import annotations

import argparse
import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from np_sim.errors import NPSimError

USER_ERRORS = (NPSimError, FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError,
               PermissionError)
"""Exceptions the boundary reports as a user's mistake: the project's own errors and unusable input files."""


def _number(text: str, kind: Callable[[str], Any], what: str) -> Any:
    """``text`` parsed by ``kind`` (int or float), or an ArgumentTypeError naming ``what`` was expected."""
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}") from None
    if kind is float and value != value:  # NaN passes every comparison below
        raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (``--limit``, ``--steps``, ``--workers`` …); '2.5', '0' and '-2' are refused."""
    value = _number(text, int, "a positive integer")
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def non_negative_int(text: str) -> int:
    """An integer >= 0 (seeds, counts where 0 means none)."""
    value = _number(text, int, "a non-negative integer")
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a non-negative integer, got {text}")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (durations, scales)."""
    value = _number(text, float, "a positive number")
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def non_negative_float(text: str) -> float:
    """A finite number >= 0 (margins and clearances in metres)."""
    value = _number(text, float, "a non-negative number")
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a non-negative number, got {text}")
    return value


def probability(text: str) -> float:
    """A number in [0, 1]."""
    value = _number(text, float, "a probability in [0, 1]")
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"must be a probability in [0, 1], got {text}")
    return value


def existing_file(text: str) -> Path:
    """The path of a file that exists (a missing path or a folder is refused at parse time)."""
    path = Path(text)
    if not path.exists():
        raise argparse.ArgumentTypeError(f"no such file: {text}")
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"expected a file, got the folder {text}")
    return path


def vehicle_spec(text: str):
    """A vehicle: a preset name ('sedan', 'van') or a vehicle JSON file (`np_sim.vehicle.load_vehicle`); a bad
    file is refused at parse time with its file and field."""
    from np_sim.vehicle import load_vehicle

    try:
        return load_vehicle(text)
    except NPSimError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def output_folder(text: str) -> Path:
    """A folder to write into, created when missing (an existing file is refused at parse time)."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file; expected a folder")
    return path


def folder_problem(path: Path) -> str | None:
    """Why ``path`` cannot be a fresh output folder (it is a file, or a folder with something in it); None when
    it does not exist yet or is an empty folder."""
    if path.exists() and not path.is_dir():
        return f"{path} is a file; expected a new or empty folder"
    if path.is_dir() and any(path.iterdir()):
        return (f"{path} exists and is not empty (an earlier run's results are kept); give a new or empty folder, "
                f"or omit --out for a fresh timestamped one")
    return None


def fresh_folder(text: str) -> Path:
    """An output folder that does not exist yet or is empty (an earlier run is never reused or overwritten)."""
    problem = folder_problem(Path(text))
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return Path(text)


def report_user_error(error: BaseException) -> None:
    """Print ``error: <message>`` to stderr and exit with status 2 (the boundary's one line)."""
    print(f"error: {error}", file=sys.stderr)
    raise SystemExit(2)


def cli_boundary(main: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate a CLI's ``main(argv=None)``: `USER_ERRORS` become one ``error:`` line on stderr and exit status 2;
    everything else (bugs) propagates unchanged."""

    @functools.wraps(main)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return main(*args, **kwargs)
        except USER_ERRORS as error:
            report_user_error(error)

    return wrapper
