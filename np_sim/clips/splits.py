"""The train and eval splits of the clips and the evaluation-clip file (paper App. C).

Train and eval use disjoint seed streams: train seeds 0, 1, 2, … (clips ``train-0000000`` …), eval seeds
1,000,000, 1,000,001, … (``eval-1000000`` …). The **1,000 training clips** are the first 1,000 feasible candidates
of the train stream (difficult ones included), generated on demand by `load_clips("train")` and cached in memory.
The **47 evaluation clips** are the first 47 difficult feasible candidates of the eval stream; they ship as
``np_sim/data/clips_eval_v1.json.gz`` (`regenerate_data_files`, ``python -m np_sim.clips --regenerate``, rewrites
it and the site file; regenerating reproduces them exactly).
"""

from __future__ import annotations

import gzip
import io
import json
import time
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from np_sim.clips.config import (
    CLIPS_FORMAT_VERSION,
    EVAL_PATH,
    N_CLIPS,
    REJECTION_REASONS,
    SEED_BASE,
    SPLITS,
    ClipConfig,
)
from np_sim.clips.difficulty import DifficultyRule
from np_sim.clips.generation import generate_candidate, generate_clip
from np_sim.clips.model import Clip
from np_sim.errors import ConfigError, SceneError
from np_sim.site import DATA_DIR, SITE_PATH, Site, generate_site, load_site


@dataclass(frozen=True)
class SplitStatistics:
    """How a split was drawn from its seed stream."""

    split: str
    """``"train"`` or ``"eval"``."""
    examined: int
    """Candidates generated."""
    accepted: int
    """Clips kept."""
    rejected: dict
    """Rejection reason -> count."""
    seconds: float = 0.0
    """Wall time of the generation (s); 0 when read from a file."""


def generate_split(split: str, n: int | None = None, *, site: Site | None = None, config: ClipConfig | None = None,
                   rule: DifficultyRule | None = None) -> tuple[list[Clip], SplitStatistics]:
    """Walk ``split``'s seed stream until ``n`` clips (default `N_CLIPS`) are kept: feasible, and for eval
    also difficult. Returns the clips and the rejection statistics."""
    check_split(split)
    n = N_CLIPS[split] if n is None else int(n)
    clips: list[Clip] = []
    rejected = {reason: 0 for reason in REJECTION_REASONS if split == "eval" or reason != "not_difficult"}
    seed = SEED_BASE[split]
    t0 = time.perf_counter()
    while len(clips) < n:
        if split == "train" and seed >= SEED_BASE["eval"]:
            raise ConfigError("generate_split: the train seed stream ran into the eval stream's seeds")
        candidate = generate_candidate(seed, site=site, config=config, rule=rule)
        seed += 1
        if candidate.clip is None:
            rejected[candidate.reason] += 1
        elif split == "eval" and not candidate.clip.difficulty.difficult:
            rejected["not_difficult"] += 1
        else:
            clips.append(candidate.clip)
    examined = seed - SEED_BASE[split]
    return clips, SplitStatistics(split, examined, len(clips), rejected, time.perf_counter() - t0)


def check_split(split: str) -> None:
    """ConfigError unless ``split`` is one of `SPLITS`."""
    if split not in SPLITS:
        raise ConfigError(f"clip split: unknown split {split!r}; expected one of {', '.join(repr(s) for s in SPLITS)}")


def eval_file_text(clips: Sequence[Clip], statistics: SplitStatistics) -> str:
    """The JSON text of the evaluation-clip file (compact, fixed key order, one clip per line)."""
    header = {
        "version": CLIPS_FORMAT_VERSION,
        "site": clips[0].site.name if clips else "",
        "split": "eval",
        "seed_base": SEED_BASE["eval"],
        "candidates": {"examined": statistics.examined, "accepted": statistics.accepted,
                       "rejected": dict(statistics.rejected)},
        "config": asdict(ClipConfig()),
        "rule": asdict(DifficultyRule()),
    }
    lines = [json.dumps(c.to_dict(), separators=(",", ":"), allow_nan=False) for c in clips]
    head = json.dumps(header, separators=(",", ":"))[:-1]
    return head + ',"clips":[\n' + ",\n".join(lines) + "\n]}\n"


def write_eval_file(path: Path, text: str) -> None:
    """Gzip ``text`` to ``path`` reproducibly (no file name, mtime 0)."""
    buffer = io.BytesIO()
    with gzip.GzipFile(filename="", mode="wb", fileobj=buffer, mtime=0, compresslevel=9) as stream:
        stream.write(text.encode("utf-8"))
    Path(path).write_bytes(buffer.getvalue())


def read_eval_file(path: Path | None = None) -> tuple[list[Clip], SplitStatistics]:
    """Read the evaluation-clip file (default the shipped one): clips and their candidate statistics."""
    path = EVAL_PATH if path is None else Path(path)
    source = str(path)
    try:
        data = json.loads(gzip.decompress(path.read_bytes()).decode("utf-8"))
    except FileNotFoundError:
        raise SceneError(f"{source}: evaluation clips not found; run `python -m np_sim.clips --regenerate`") from None
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as error:
        raise SceneError(f"{source}: not a gzipped JSON clip file ({error})") from None
    if not isinstance(data, dict) or data.get("version") != CLIPS_FORMAT_VERSION:
        raise SceneError(f"{source}: version: expected {CLIPS_FORMAT_VERSION}, got "
                         f"{data.get('version') if isinstance(data, dict) else type(data).__name__!r}")
    site = load_site()
    if data.get("site") != site.name:
        raise SceneError(f"{source}: site: expected {site.name!r}, got {data.get('site')!r}")
    clips = [Clip.from_dict(item, site=site, source=source) for item in data["clips"]]
    cand = data["candidates"]
    return clips, SplitStatistics("eval", int(cand["examined"]), int(cand["accepted"]), dict(cand["rejected"]))


@lru_cache(maxsize=None)
def _split_cached(split: str) -> tuple[tuple[Clip, ...], SplitStatistics]:
    if split == "eval":
        clips, stats = read_eval_file()
    else:
        clips, stats = generate_split("train")
    return tuple(clips), stats


def load_clips(split: str) -> list[Clip]:
    """The clips of ``split`` (spec §10): ``"train"`` — 1,000 clips generated from the train seed stream on the
    first call (about a minute), then cached in memory; ``"eval"`` — the 47 shipped difficult clips.

    Raises
    ------
    ConfigError
        For a split other than ``"train"`` or ``"eval"``.
    """
    check_split(split)
    return list(_split_cached(split)[0])


def difficult_clips(split: str) -> list[Clip]:
    """The clips of ``split`` the difficulty rule marks difficult (`clip_difficulty`), in clip order: all 47 eval
    clips; 304 of the 1,000 training clips."""
    return [clip for clip in load_clips(split) if clip.difficulty.difficult]


def split_statistics(split: str) -> SplitStatistics:
    """Candidate statistics of ``split`` (loads or generates it, see `load_clips`)."""
    check_split(split)
    return _split_cached(split)[1]


def find_clip(name: str) -> Clip:
    """A clip by name: an eval clip from the shipped file, or ``train-<seed>`` generated from its seed."""
    for clip in load_clips("eval"):
        if clip.name == name:
            return clip
    if name.startswith("train-") and name[6:].isdigit():
        return generate_clip(int(name[6:]))
    raise ConfigError(f"find_clip: no clip named {name!r}; expected an eval clip name (e.g. "
                      f"{load_clips('eval')[0].name!r}) or 'train-<seed>'")


def regenerate_data_files() -> None:
    """Regenerate the shipped site file (`np_sim.site.generate_site` of seed 0) and the evaluation-clip file from
    their seeds, and forget the clips loaded before."""
    site = generate_site(0)
    DATA_DIR.mkdir(parents=True, exist_ok=True)
    site.save(SITE_PATH)
    clips, stats = generate_split("eval", site=site)
    write_eval_file(EVAL_PATH, eval_file_text(clips, stats))
    _split_cached.cache_clear()
