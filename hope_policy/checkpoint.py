"""Adapted-HOPE checkpoints: weights, the full training config and the observation statistics (paper App.
``app:hope-adaptation``: "the training statistics are stored with each checkpoint and restored for evaluation").

The file format is the project's (`np_policy.checkpoint`: ``torch.save`` of tensors and plain data only, read with
``weights_only=True``, a SHA-256 of the content checked at every load, written atomically); an adapted-HOPE file is
marked by ``policy: "hope"`` so a NeuralParker checkpoint given where a HOPE one is expected (or the reverse) is one
clear error.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from np_policy.checkpoint import CheckpointError, load_checkpoint, save_checkpoint

POLICY = "hope"
"""The ``policy`` entry of every adapted-HOPE checkpoint."""
REQUIRED = ("obs_norm", "episodes", "updates")
"""Entries besides ``model`` and ``config`` that every adapted-HOPE checkpoint holds."""


def save_hope_checkpoint(path: str | Path, payload: dict[str, Any]) -> Path:
    """Write ``payload`` (``model``, ``config``, ``obs_norm``, counters, optionally the training state) with the
    ``policy`` mark, atomically and with its digest (`np_policy.checkpoint.save_checkpoint`)."""
    return save_checkpoint(path, {**payload, "policy": POLICY})


def load_hope_checkpoint(path: str | Path) -> dict[str, Any]:
    """Read and verify an adapted-HOPE checkpoint; CheckpointError naming the file when it is not readable, fails
    its digest, is another policy's checkpoint or lacks an entry of `REQUIRED`."""
    payload = load_checkpoint(path)
    if payload.get("policy") != POLICY:
        raise CheckpointError(f"{path}: expected an adapted-HOPE checkpoint (policy {POLICY!r}), found policy "
                              f"{payload.get('policy', 'neuralparker')!r}")
    missing = [key for key in REQUIRED if key not in payload]
    if missing:
        raise CheckpointError(f"{path}: adapted-HOPE checkpoint lacks {missing}")
    return payload
