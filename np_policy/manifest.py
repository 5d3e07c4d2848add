"""Manifest of the shipped checkpoints: for each file, the training run it came from and its SHA-256.

``checkpoints/MANIFEST.json`` lists every ``.pt`` file under ``checkpoints/`` except the runs' ``snapshot.pt``
files, an unfinished autoencoder pretraining's ``<name>.snapshot.pt`` and the ``best.pt`` of runs that can still be
resumed (they hold a ``snapshot.pt``, so their ``best.pt`` changes when training goes on; those runs are listed by
folder under ``resumable_runs``). Each entry records:

- ``run``: the run folder (``checkpoints/runs/<run>``) whose ``best.pt`` the file is or is a copy of — a copy is
  found by the SHA-256 of its bytes, else by equal weights and epoch (``copy_of`` names that ``best.pt``);
- ``epoch``: the training epoch of the weights (stored in the checkpoint);
- ``config``: the run's ``config.json``, the training config the checkpoint also stores;
- ``sha256`` and ``size_bytes`` of the file, and ``format``, the checkpoint format version
  (`np_policy.checkpoint.CHECKPOINT_FORMAT`; every file is loaded, so its content digest is verified too).

A pretrained BEV autoencoder (``checkpoints/bev/<benchmark>_ae.pt``, `np_policy.bev_encoder`) comes from no training
run: its entry holds ``kind``, its ``pretraining`` config, ``epochs``, the final ``held_out_mse``, ``sha256``,
``size_bytes`` and ``format``.

``python -m np_policy.manifest build`` writes the manifest from the files; ``python -m np_policy.manifest check``
rebuilds it and reports every difference with the committed one (exit status 2), e.g. a checkpoint replaced
without rebuilding the manifest, a new shipped file, or a run that finished since.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path
from typing import Any

import torch

from np_policy.bev_encoder import KIND as AUTOENCODER_KIND
from np_policy.checkpoint import CHECKPOINT_FORMAT, CheckpointError, load_checkpoint, write_atomic
from np_sim.cli import cli_boundary

MANIFEST_FORMAT = "neuralparker-manifest-v1"
MANIFEST_FILE = "MANIFEST.json"
DEFAULT_ROOT = Path(__file__).resolve().parent.parent / "checkpoints"
"""The repository's ``checkpoints/`` folder."""
_ABOUT = "Shipped checkpoints and the runs they came from; `python -m np_policy.manifest check` verifies this file."


def file_sha256(path: Path) -> str:
    """SHA-256 (hex) of the bytes of ``path``."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def run_folders(root: Path) -> list[Path]:
    """The training run folders under ``root``: those holding a ``config.json`` and a ``metrics.jsonl``."""
    return sorted(p.parent for p in root.rglob("metrics.jsonl") if (p.parent / "config.json").is_file())


def shipped_files(root: Path) -> list[Path]:
    """Every ``.pt`` under ``root`` except snapshots and the ``best.pt`` of runs still holding a snapshot."""
    resumable = {run for run in run_folders(root) if (run / "snapshot.pt").exists()}
    return sorted(p for p in root.rglob("*.pt")
                  if p.name != "snapshot.pt" and not p.name.endswith(".snapshot.pt")  # a pretraining's snapshot
                  and not (p.name == "best.pt" and p.parent in resumable))


def _same_weights(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return (a.get("epoch") == b.get("epoch") and a["model"].keys() == b["model"].keys()
            and all(torch.equal(a["model"][k], b["model"][k]) for k in a["model"]))


RUN_OUTPUTS = ("best.pt", "final.pt")
"""What a finished run ships: NeuralParker's selected ``best.pt``, the adapted HOPE's ``final.pt`` (no selection)."""


def _source_run(path: Path, payload: dict[str, Any], runs: list[Path], digest: str) -> tuple[Path, Path | None]:
    """(run folder, the run output (`RUN_OUTPUTS`) ``path`` copies or None when it is one); a CheckpointError when
    no run's output has its bytes or weights, or more than one does."""
    if path.name in RUN_OUTPUTS and path.parent in runs:
        return path.parent, None
    bests = [run / name for run in runs for name in RUN_OUTPUTS if (run / name).is_file()]
    found = [b for b in bests if file_sha256(b) == digest]
    if not found:
        found = [b for b in bests if _same_weights(payload, load_checkpoint(b))]
    if len(found) != 1:
        where = "no run's best.pt" if not found else f"{len(found)} runs' best.pt ({', '.join(map(str, found))})"
        raise CheckpointError(f"{path}: {where} has its SHA-256 or its weights and epoch, so the manifest cannot "
                              "name the run it came from; ship a copy of one run's best.pt")
    return found[0].parent, found[0]


def autoencoder_entry(payload: dict[str, Any], digest: str, size: int) -> dict[str, Any]:
    """The manifest entry of a pretrained BEV autoencoder (`np_policy.bev_encoder`): no training run, but its
    pretraining config (the seed makes its images), epochs and final held-out MSE, as stored in the file."""
    metrics = payload.get("metrics") or [{}]
    pretraining = json.loads(json.dumps(payload.get("config")))  # as the manifest file holds it (lists)
    return {"kind": AUTOENCODER_KIND, "pretraining": pretraining, "epochs": len(payload.get("metrics", [])),
            "held_out_mse": metrics[-1].get("held_out_mse"), "sha256": digest, "size_bytes": size,
            "format": CHECKPOINT_FORMAT}


def _folder(root: str | Path) -> Path:
    """``root`` as a Path; a CheckpointError when it is not a folder."""
    if not Path(root).is_dir():
        raise CheckpointError(f"{root}: expected the checkpoints folder")
    return Path(root)


def _relative(path: str | Path, base: Path) -> str:
    """``path`` relative to ``base``, with forward slashes."""
    return Path(path).resolve().relative_to(base).as_posix()


def build_manifest(root: str | Path = DEFAULT_ROOT) -> dict[str, Any]:
    """The manifest of the checkpoint folder ``root`` (see the module docstring); paths are relative to
    ``root``'s parent (the repository), so they read ``checkpoints/...``."""
    root = _folder(root)
    base = root.resolve().parent
    runs = run_folders(root)
    files = {}
    for path in shipped_files(root):
        payload = load_checkpoint(path)
        digest = file_sha256(path)
        if payload.get("kind") == AUTOENCODER_KIND:
            files[_relative(path, base)] = autoencoder_entry(payload, digest, path.stat().st_size)
            continue
        run, copy_of = _source_run(path, payload, runs, digest)
        entry = {"run": _relative(run, base), "epoch": payload.get("epoch"),
                 "config": _relative(run / "config.json", base), "sha256": digest,
                 "size_bytes": path.stat().st_size, "format": CHECKPOINT_FORMAT}
        if copy_of is not None:
            entry["copy_of"] = _relative(copy_of, base)
        files[_relative(path, base)] = entry
    resumable = [_relative(run, base) for run in runs if (run / "snapshot.pt").exists()]
    return {"format": MANIFEST_FORMAT, "about": _ABOUT, "files": files, "resumable_runs": resumable}


def manifest_differences(stored: dict[str, Any], built: dict[str, Any]) -> list[str]:
    """What differs between a ``stored`` manifest and one ``built`` from the files, one phrase per difference."""
    out = [] if stored.get("format") == MANIFEST_FORMAT else [f"format is {stored.get('format')!r}, expected "
                                                              f"{MANIFEST_FORMAT!r}"]
    listed, found = stored.get("files", {}), built["files"]
    out += [f"{p}: listed but not found (or its run can be resumed now)" for p in sorted(set(listed) - set(found))]
    out += [f"{p}: shipped but not listed" for p in sorted(set(found) - set(listed))]
    for path in sorted(set(listed) & set(found)):
        for key in sorted(set(listed[path]) | set(found[path])):
            if listed[path].get(key) != found[path].get(key):
                out.append(f"{path}: {key} is {listed[path].get(key)!r} in the manifest, {found[path].get(key)!r} "
                           "in the files")
    if sorted(stored.get("resumable_runs", [])) != sorted(built["resumable_runs"]):
        out.append(f"resumable_runs are {stored.get('resumable_runs')} in the manifest, "
                   f"{built['resumable_runs']} in the files")
    return out


def read_manifest(path: Path) -> dict[str, Any]:
    """The manifest in ``path``; a CheckpointError naming it when it is missing or not a JSON object."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise CheckpointError(f"{path}: not a readable manifest ({exc}); write it with "
                              "`python -m np_policy.manifest build`") from exc
    if not isinstance(data, dict):
        raise CheckpointError(f"{path}: expected a JSON object, got a {type(data).__name__}")
    return data


def check_manifest(root: str | Path = DEFAULT_ROOT) -> dict[str, Any]:
    """The manifest of ``root`` when ``root/MANIFEST.json`` matches the files (every hash recomputed, every
    checkpoint loaded); else a CheckpointError listing every difference."""
    root = _folder(root)
    stored = read_manifest(root / MANIFEST_FILE)
    built = build_manifest(root)
    problems = manifest_differences(stored, built)
    if problems:
        raise CheckpointError(f"{root / MANIFEST_FILE} does not match the files: " + "; ".join(problems)
                              + "; rebuild it with `python -m np_policy.manifest build` if the change is intended")
    return built


@cli_boundary
def main(argv: list[str] | None = None) -> dict[str, Any]:
    """``build`` writes ``MANIFEST.json`` in the checkpoints folder, ``check`` verifies it; returns the manifest."""
    parser = argparse.ArgumentParser(prog="python -m np_policy.manifest", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=("build", "check"),
                        help="build: write MANIFEST.json from the files; check: verify it against them")
    parser.add_argument("--root", type=Path, default=DEFAULT_ROOT,
                        help="the checkpoints folder (default: the repository's checkpoints/)")
    args = parser.parse_args(argv)
    if args.command == "build":
        manifest = build_manifest(args.root)
        write_atomic(args.root / MANIFEST_FILE, (json.dumps(manifest, indent=2) + "\n").encode())
        verb = "wrote"
    else:
        manifest = check_manifest(args.root)
        verb = "checked"
    print(f"{verb} {args.root / MANIFEST_FILE}: {len(manifest['files'])} shipped files, "
          f"{len(manifest['resumable_runs'])} resumable runs")
    return manifest


if __name__ == "__main__":
    main()
