"""Recorded-style clips of the delivery site (spec §4.4, §8 "Closed loop on a clip"; paper §V-F, App. C).

A **clip** is what the paper's real vehicle recorded on the way back to its parking spot: an initial ego pose, an
assigned parking spot and a 10 Hz sequence of frames, each with the ground truth of every object and, stored
apart, the noisy five-vertex detections a planner sees. The 1,000 training clips are generated on demand from
their seeds; the 47 difficult evaluation clips ship as ``np_sim/data/clips_eval_v1.json.gz``.

Modules:

* `np_sim.clips.config` — the generator's parameters (`ClipConfig`) and the split constants;
* `np_sim.clips.model` — the data model (`Clip`, `TrackedObject`) and a frame as a planner's `Scene`;
* `np_sim.clips.geometry` — point-to-polygon distances, object outlines, the geodesic grid;
* `np_sim.clips.difficulty` — the difficulty rule (`DifficultyRule`, `Difficulty`, `clip_difficulty`);
* `np_sim.clips.generation` — one clip from one seed (`generate_candidate`), feasibility;
* `np_sim.clips.detections` — the detection noise model (five-vertex outlines, jitter, drop-outs, missed frames);
* `np_sim.clips.splits` — the train and eval splits, the evaluation-clip file (`load_clips`);
* `np_sim.clips.resets` — training resets (App. C) and their cached pool (`cached_training_pool`);
* `np_sim.clips.cli` — ``python -m np_sim.clips [--summary] [--figure CLIP_NAME --out PNG] [--regenerate]``.

The perception model of the closed loop (detections filtered over several frames) is `tracking.perception`.
Every name other modules use is importable from ``np_sim.clips`` itself.
"""

from np_sim.clips.cli import build_parser, main, summarize
from np_sim.clips.config import (
    CLIPS_FORMAT_VERSION,
    EVAL_PATH,
    N_CLIPS,
    OBJECT_KINDS,
    REJECTION_REASONS,
    SEED_BASE,
    SPLITS,
    ClipConfig,
)
from np_sim.clips.detections import five_vertex_outline
from np_sim.clips.difficulty import Difficulty, DifficultyRule, clip_difficulty, measure_difficulty, target_clearance
from np_sim.clips.generation import Candidate, ClipRejected, generate_candidate, generate_clip, split_of_seed
from np_sim.clips.geometry import polygon_distances
from np_sim.clips.model import Clip, TrackedObject
from np_sim.clips.resets import cached_training_pool, sample_recorded_reset, sample_training_scene, training_pool
from np_sim.clips.splits import (
    SplitStatistics,
    difficult_clips,
    eval_file_text,
    find_clip,
    generate_split,
    load_clips,
    read_eval_file,
    split_statistics,
    write_eval_file,
)
from np_sim.site import SITE_OBSERVATION, load_site

__all__ = [
    "SITE_OBSERVATION",
    "SPLITS",
    "Clip",
    "ClipConfig",
    "ClipRejected",
    "Difficulty",
    "DifficultyRule",
    "TrackedObject",
    "clip_difficulty",
    "generate_candidate",
    "generate_clip",
    "generate_split",
    "load_clips",
    "load_site",
    "polygon_distances",
    "sample_training_scene",
]
