"""The scene and start of the closed loop's first planner call on a training clip (shared by the planner tests)."""

import numpy as np

from np_sim.clips.generation import generate_clip
from tracking.perception import perceived_scene


def first_frame(seed: int):
    """(scene, start pose) of the first call on training clip ``seed`` (``train-<seed>``, never a held-out clip):
    the raw detections of frame 0 seen from the clip's start, as the closed loop plans its first call."""
    clip = generate_clip(seed)
    start = np.asarray(clip.start, float)
    return perceived_scene(clip, 0, pose=start), start
