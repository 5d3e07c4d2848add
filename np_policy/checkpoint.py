"""NeuralParker checkpoints: weights, the complete training config and normalisation statistics (spec §6).

Format ``neuralparker-checkpoint-v2``: a ``torch.save`` file holding only tensors and plain data (dicts, lists,
tuples, str, int, float, bool, None), so it is read with ``torch.load(weights_only=True)`` and a crafted file
cannot run code; numpy arrays are stored as ``{"__ndarray__": tensor}``. The file also holds ``sha256``, a digest
of its whole content (every tensor's dtype, shape and bytes, every plain value; `payload_digest`), checked at
every load, so a flipped byte is reported rather than loaded. Every problem is a `CheckpointError` naming the file.

Files of the earlier format v1 (pickled numpy arrays, no digest) are refused by the loader; convert a v1 file you
trust with ``python -m np_policy.checkpoint upgrade FILE...``. Only that explicit command reads a file with
``weights_only=False`` (it unpickles arbitrary objects, so never run it on a file from an unknown source); it
rewrites the file as v2 atomically. ``python -m np_policy.checkpoint check FILE...`` loads and verifies files.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import os
import pickle
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import torch

from np_sim.errors import NPSimError
from np_sim.vehicle import VehicleSpec

CHECKPOINT_FORMAT = "neuralparker-checkpoint-v2"
LEGACY_FORMAT = "neuralparker-checkpoint-v1"
UPGRADE_COMMAND = "python -m np_policy.checkpoint upgrade"
_NDARRAY = "__ndarray__"
_RESERVED = ("format", "sha256")


class CheckpointError(NPSimError, ValueError):
    """A checkpoint file is missing, unreadable, of another format, corrupted, or does not match what uses it."""


# ------------------------------------------------------------------------------------------------ atomic files
def write_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` so that a reader (or a crash) sees the old file or the new one, never a part:
    a temporary file in the same folder, flushed and fsynced, then renamed over ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


# ------------------------------------------------------------------------------------------------ plain data
def _encode(obj: Any, where: str) -> Any:
    """``obj`` with numpy arrays as ``{"__ndarray__": tensor}`` and numpy scalars as Python numbers; anything
    that is not a tensor or plain data is an error naming its key path."""
    if isinstance(obj, torch.Tensor):
        return obj.detach().cpu()
    if isinstance(obj, np.ndarray):
        return {_NDARRAY: torch.from_numpy(np.ascontiguousarray(obj).copy())}
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, dict):
        return {key: _encode(value, f"{where}.{key}") for key, value in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(_encode(value, f"{where}[{i}]") for i, value in enumerate(obj))
    if obj is None or isinstance(obj, (bool, int, float, str)):
        return obj
    raise CheckpointError(f"checkpoint entry {where}: {type(obj).__name__} is not storable; use tensors, numpy "
                          "arrays or plain data")


def _decode(obj: Any) -> Any:
    """Inverse of `_encode`."""
    if isinstance(obj, dict):
        if set(obj) == {_NDARRAY}:
            return obj[_NDARRAY].numpy()
        return {key: _decode(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(_decode(value) for value in obj)
    return obj


def _feed(h: Any, obj: Any) -> None:
    if isinstance(obj, torch.Tensor):
        t = obj.detach().cpu().contiguous()
        h.update(f"T{t.dtype}{tuple(t.shape)}:".encode())
        h.update(t.reshape(-1).view(torch.uint8).numpy().tobytes())
    elif isinstance(obj, dict):
        h.update(f"D{len(obj)}:".encode())
        for key in sorted(obj, key=repr):
            _feed(h, key)
            _feed(h, obj[key])
    elif isinstance(obj, (list, tuple)):
        h.update(f"{'L' if isinstance(obj, list) else 'U'}{len(obj)}:".encode())
        for value in obj:
            _feed(h, value)
    else:
        h.update(f"{type(obj).__name__}:{obj!r};".encode())


def payload_digest(payload: dict[str, Any]) -> str:
    """SHA-256 (hex) of an encoded payload: dict keys in sorted order, each tensor as dtype, shape and raw bytes,
    each plain value as its type name and ``repr`` (exact for floats), containers with their lengths."""
    h = hashlib.sha256()
    _feed(h, payload)
    return h.hexdigest()


# ------------------------------------------------------------------------------------------------ save / load
def save_checkpoint(path: str | Path, payload: dict[str, Any]) -> Path:
    """Write ``payload`` (must hold ``model`` and ``config``; tensors, numpy arrays and plain data) as a v2 file
    with its digest, atomically (`write_atomic`)."""
    path = Path(path)
    missing = [key for key in ("model", "config") if key not in payload]
    reserved = [key for key in _RESERVED if key in payload]
    if missing or reserved:
        raise CheckpointError(f"{path}: cannot save: payload lacks {missing} or holds reserved keys {reserved}")
    encoded = _encode(payload, "payload")
    buffer = io.BytesIO()
    torch.save({"format": CHECKPOINT_FORMAT, "sha256": payload_digest(encoded), **encoded}, buffer)
    return write_atomic(path, buffer.getvalue())


def _pickled_format(path: Path) -> str | None:
    """The format string found in the file's pickle stream, read as bytes (nothing is unpickled); None if none."""
    try:
        with zipfile.ZipFile(path) as archive:
            name = next(n for n in archive.namelist() if n.endswith("data.pkl"))
            data = archive.read(name)
    except Exception:  # not a zip, no pickle inside: no format to report
        return None
    return next((f for f in (LEGACY_FORMAT, CHECKPOINT_FORMAT) if f.encode() in data), None)


def _legacy_error(path: Path) -> CheckpointError:
    return CheckpointError(f"{path}: format {LEGACY_FORMAT!r} is no longer loaded (it may hold pickled objects "
                           f"and has no digest); if you trust the file, convert it with `{UPGRADE_COMMAND} {path}`")


def _read(path: Path) -> dict[str, Any]:
    """The raw v2 dict of ``path`` (``weights_only=True``), format checked."""
    if not path.exists():
        raise CheckpointError(f"{path}: checkpoint file not found")
    if not path.is_file():
        raise CheckpointError(f"{path}: expected a checkpoint file, found a directory or special file")
    try:
        raw = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        if _pickled_format(path) == LEGACY_FORMAT:
            raise _legacy_error(path) from exc
        if not zipfile.is_zipfile(path):
            raise CheckpointError(f"{path}: not a readable checkpoint (not a torch.save zip file)") from exc
        reason = [line for line in str(exc).splitlines() if "GLOBAL" in line or "WeightsUnpickler" in line]
        reason = reason or [type(exc).__name__]
        raise CheckpointError(f"{path}: refused: it holds objects other than tensors and plain data (nothing in "
                              f"it was run; {reason[0].strip()})") from exc
    except Exception as exc:  # torch raises many types for truncated or foreign files
        raise CheckpointError(f"{path}: not a readable checkpoint ({type(exc).__name__}: {exc})") from exc
    found = raw.get("format") if isinstance(raw, dict) else type(raw).__name__
    if found == LEGACY_FORMAT:
        raise _legacy_error(path)
    if found != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path}: expected format {CHECKPOINT_FORMAT!r}, found {found!r}")
    return raw


def load_checkpoint(path: str | Path, expected_config: dict[str, Any] | None = None) -> dict[str, Any]:
    """Read a v2 checkpoint; CheckpointError naming the file and the problem when it is missing, unreadable, of
    another format, holds anything but tensors and plain data, fails its SHA-256, lacks ``model`` (a dict of
    tensors) or ``config``, or (with ``expected_config``) was trained under a different config — every differing
    field is listed. Returns the payload with numpy arrays restored."""
    path = Path(path)
    raw = _read(path)
    stored = raw.pop("sha256", None)
    raw.pop("format")
    computed = payload_digest(raw)
    if stored != computed:
        raise CheckpointError(f"{path}: content does not match its SHA-256 (stored {str(stored)[:16]}…, computed "
                              f"{computed[:16]}…): the file is corrupted or was modified")
    payload = _decode(raw)
    for key, kind in (("model", dict), ("config", dict)):
        if not isinstance(payload.get(key), kind):
            raise CheckpointError(f"{path}: expected a {key!r} entry holding a dict, found "
                                  f"{type(payload.get(key)).__name__}")
    bad = sorted(k for k, v in payload["model"].items() if not isinstance(v, torch.Tensor))
    if bad:
        raise CheckpointError(f"{path}: model entries {bad} are not tensors")
    if expected_config is not None:
        check_config(path, expected_config, payload["config"])
    return payload


# ------------------------------------------------------------------------------------------------ checks
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


def check_config(path: str | Path, expected: dict[str, Any], stored: dict[str, Any]) -> None:
    """CheckpointError naming ``path`` and every field where the checkpoint's ``stored`` config differs from
    ``expected``."""
    diffs = config_differences(expected, stored)
    if diffs:
        raise CheckpointError(f"{path}: checkpoint config differs from the expected one:\n  " + "\n  ".join(diffs))


def describe_layout(observation: dict[str, Any]) -> str:
    """One line naming an observation layout (``np_sim.config.ObservationConfig`` as a dict)."""
    o = observation
    lidar = f"LiDAR {o.get('n_beams')} beams to {o.get('lidar_range_m')} m" if o.get("use_lidar") else "no LiDAR"
    obstacles = (f"{o.get('max_obstacles')} obstacles x {o.get('vertices_per_obstacle')} vertices"
                 if o.get("use_obstacles") else "no obstacle slots")
    boundary = f"{o.get('max_boundary_segments')} boundary segments" if o.get("use_boundary") else "no boundary slots"
    bev = f", BEV latent {o.get('bev_latent_dim')} from {o.get('bev_encoder_file')}" if o.get("use_bev") else ""
    return f"{obstacles}, {boundary}, {lidar}{bev}"


def check_layout(path: str | Path, stored: dict[str, Any], expected: dict[str, Any], stored_name: str,
                 expected_name: str) -> None:
    """CheckpointError naming ``path`` and both layouts when the checkpoint's observation layout ``stored``
    (trained on ``stored_name``) is not ``expected`` (that of ``expected_name``): its network reads another
    observation vector, so it cannot plan those scenes."""
    diffs = config_differences(expected, stored)
    if diffs:
        raise CheckpointError(
            f"{path}: its observation layout ({stored_name}: {describe_layout(stored)}) is not the one of "
            f"{expected_name} ({describe_layout(expected)}); use a checkpoint trained for {expected_name}. "
            "Differing fields:\n  " + "\n  ".join(f"observation.{d}" for d in diffs))


def check_vehicle(path: str | Path, trained: VehicleSpec, vehicle: VehicleSpec) -> None:
    """CheckpointError naming ``path`` and both vehicles when the policy in ``path`` was trained for ``trained``
    and is asked to plan for another ``vehicle``: its actions are scaled by the trained κ_max and its LiDAR
    clearances and checks use the trained footprint (spec §3)."""
    if trained != vehicle:
        raise CheckpointError(f"{path}: trained for the vehicle {trained.describe()}, refused for the vehicle "
                              f"{vehicle.describe()}; plan with a policy trained for this vehicle "
                              "(python -m np_policy.train --vehicle ...) or pass the vehicle it was trained for")


def load_weights(module: torch.nn.Module, state: dict[str, Any], path: str | Path, what: str = "model") -> None:
    """``module.load_state_dict(state)``, or a CheckpointError naming ``path`` and every missing or unexpected key
    and every shape that differs between the checkpoint and the network built from its config."""
    own = module.state_dict()
    problems = [f"missing keys {sorted(set(own) - set(state))}"] if set(own) - set(state) else []
    if set(state) - set(own):
        problems.append(f"unexpected keys {sorted(set(state) - set(own))}")
    for key in sorted(set(own) & set(state)):
        theirs = tuple(state[key].shape) if isinstance(state[key], torch.Tensor) else type(state[key]).__name__
        if theirs != tuple(own[key].shape):
            problems.append(f"{key}: checkpoint shape {theirs}, network shape {tuple(own[key].shape)}")
    if problems:
        raise CheckpointError(f"{path}: the {what} weights do not fit the network built from its config: "
                              + "; ".join(problems))
    module.load_state_dict(state)


# ------------------------------------------------------------------------------------------------ CLI
def upgrade_checkpoint(path: str | Path) -> bool:
    """Rewrite a v1 file as v2 (atomically) after checking that the v2 file reads back to the same content.
    True if upgraded, False if it already was v2. Reads the v1 file with ``weights_only=False``: it runs
    whatever the file's pickle holds, so use it on files you trust only."""
    path = Path(path)
    try:
        load_checkpoint(path)
        return False
    except CheckpointError:
        if _pickled_format(path) != LEGACY_FORMAT:
            raise
    try:
        old = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # torch raises many types for truncated or foreign files
        raise CheckpointError(f"{path}: not a readable v1 checkpoint ({type(exc).__name__}: {exc})") from exc
    if not isinstance(old, dict) or old.get("format") != LEGACY_FORMAT:
        raise CheckpointError(f"{path}: expected format {LEGACY_FORMAT!r} to upgrade")
    payload = {k: v for k, v in old.items() if k != "format"}
    staged = save_checkpoint(path.with_name(path.name + ".v2.tmp"), payload)
    try:
        back = load_checkpoint(staged)
        if payload_digest(_encode(back, "payload")) != payload_digest(_encode(payload, "payload")):
            raise CheckpointError(f"{path}: the upgraded file does not read back to the same content; left as v1")
        os.replace(staged, path)
    finally:
        staged.unlink(missing_ok=True)
    return True


def main(argv: list[str] | None = None) -> int:
    """``upgrade FILE...`` (v1 → v2, trusted files only) or ``check FILE...`` (load and verify)."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.checkpoint", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=("upgrade", "check"),
                        help="upgrade: rewrite trusted v1 files as v2; check: load and verify v2 files")
    parser.add_argument("files", type=Path, nargs="+", help="checkpoint files")
    args = parser.parse_args(argv)
    try:
        for path in args.files:
            if args.command == "check":
                payload = load_checkpoint(path)
                print(f"{path}: ok ({CHECKPOINT_FORMAT}, epoch {payload.get('epoch')})")
            else:
                print(f"{path}: {'upgraded to' if upgrade_checkpoint(path) else 'already'} {CHECKPOINT_FORMAT}")
    except CheckpointError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
