"""Configuration of the clips: the generator's parameters (`ClipConfig`) and the split constants (spec §4.4,
paper App. C): which seeds make which split, how many clips each holds, and where the evaluation clips ship."""

from __future__ import annotations

from dataclasses import dataclass

from np_sim.site import DATA_DIR

SPLITS = ("train", "eval")
"""Valid clip splits."""
N_CLIPS = {"train": 1000, "eval": 47}
"""Clips per split (paper App. C)."""
SEED_BASE = {"train": 0, "eval": 1_000_000}
"""First seed of each split's stream; train seeds stay below the eval base, so the streams are disjoint."""
EVAL_PATH = DATA_DIR / "clips_eval_v1.json.gz"
"""The shipped evaluation clips."""
CLIPS_FORMAT_VERSION = 1
"""The only clip-file version this package reads and writes."""
OBJECT_KINDS = ("vehicle", "cart", "pallet", "bin", "pedestrian")
"""Kinds of ground-truth objects."""
REJECTION_REASONS = ("no_free_start", "start_disconnected", "disconnected_last_frame", "not_difficult")
"""Why a candidate is not used (``not_difficult`` only in the eval stream)."""


@dataclass(frozen=True)
class ClipConfig:
    """Parameters of the clip generator; the defaults make the shipped and training clips."""

    frame_dt_s: float = 0.1
    """Frame period (s): 10 Hz."""
    n_frames_range: tuple[int, int] = (60, 100)
    """Frames per clip, drawn uniformly, both ends included."""
    occupancy_range: tuple[float, float] = (0.35, 0.75)
    """Per-clip probability that a non-target spot holds a parked vehicle, drawn uniformly."""
    vehicle_length_range_m: tuple[float, float] = (4.3, 5.2)
    """Parked-vehicle length (m)."""
    vehicle_width_range_m: tuple[float, float] = (1.75, 2.1)
    """Parked-vehicle width (m)."""
    parking_offset_sd_m: float = 0.12
    """Sd of a tidy parker's lateral and longitudinal offset from the spot centre (m), truncated at 2 sd."""
    parking_yaw_sd_deg: float = 1.5
    """Sd of a tidy parker's heading error (deg), truncated at 2 sd."""
    sloppy_probability: float = 0.15
    """Probability that a parked vehicle stands off-centre and skewed."""
    sloppy_offset_range_m: tuple[float, float] = (0.3, 0.65)
    """Lateral offset of a sloppy parker, to a random side (m)."""
    sloppy_yaw_deg: float = 6.0
    """Largest heading error of a sloppy parker (deg)."""
    n_bins_range: tuple[int, int] = (1, 5)
    """Bins per clip (both ends included)."""
    n_pallets_range: tuple[int, int] = (0, 3)
    """Pallets per clip (both ends included)."""
    n_carts_range: tuple[int, int] = (1, 3)
    """Hand carts per clip (both ends included)."""
    n_pedestrians_range: tuple[int, int] = (1, 4)
    """Pedestrians per clip (both ends included)."""
    kerb_clutter_probability: float = 0.7
    """Probability that a clutter object stands along a kerb rather than anywhere in the open."""
    near_target_probability: float = 0.2
    """Probability of one clutter object right beside the target bay."""
    near_target_gap_range_m: tuple[float, float] = (0.2, 0.6)
    """Gap between that object and the target footprint (m)."""
    moving_cart_probability: float = 0.35
    """Probability that a cart is being pushed."""
    walking_probability: float = 0.7
    """Probability that a pedestrian walks (else stands)."""
    cart_speed_range_mps: tuple[float, float] = (0.3, 0.8)
    """Speed of a pushed cart (m/s); it stops at the end of its path."""
    pedestrian_speed_range_mps: tuple[float, float] = (0.8, 1.4)
    """Walking speed (m/s); a pedestrian turns back at the ends of its path."""
    path_length_range_m: tuple[float, float] = (4.0, 14.0)
    """Length of a mover's straight path (m)."""
    object_gap_m: float = 0.15
    """Least gap between static ground-truth objects, and from the boundary (m)."""
    target_gap_m: float = 0.2
    """Least gap between any ground-truth object and the target footprint (m)."""
    start_gap_m: float = 0.2
    """Least gap between the start footprint and ground-truth objects or the boundary at frame 0 (m)."""
    start_target_gap_m: float = 0.5
    """Least gap between the start and target footprints (m)."""
    mover_target_gap_m: float = 0.6
    """Least gap between a mover's swept path and the target footprint (m)."""
    mover_start_gap_m: float = 0.5
    """Least gap between a mover's swept path and the start footprint (m)."""
    front_start_probability: float = 0.3
    """Probability that the start is drawn in the aisle in front of the target (arriving at the spot)."""
    front_start_along_m: tuple[float, float] = (4.5, 10.0)
    """Offset of a front start along the target heading (m)."""
    front_start_lateral_m: float = 4.0
    """Largest offset of a front start across the target heading (m)."""
    front_start_cross_probability: float = 0.5
    """Probability that a front start drives across the bay axis (heading ±90° ± 17°), else uniform heading."""
    near_start_probability: float = 0.2
    """Probability that the start is drawn at a random bearing near the target."""
    near_start_range_m: tuple[float, float] = (3.0, 9.0)
    """Distance band of a near start from the target reference point (m)."""
    start_draws: int = 300
    """Start draws before the candidate is rejected as ``no_free_start``."""
    jitter_sd_range_m: tuple[float, float] = (0.05, 0.15)
    """Per-clip sd of the Gaussian detection vertex jitter (m), drawn uniformly."""
    jitter_truncation_sd: float = 2.5
    """Jitter is truncated at this many sd (per coordinate)."""
    dropout_onset_range: tuple[float, float] = (0.01, 0.03)
    """Per-clip probability per frame that a detected object drops out, drawn uniformly."""
    dropout_persistence: float = 0.6
    """Probability that a dropped-out object stays dropped in the next frame (mean burst 2.5 frames)."""
    missed_frame_range: tuple[float, float] = (0.0, 0.02)
    """Per-clip probability that a whole frame is missed, drawn uniformly."""
    grid_m: float = 1.5
    """Cell size of the feasibility and detour grid (m)."""
