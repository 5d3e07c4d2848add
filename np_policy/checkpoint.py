"""NeuralParker checkpoints: weights, the complete training config and normalisation statistics (SPEC §6).

Loading checks the file and, when an expected config is given, names every field that differs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch

from np_sim.errors import NPSimError

CHECKPOINT_FORMAT = "neuralparker-checkpoint-v1"


class CheckpointError(NPSimError, ValueError):
    """A checkpoint file is missing, unreadable, of another format, or does not match the expected config."""


def save_checkpoint(path: str | Path, payload: dict[str, Any]) -> Path:
    """Write ``payload`` (must hold ``model``, ``config``) atomically to ``path`` (temporary file + rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save({"format": CHECKPOINT_FORMAT, **payload}, tmp)
    tmp.replace(path)
    return path


def _diff(expected: Any, got: Any, where: str) -> list[str]:
    if isinstance(expected, dict) and isinstance(got, dict):
        out = []
        for key in sorted(set(expected) | set(got)):
            sub = f"{where}.{key}" if where else key
            if key not in got:
                out.append(f"{sub}: missing in the checkpoint (expected {expected[key]!r})")
            elif key not in expected:
                out.append(f"{sub}: unexpected in the checkpoint ({got[key]!r})")
            else:
                out.extend(_diff(expected[key], got[key], sub))
        return out
    if isinstance(expected, (list, tuple)) and isinstance(got, (list, tuple)):
        expected, got = list(expected), list(got)
    return [] if expected == got else [f"{where}: checkpoint has {got!r}, expected {expected!r}"]


def config_differences(expected: dict[str, Any], got: dict[str, Any]) -> list[str]:
    """Field paths (``env.connector.mode: checkpoint has 'fixed', expected 'ensemble'``) where two configs differ."""
    return _diff(expected, got, "")


def load_checkpoint(path: str | Path, expected_config: dict[str, Any] | None = None) -> dict[str, Any]:
    """Read a checkpoint; CheckpointError naming the file and the problem when it is missing, corrupted, of
    another format, or (with ``expected_config``) trained under a different config — every differing field is
    listed."""
    path = Path(path)
    if not path.exists():
        raise CheckpointError(f"{path}: checkpoint file not found")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # torch raises many types for truncated or foreign files
        raise CheckpointError(f"{path}: not a readable checkpoint ({type(exc).__name__}: {exc})") from exc
    if not isinstance(payload, dict) or payload.get("format") != CHECKPOINT_FORMAT:
        found = payload.get("format") if isinstance(payload, dict) else type(payload).__name__
        raise CheckpointError(f"{path}: expected format {CHECKPOINT_FORMAT!r}, found {found!r}")
    for key in ("model", "config"):
        if key not in payload:
            raise CheckpointError(f"{path}: checkpoint lacks the {key!r} entry")
    if expected_config is not None:
        check_config(path, expected_config, payload["config"])
    return payload


def check_config(path: str | Path, expected: dict[str, Any], stored: dict[str, Any]) -> None:
    """CheckpointError naming ``path`` and every field where the checkpoint's ``stored`` config differs from
    ``expected``."""
    diffs = config_differences(expected, stored)
    if diffs:
        raise CheckpointError(f"{path}: checkpoint config differs from the expected one:\n  " + "\n  ".join(diffs))
