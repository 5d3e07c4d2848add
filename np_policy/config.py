"""Configuration of the NeuralParker policy network and its PPO recipe (paper App. A Tables IV and V, spec §6).

Defaults are the paper's numbers. The recipe's names (epochs, steps per epoch, steps per collect, repeats, batch)
are those of Tianshou's on-policy trainer, whose semantics the PPO here reproduces: each epoch collects
``steps_per_collect`` transitions at a time from ``num_train_envs`` envs until at least ``steps_per_epoch`` are in;
after each collect, ``repeats`` passes over the collected data in shuffled minibatches of ``batch_size``.
Variants are ``dataclasses.replace``; ``from_dict`` rejects unknown keys (``np_sim.errors.ConfigError``).
``TrainConfig`` bundles them with the env rules of a run; it is written beside its checkpoints and stored inside
them, so a planner rebuilds the env a policy was trained in from the checkpoint alone (``checkpoint_config``).
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from np_policy.sampling import FIRST_ARCS, ChoiceWeights
from np_sim.config import CONNECTOR_VARIANTS, EnvConfig, config_from_dict
from np_sim.curriculum import CurriculumSchedule
from np_sim.errors import ConfigError
from np_sim.site import SITE_OBSERVATION

BENCHMARKS = ("factorial", "topology", "examples", "site")
CURRICULUM_REGIONS = ("start_region", "lot")


def _matches(hint: Any, value: Any) -> bool:
    """``value`` (as read from JSON, or a stored config) has the type ``hint`` asks for; ints count as floats,
    bools count as neither; hints of other kinds are not checked here."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is bool:
        return isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if hint is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if hint is str:
        return isinstance(value, str)
    if hint is type(None):
        return value is None
    if origin is typing.Literal:
        return any(value == a and type(value) is type(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        return any(_matches(a, value) for a in args)
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            return False
        if len(args) == 2 and args[1] is Ellipsis:
            return all(_matches(args[0], v) for v in value)
        return len(args) == len(value) and all(_matches(a, v) for a, v in zip(args, value))
    return True


def _describe(hint: Any) -> str:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is typing.Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_describe(a) for a in args)
    if origin is tuple:
        return f"a list of {_describe(args[0])}" if args[1:] == (Ellipsis,) else f"a list of {len(args)} values"
    names = {bool: "true or false", int: "an integer", float: "a number", str: "a string", type(None): "null"}
    return names.get(hint, getattr(hint, "__name__", str(hint)))


def check_types(cls: type, data: Any, path: str | None = None) -> None:
    """ConfigError naming the field path (``TrainConfig.ppo.epochs: expected an integer, got 2.5``) of the first
    value in ``data`` whose type is not the one the frozen config dataclass ``cls`` declares, recursing into
    nested configs; a non-mapping is an error too. Unknown keys are left to ``np_sim.config.config_from_dict``."""
    path = cls.__name__ if path is None else path
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping (a JSON object), got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    for name, value in data.items():
        hint = hints.get(name)
        if hint is None:
            continue
        if dataclasses.is_dataclass(hint):
            check_types(hint, value, f"{path}.{name}")
        elif not _matches(hint, value):
            raise ConfigError(f"{path}.{name}: expected {_describe(hint)}, got {value!r}")


@dataclass(frozen=True)
class PPOConfig:
    """The PPO training recipe of paper Table V (Tianshou on-policy trainer semantics)."""

    learning_rate: float = 3.0e-4
    """Adam step size at the first update."""
    lr_linear_decay: bool = True
    """Decay the learning rate linearly to 0 over ``total_updates`` (one scheduler step per collect)."""
    gamma: float = 0.99
    """Discount γ per arc."""
    gae_lambda: float = 0.95
    """GAE λ."""
    clip_coef: float = 0.15
    """PPO ratio clip ε."""
    value_clip: bool = False
    """Clip the value prediction around the collected value by ``clip_coef`` (Tianshou ``value_clip``; off)."""
    vf_coef: float = 0.25
    """Weight of the value loss (mean squared error, no ½ factor, as in Tianshou)."""
    ent_coef: float = 0.005
    """Weight of the entropy bonus."""
    max_grad_norm: float = 0.5
    """Global gradient-norm clip per minibatch step."""
    norm_advantages: bool = True
    """Normalise advantages per minibatch to zero mean and unit std."""
    norm_rewards: bool = True
    """Tianshou reward normalisation: GAE returns divided by a running std of the returns; the critic learns them."""
    epochs: int = 240
    """Training epochs (snapshot and selection granularity)."""
    steps_per_epoch: int = 60_000
    """Minimum env steps collected per epoch (collects repeat until reached)."""
    steps_per_collect: int = 16_384
    """Env transitions per collect (= per PPO update), summed over the training envs."""
    repeats: int = 10
    """Passes over each collected batch."""
    batch_size: int = 8_192
    """Minibatch size; a short last minibatch is merged into the previous one (Tianshou ``merge_last``)."""
    update_chunk: int = 1_024
    """Samples per forward/backward pass inside a minibatch. The chunks' gradients are summed before the one
    optimiser step, so the step is the whole-minibatch step up to float rounding; chunks that fit in cache make
    the update faster on CPU (``python -m np_policy.bench_update --chunks``). Not a recipe parameter: runs trained
    before this field existed passed the whole minibatch at once."""
    buffer_size: int = 131_072
    """Replay-buffer capacity of the Tianshou recipe (≥ ``steps_per_collect``; on-policy data is cleared per
    collect)."""
    num_train_envs: int = 128
    """Parallel training environments."""
    num_test_envs: int = 32
    """Parallel test environments (checkpoint selection episodes)."""
    snapshot_every_epochs: int = 20
    """Save a snapshot every this many epochs."""
    selection_episodes: int = 32
    """Sampled full-range training-distribution episodes per epoch for checkpoint selection."""
    adam_eps: float = 1.0e-8
    """Adam ε (torch default, as in Tianshou's examples)."""
    norm_eps: float = 1.0e-8
    """ε added to the running return variance and to the minibatch advantage std."""

    def __post_init__(self) -> None:
        for name in ("steps_per_epoch", "steps_per_collect", "repeats", "batch_size", "update_chunk",
                     "num_train_envs", "num_test_envs", "epochs"):
            if getattr(self, name) <= 0:
                raise ConfigError(f"PPOConfig.{name}: expected a positive integer, got {getattr(self, name)!r}")
        if self.selection_episodes % self.num_test_envs:
            raise ConfigError(
                f"PPOConfig.selection_episodes: expected a multiple of num_test_envs={self.num_test_envs}, "
                f"got {self.selection_episodes}")
        if self.steps_per_collect % self.num_train_envs:
            raise ConfigError(
                f"PPOConfig.steps_per_collect: expected a multiple of num_train_envs={self.num_train_envs}, "
                f"got {self.steps_per_collect}")

    @property
    def steps_per_env_per_collect(self) -> int:
        """Rollout length T per training env per collect."""
        return self.steps_per_collect // self.num_train_envs

    @property
    def collects_per_epoch(self) -> int:
        """Collects (= PPO updates) per epoch: ceil(steps_per_epoch / steps_per_collect)."""
        return math.ceil(self.steps_per_epoch / self.steps_per_collect)

    @property
    def total_updates(self) -> int:
        """Scheduler length of the linear learning-rate decay (Tianshou examples' ``max_update_num``)."""
        return self.collects_per_epoch * self.epochs

    def lr_at(self, update: int) -> float:
        """Learning rate for the 0-based ``update`` (linear decay to 0 over ``total_updates`` when enabled)."""
        if not self.lr_linear_decay:
            return self.learning_rate
        return self.learning_rate * max(0.0, 1.0 - update / self.total_updates)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "PPOConfig":
        """Inverse of ``to_dict``; unknown keys and values of the wrong type are a ConfigError."""
        check_types(cls, data)
        return config_from_dict(cls, data)


@dataclass(frozen=True)
class NetworkConfig:
    """The scene encoder and actor–critic heads of paper §III-C and App. A Table IV (Panel A)."""

    token_dim: int = 16
    """Width of each geometry token (obstacle or boundary slot)."""
    token_heads: int = 1
    """Attention heads over the geometry tokens."""
    token_ff_dim: int = 32
    """Hidden width of the geometry block's feed-forward layer."""
    stream_hidden: int = 64
    """Hidden width of each stream MLP (ego, LiDAR, obstacle slot, boundary slot)."""
    fusion_dim: int = 128
    """Width of the global–local fusion tokens and of the encoder feature."""
    fusion_depth: int = 1
    """Transformer layers in the global–local fusion."""
    fusion_heads: int = 4
    """Attention heads in the fusion (4 × 32 = 128)."""
    fusion_ff_dim: int = 256
    """Hidden width of the fusion layer's feed-forward block."""
    head_hidden: tuple[int, ...] = (64, 128, 256, 64)
    """Hidden widths of the separate actor and critic MLPs."""
    init_log_std: float = -0.5
    """Initial value of the state-independent log-std of the Gaussian (Tianshou MuJoCo PPO example)."""
    action_dim: int = 2
    """Normalised action (a_κ, a_l) ∈ [−1, 1]²."""

    def __post_init__(self) -> None:
        if self.fusion_dim % self.fusion_heads:
            raise ConfigError(f"NetworkConfig.fusion_dim: expected a multiple of fusion_heads={self.fusion_heads}, "
                              f"got {self.fusion_dim}")
        if self.token_dim % self.token_heads:
            raise ConfigError(f"NetworkConfig.token_dim: expected a multiple of token_heads={self.token_heads}, "
                              f"got {self.token_dim}")

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "NetworkConfig":
        """Inverse of ``to_dict``; unknown keys and values of the wrong type are a ConfigError."""
        check_types(cls, data)
        return config_from_dict(cls, data)


def is_scene_path(benchmark: str) -> bool:
    """``benchmark`` names a scene JSON file or a folder (of them) rather than a built-in benchmark."""
    path = Path(benchmark)
    return path.is_dir() or (path.suffix == ".json" and path.is_file())


@dataclass(frozen=True)
class TrainConfig:
    """Everything a run depends on; written beside its checkpoints and stored inside them."""

    benchmark: str = "factorial"
    """Training scenes: 'factorial', 'topology' (their train splits), 'examples' (the hand-made scenes), 'site'
    (App. C resets from the 1,000 training clips; start with ``benchmark_defaults('site')``), or the path of a
    scene JSON file or of a folder of them (your own scenes)."""
    seed: int = 0
    """Seed of torch, the envs' starts and the minibatch shuffling."""
    torch_threads: int = 0
    """Threads of torch and of numba's parallel env loops (`np_policy.threads.use_threads`; 0 = all cores)."""
    curriculum_pool: int = 256
    """Start poses per scene in the geodesic curriculum pool."""
    curriculum_region: str = "start_region"
    """Where the curriculum pool is drawn: 'start_region' (each scene's start region, spec §5's reading of the
    paper's "5 % of the available range") or, beyond that reading, 'lot' (anywhere in the scene's drivable lot
    that is connected to the target, so the nearest 5 % start next to the bay; a reverse curriculum in the sense
    of Florensa et al. 2017). Selection episodes keep the start regions either way."""
    site_pool: int = 8192
    """Site only: (scene, start) training resets drawn once from the training clips (``np_sim.clips.training_pool``)."""
    site_recorded_share: float = 0.0
    """Site only, beyond the paper: this share of the pool are resets from the difficult training clips' own
    recorded tasks (``np_sim.clips.sample_recorded_reset``: the clip's start, exact or perturbed, and target) instead
    of App. C's random ones; 0 is the paper's pool."""
    site_recorded_skip: int = 0
    """Site only: the first this many difficult training clips (in clip order) are left out of the recorded resets,
    so they can validate the result as clips the policy never started from."""
    train_margin_m: float = 0.0
    """Beyond the paper: the training and selection envs, and the start pools, use the vehicle's footprint grown by
    this much on every side (`VehicleSpec.inflated`), so an episode ends when the body comes closer than this to an
    obstacle or the boundary, and the policy learns to keep that clearance. The checkpoint keeps the real vehicle:
    planners roll it out against the real body. Meaningful under the footprint convention; 0 is the paper's."""
    holdout_every: int = 0
    """Beyond the paper (Factorial and Topology-Stress only): leave every this-many-th training scene out of training
    and selection (`np_sim.benchmarks.frozen.held_out`: with 4, two scenes per Topology-Stress cell, 12 of 48), so
    ``python -m experiments.evaluate --split holdout`` can measure how a recipe carries over to scenes it never saw
    without looking at the test scenes; 0 (the paper's) trains on all of them."""
    env: EnvConfig = field(default_factory=EnvConfig)
    ppo: PPOConfig = field(default_factory=PPOConfig)
    network: NetworkConfig = field(default_factory=NetworkConfig)
    curriculum: CurriculumSchedule = field(default_factory=CurriculumSchedule)

    def __post_init__(self) -> None:
        if self.benchmark not in BENCHMARKS and not is_scene_path(self.benchmark):
            raise ConfigError(f"TrainConfig.benchmark: expected one of {list(BENCHMARKS)} or the path of a scene "
                              f"JSON file or folder, got {self.benchmark!r}")
        if self.curriculum_region not in CURRICULUM_REGIONS:
            raise ConfigError(f"TrainConfig.curriculum_region: expected one of {CURRICULUM_REGIONS}, got "
                              f"{self.curriculum_region!r}")
        if not 0.0 <= self.site_recorded_share <= 1.0:
            raise ConfigError(f"TrainConfig.site_recorded_share: expected a share in [0, 1], "
                              f"got {self.site_recorded_share!r}")
        if not (math.isfinite(self.train_margin_m) and self.train_margin_m >= 0.0):
            raise ConfigError("TrainConfig.train_margin_m: expected a finite number >= 0 m, "
                              f"got {self.train_margin_m!r}")
        if self.train_margin_m and self.env.collision != "footprint":
            raise ConfigError("TrainConfig.train_margin_m: a clearance margin needs env.collision 'footprint' (the "
                              f"reference-point convention has no body to grow), got {self.env.collision!r}")
        if self.holdout_every and (self.holdout_every < 2 or self.benchmark not in ("factorial", "topology")):
            raise ConfigError("TrainConfig.holdout_every: expected 0 or an integer >= 2 on the 'factorial' or "
                              f"'topology' benchmark, got {self.holdout_every!r} on {self.benchmark!r}")
        if self.site_recorded_skip < 0:
            raise ConfigError(f"TrainConfig.site_recorded_skip: expected >= 0 clips, got {self.site_recorded_skip!r}")
        if self.site_recorded_share and self.benchmark != "site":
            raise ConfigError(f"TrainConfig.site_recorded_share: recorded resets exist on the site only, got "
                              f"benchmark {self.benchmark!r}")
        if self.benchmark == "site" and self.curriculum.enabled:
            raise ConfigError("TrainConfig.curriculum.enabled: the site trains from App. C resets (start and "
                              "detections drawn together), so the geodesic curriculum must be off; start from "
                              "benchmark_defaults('site')")

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON-safe)."""
        return dataclasses.asdict(self)

    def training_env(self) -> EnvConfig:
        """The env the run trains and selects in: ``env`` with the footprint grown by ``train_margin_m``."""
        if not self.train_margin_m:
            return self.env
        return dataclasses.replace(self.env, vehicle=self.env.vehicle.inflated(self.train_margin_m))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "TrainConfig":
        """Inverse of ``to_dict``; an unknown key or a value of the wrong type (2.5 for an int) anywhere is a
        ConfigError naming its field path."""
        check_types(cls, data)
        return config_from_dict(cls, data)


def benchmark_defaults(benchmark: str) -> dict[str, Any]:
    """The TrainConfig fields a benchmark changes from the paper's Factorial defaults, as a nested dict.

    'site' is the paper's real-vehicle configuration (App. C): target-relative ego, the nearest ten detections as
    five-vertex polygons and the site boundary (``np_sim.site.SITE_OBSERVATION``), no policy-level LiDAR, the
    fixed nine-candidate Hermite connector, App. C resets instead of the curriculum.
    """
    if benchmark != "site":
        return {"benchmark": benchmark}
    return {"benchmark": "site", "env": {"observation": dataclasses.asdict(SITE_OBSERVATION),
                                         "connector": {"mode": "fixed"}},
            "curriculum": {"enabled": False}}


def checkpoint_config(path: str | Path, payload: dict[str, Any]) -> TrainConfig:
    """The TrainConfig stored in a loaded checkpoint; CheckpointError naming ``path`` when it is not a valid one."""
    from np_policy.checkpoint import CheckpointError

    try:
        return TrainConfig.from_dict(payload["config"])
    except ConfigError as exc:
        raise CheckpointError(f"{path}: its stored config is not a valid TrainConfig: {exc}") from exc


def benchmark_layout(benchmark: str) -> dict[str, Any]:
    """The observation layout (``ObservationConfig`` as a dict) a policy needs to plan ``benchmark``'s scenes: the
    site's (App. C) for 'site', the paper's default for the Factorial, Topology-Stress and example scenes."""
    defaults = TrainConfig.from_dict(benchmark_defaults(benchmark) if benchmark == "site" else {})
    return dataclasses.asdict(defaults.env.observation)


def check_benchmark_layout(path: str | Path, config: TrainConfig, benchmark: str) -> None:
    """CheckpointError naming ``path`` and both layouts when the checkpoint trained under ``config`` on another
    benchmark reads another observation layout than ``benchmark``'s scenes need (e.g. a site checkpoint for the
    Factorial scenes). A checkpoint trained on ``benchmark`` itself plans its scenes whatever its layout: the
    representation ablations of Table III (no added input, BEV) train there with layouts of their own."""
    from np_policy.checkpoint import check_layout

    if config.benchmark == benchmark:
        return
    check_layout(path, dataclasses.asdict(config.env.observation), benchmark_layout(benchmark),
                 f"trained on {config.benchmark!r}", f"benchmark {benchmark!r}")


ACTIONS = ("mean", "sample")
"""How a NeuralParker planner acts: the policy's mean action (the paper's planner, spec §7) or one sampled action
per arc (each arc ``clip(μ(o) + σ·ε, −1, 1)``: what a Tianshou PPO policy plays at test time unless it is built
with ``deterministic_eval=True``)."""

OVER_CAPACITY = ("nearest", "refuse")
"""What a NeuralParker planner does with a scene of more obstacles than its slots (``NeuralParkerConfig``)."""

RescueRound = tuple[int, float, str]
"""One rescue round: (rollouts, standard-deviation scale, first arc 'policy' or 'uniform')."""


def rescue_round(spec) -> RescueRound:
    """A rescue round as (n, scale, first_arc) from (n, scale[, first_arc]), the first arc 'policy' when left out;
    ConfigError naming what is wrong otherwise."""
    spec = tuple(spec)
    if len(spec) not in (2, 3):
        raise ConfigError(f"NeuralParkerConfig.rescue: a rescue round is (n, scale[, first_arc]), got {spec!r}")
    n, scale, first_arc = (*spec, "policy")[:3]
    if isinstance(n, bool) or int(n) != n or int(n) < 1 or not scale > 0:
        raise ConfigError(f"NeuralParkerConfig.rescue: rescue rounds must be (n >= 1, scale > 0), got {spec!r}")
    if first_arc not in FIRST_ARCS:
        raise ConfigError(f"NeuralParkerConfig.rescue: a rescue round's first arc must be one of {FIRST_ARCS}, "
                          f"got {spec!r}")
    return int(n), float(scale), first_arc


@dataclass(frozen=True)
class NeuralParkerConfig:
    """How a NeuralParker planner plays its policy (``np_policy.planner``); the named presets are ``PRESETS``.

    The mean rollout alone (``samples=0``, no rescue rounds) is the paper's planner. ``samples`` adds that many
    seeded sampled rollouts and returns the best by ``weights`` (`np_policy.sampling.choose`); each rescue round
    ``(n, scale, first_arc)`` runs, in order, only while no rollout so far has succeeded (or, with
    ``rescue_clearance_m``, the chosen plan keeps less clearance than that; after the first round, than
    ``rescue_stop_m`` when set): ``n`` more rollouts at the policy's standard deviation times ``scale``, their first
    arc drawn by the policy or uniformly over the action box; ``rollout_max_arcs`` bounds every sampled rollout."""

    connector: str | None = None
    """Terminal connector: 'fixed', 'ensemble' or 'centred' replaces the checkpoint's
    (`np_sim.config.ConnectorConfig.variant`; paper §III-E: the 81-candidate ensemble is an evaluation-only swap);
    None keeps it."""
    action: str = "mean"
    """'mean' (the deterministic planner) or 'sample' (one rollout of sampled actions, its noise seeded by
    ``seed`` and the start pose), ``ACTIONS``."""
    samples: int = 0
    """Sampled rollouts beside the mean rollout; the best of all is returned (0 = the mean rollout only)."""
    rescue: tuple[tuple, ...] = ()
    """Wider rounds after a failure: (rollouts, standard-deviation scale[, first arc 'policy' (default) or
    'uniform']) each, kept as full ``RescueRound`` triples (`rescue_round` checks each)."""
    rescue_clearance_m: float = 0.0
    """The rescue rounds also run while the chosen plan's clearance level (the ``weights.margins_m`` ladder) is
    below this (m); 0 = only after a failure."""
    rescue_stop_m: float | None = None
    """After a rescue round the remaining rounds are skipped once the chosen plan succeeds and keeps this clearance
    level (m, at most ``rescue_clearance_m``; 0 = any validated plan): a bound on the rounds of a call whose first
    rescue round found a plan. None = the later rounds run on the first round's rule, ``rescue_clearance_m``."""
    rollout_max_arcs: int | None = None
    """Arc budget of the ``samples`` rollouts, the rescue rounds', the grown-body mean rollout's and the guarded
    rollout's (at most the checkpoint env's ``episode.max_arcs``): one still running after this many arcs ends as a
    timeout, so the rounds step at most (``samples`` + the rescue rounds' rollouts) × this many envs per call. None =
    the env's budget (200 arcs for the site checkpoints), which the plain mean rollout keeps unless ``mean_capped``."""
    mean_capped: bool = False
    """Anytime play (with ``accept_mean_m``), beyond the paper: the plain mean rollout keeps ``rollout_max_arcs`` too,
    so a call whose mean rollout wanders stops it there (a timeout) instead of at the env's budget; only a rollout
    that would end after that many arcs changes. False = the env's budget, as the paper's planner plays it."""
    accept_mean_m: float | None = None
    """Anytime play: the mean rollout is returned at once, before any sampling, when it succeeds, passes the
    validation, is steerable (``weights.curvature_tolerance``) and keeps its footprint grown by this (m) off every
    obstacle along the whole path; otherwise the sampled and rescue rounds run as without it, the validated mean
    rollout among their candidates. None = always sample (best of all)."""
    accept_aligned: bool = False
    """Anytime play (with ``accept_mean_m``): the anytime test also requires the plan to end within
    ``weights.heading_slack_deg`` of the target's heading, so a plan ending at the edge of the parking tolerance
    (the connector's 80° and 100° candidates) goes to the sampled round, whose cost charges it."""
    mean_margin_m: float = 0.0
    """Anytime play (with ``accept_mean_m``): the mean rollout is first played in the env with the footprint grown by
    this on every side (m; the policy observes the grown body and the checks use it, so a success keeps about this
    much clearance) and returned when the anytime test accepts it; otherwise the plain mean rollout follows as
    without it, and both are candidates of the sampled round. Skipped where the grown body's start is in collision.
    It keeps the arc budget ``rollout_max_arcs`` (the plain mean rollout the env's, unless ``mean_capped``). 0 =
    the plain mean rollout only."""
    guard_sigmas: tuple[float, ...] = ()
    """Anytime play (with ``accept_mean_m``): after the grown-body mean rollout and before the plain one, the guarded
    mean rollout (`np_policy.guarded`: each arc, of the mean action and offsets of these multiples of the policy's
    standard deviation, the first that parks within ``weights.heading_slack_deg`` of the target's heading, else the
    first that neither collides nor parks, else any park), in the env of the grown-body mean rollout
    (``mean_margin_m``; the plain env without one), with the arc budget ``rollout_max_arcs``; returned when the
    anytime test accepts it, otherwise a candidate of the sampled round. () = no guarded rollout (the presets:
    measured on training clips, it cost closed-loop success; docs/best_of_n.md, 2026-12-06)."""
    search_margin_m: float | None = None
    """Anytime play (with ``accept_mean_m``), beyond the paper: after the mean rollouts and before the sampled round,
    a Hybrid A* search (`np_sim.planners.HybridAStar`, footprint convention, swept exactly) for the footprint grown by
    this on every side (m); its plan answers the call (stage 'search') when the anytime test accepts it with the
    real body, otherwise the rounds run as without it. None = no search."""
    search_max_expanded: int = 2000
    """Node budget of that search: it gives up after this many expansions (no wall-time budget, so the answer does
    not depend on the machine's speed or load). 2,000 expansions took about 50 ms here when it was set (about 40 ms
    since Hybrid A* computes a node's Reeds–Shepp term only when it pops it), the 90th-percentile call time the
    footprint planner aims at; on the first frames of the 94 validation training clips that the mean rollouts do not
    answer, the search's successes for the body grown by 0.2 m took a median of 21 expansions, and 35 of its 39 took
    fewer than 2,000."""
    search_steer_cost_m: float | None = None
    """Cost per primitive at full curvature of that search (`HybridAStarConfig.steer_cost_m`, m). None = the
    choice's own drive-time price of it (`np_policy.sampling.curve_surcharge` of a primitive at κ_max: 0.65 m for
    the site's sedan), so the search, like the sampled round's choice, prefers plans that are quick to drive rather
    than short (Hybrid A*'s default, 0.1 m, made plans that ran out of the clip runs' 60 s)."""
    start_limited_clearance: bool = False
    """The clearance the anytime test (``accept_mean_m``), the rescue for clearance (``rescue_clearance_m``,
    ``rescue_stop_m``) and the search (``search_margin_m``) ask of a call's plans is capped by the clearance level of
    its start pose (the ``weights.margins_m`` ladder, 0 below its lowest rung): a plan never keeps more than its
    start, so rounds run to find more from a start closer than that to an object are wasted."""
    target_limited_clearance: bool = False
    """The same cap by the clearance level of the scene's target pose: a plan ends at the target, so it keeps no
    more than the target pose does, and where a slot leaves less than the wanted clearance beside the parked car,
    the search for the grown body cannot succeed and spent its whole node budget (on the first 94 difficult training
    clips, 32 of its 38 failed calls)."""
    margin_m: float = 0.0
    """The rollouts' collision checks use the footprint grown by this on every side (m,
    `np_sim.vehicle.VehicleSpec.inflated`); the choice's costs and the validation see the real body."""
    seed: int = 0
    """Seed of the sampled rollouts (rescue round k: ``seed + 1 + k``) and of ``action='sample'``."""
    weights: ChoiceWeights = field(default_factory=ChoiceWeights)
    """How the best plan is chosen (`np_policy.sampling.ChoiceWeights`)."""
    over_capacity: str = "nearest"
    """A scene with more obstacles than the policy's slots: 'nearest' observes the nearest ones, re-selected after
    every arc, while every check stays on the whole scene (the site's rule, `np_sim.nearest`); 'refuse' raises
    CapacityError. A scene within the slots is observed whole either way."""

    def __post_init__(self) -> None:
        if self.over_capacity not in OVER_CAPACITY:
            raise ConfigError(f"NeuralParkerConfig.over_capacity: expected one of {OVER_CAPACITY}, got "
                              f"{self.over_capacity!r}")
        if self.connector is not None and self.connector not in CONNECTOR_VARIANTS:
            raise ConfigError(f"NeuralParkerConfig.connector: expected one of {CONNECTOR_VARIANTS} or None, got "
                              f"{self.connector!r}")
        if self.action not in ACTIONS:
            raise ConfigError(f"NeuralParkerConfig.action: expected one of {ACTIONS}, got {self.action!r}")
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 0:
            raise ConfigError(f"NeuralParkerConfig.samples: expected an integer >= 0, got {self.samples!r}")
        object.__setattr__(self, "rescue", tuple(rescue_round(spec) for spec in self.rescue))
        if self.action == "sample" and (self.samples or self.rescue):
            raise ConfigError(f"NeuralParkerConfig.action: 'sample' plays one sampled rollout; it does not combine "
                              f"with samples ({self.samples}) or rescue rounds ({list(self.rescue)})")
        for name in ("rescue_clearance_m", "margin_m", "mean_margin_m", "accept_mean_m", "rescue_stop_m",
                     "search_margin_m", "search_steer_cost_m"):
            value = getattr(self, name)
            if value is None and name in ("accept_mean_m", "rescue_stop_m", "search_margin_m", "search_steer_cost_m"):
                continue
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"NeuralParkerConfig.{name}: expected a finite number >= 0 m, got {value!r}")
        for name in ("start_limited_clearance", "target_limited_clearance", "accept_aligned"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(f"NeuralParkerConfig.{name}: expected true or false, got {getattr(self, name)!r}")
        if self.accept_aligned and self.accept_mean_m is None:
            raise ConfigError("NeuralParkerConfig.accept_aligned: a heading condition on the anytime test needs "
                              "accept_mean_m (the anytime test), got None")
        if self.mean_margin_m and self.accept_mean_m is None:
            raise ConfigError(f"NeuralParkerConfig.mean_margin_m: a grown-body mean rollout ({self.mean_margin_m:g} m) "
                              "is an anytime answer; it needs accept_mean_m (the anytime test), got None")
        sigmas = self.guard_sigmas
        if not (isinstance(sigmas, (tuple, list)) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                          and math.isfinite(v) and v > 0 for v in sigmas)):
            raise ConfigError(f"NeuralParkerConfig.guard_sigmas: expected a list of finite numbers > 0 (multiples of "
                              f"the policy's standard deviation), got {sigmas!r}")
        object.__setattr__(self, "guard_sigmas", tuple(float(v) for v in sigmas))
        if self.guard_sigmas and self.accept_mean_m is None:
            raise ConfigError(f"NeuralParkerConfig.guard_sigmas: a guarded rollout ({list(self.guard_sigmas)}) is an "
                              "anytime answer; it needs accept_mean_m (the anytime test), got None")
        if self.search_margin_m is not None and self.accept_mean_m is None:
            raise ConfigError(f"NeuralParkerConfig.search_margin_m: a search answer ({self.search_margin_m:g} m) is an "
                              "anytime answer; it needs accept_mean_m (the anytime test), got None")
        if (isinstance(self.search_max_expanded, bool) or not isinstance(self.search_max_expanded, int)
                or self.search_max_expanded < 1):
            raise ConfigError(f"NeuralParkerConfig.search_max_expanded: expected an integer >= 1, got "
                              f"{self.search_max_expanded!r}")
        if not isinstance(self.mean_capped, bool):
            raise ConfigError(f"NeuralParkerConfig.mean_capped: expected true or false, got {self.mean_capped!r}")
        if self.mean_capped and (self.accept_mean_m is None or self.rollout_max_arcs is None):
            raise ConfigError("NeuralParkerConfig.mean_capped: capping the plain mean rollout needs anytime play "
                              f"(accept_mean_m, got {self.accept_mean_m!r}) and an arc budget (rollout_max_arcs, got "
                              f"{self.rollout_max_arcs!r})")
        if self.rescue_stop_m is not None and self.rescue_stop_m > self.rescue_clearance_m:
            raise ConfigError(f"NeuralParkerConfig.rescue_stop_m: expected at most rescue_clearance_m "
                              f"({self.rescue_clearance_m:g} m), got {self.rescue_stop_m!r}")
        if self.rollout_max_arcs is not None and (isinstance(self.rollout_max_arcs, bool)
                                                  or not isinstance(self.rollout_max_arcs, int)
                                                  or self.rollout_max_arcs < 1):
            raise ConfigError(f"NeuralParkerConfig.rollout_max_arcs: expected an integer >= 1 or None, got "
                              f"{self.rollout_max_arcs!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"NeuralParkerConfig.seed: expected an integer >= 0, got {self.seed!r}")

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "NeuralParkerConfig":
        """Inverse of ``to_dict``; unknown keys and values of the wrong type are a ConfigError."""
        check_types(cls, data)
        return config_from_dict(cls, data)

    @classmethod
    def preset(cls, name: str) -> "NeuralParkerConfig":
        """The preset called ``name`` (``PRESETS``); ConfigError listing them otherwise."""
        if name not in PRESETS:
            raise ConfigError(f"NeuralParkerConfig: expected a preset name, one of {sorted(PRESETS)}, got {name!r}")
        return PRESETS[name]


PAPER = NeuralParkerConfig()
"""The paper's planner (§III-A, spec §7): the policy's mean action rolled out once, the checkpoint's connector."""

FOOTPRINT_BEST_OF_N = NeuralParkerConfig(
    connector="centred", samples=32, rescue=((128, 2.0, "policy"), (128, 3.0, "policy"), (128, 1.0, "uniform")),
    rescue_clearance_m=0.2)
"""The footprint-aware site planner of the closed loop (beyond the paper): the best of the mean rollout and 32
sampled rollouts by steerability, then drive time, reversal, clearance and terminal-heading cost; three rescue
rounds (128 rollouts at 2 σ, 128 at 3 σ, 128 with a uniform first arc then 1 σ) while none succeeds or the best
keeps less than 0.2 m of clearance; the centred connector order.

Tuned on the first 94 difficult **training** clips of the site (``python -m experiments.closed_loop --clips
--split train-difficult --clips-limit 94 --planners neuralparker_footprint``), never on the held-out clips;
executed footprint success, standard error about 0.04: mean action only 0.59; best of 16 0.73, of 32 0.81 with a
length cost and 0.83 with the drive-time cost, of 64 0.78; noise σ × 1.5 0.82, × 0.7 0.78; the centred connector
order 0.82 (neutral here; chosen from the near-target cycles of three held-out clips, where the paper's order ends
plans on the edge of the 10° parking tolerance); the two policy rescue rounds 0.86 (256 rollouts each: 0.86); the
rescue for clearance below 0.2 m 0.89 (0.1 m: 0.91 vs 0.93 with ``--set clip_run.stitch=true
clip_run.track_window=5``); the third round with uniform first arcs 0.90 (64 rollouts or 2 σ: 0.89).
``docs/planners.md`` has the whole table."""

FOOTPRINT_ANYTIME = dataclasses.replace(FOOTPRINT_BEST_OF_N, accept_mean_m=FOOTPRINT_BEST_OF_N.weights.wanted_margin_m,
                                        rollout_max_arcs=50, mean_margin_m=0.2)
"""The footprint best-of-N planner played anytime: the mean rollout is returned at once when it succeeds, passes
the validation, is steerable and keeps the choice's wanted margin (0.2 m) off every obstacle; otherwise the answer
is 'footprint_best_of_n''s with its sampled and rescue rollouts cut at 50 arcs. The acceptance margin is the
choice's own wanted clearance, not a tuned number: a mean rollout that keeps it already costs no clearance term, so
sampling could only shorten it. The arc budget bounds a call at 416 rollouts × 50 arcs (the env's own budget is
200): on the 94 difficult training clips it changed no run, on the ten training clips with the slowest runs of the
next 210 it parked one more and cut their planning time by 43 % (docs/best_of_n.md, 2026-12-03). The mean rollout
is first played with the body grown by 0.2 m (``mean_margin_m``): on the first frames of the 94 validation training
clips it answered 50 calls where the plain mean rollout answered 36 (0.1 m: 37, 0.3 m: 46), median call 38.3 →
5.6 ms (docs/best_of_n.md, 2026-12-03)."""

FOOTPRINT_SEARCH = dataclasses.replace(FOOTPRINT_ANYTIME, search_margin_m=FOOTPRINT_ANYTIME.accept_mean_m,
                                       start_limited_clearance=True, target_limited_clearance=True, mean_capped=True)
"""'footprint_anytime' with a Hybrid A* search between its mean rollouts and its sampled round (beyond the paper; a
learned-first hybrid, not the learned planner alone): the footprint grown by the anytime test's 0.2 m, at most 2,000
expansions, steering priced at its drive time, its plan returned when the anytime test accepts it; and the
clearance asked of a call's plans capped at its start pose's and its target pose's. On the 188 difficult training
clips (docs/best_of_n.md, 2026-12-06): footprint success 174 against the anytime preset's 170, calls answered by the
rescue rounds 168 → 50 with the start cap alone; with the target cap too, 175 and 11 rescue calls (the search's
failures, each spending its whole node budget, 38 → 6 on the first 94). Its plain mean rollout keeps the 50-arc budget
(``mean_capped``): on the same clips the same 175 parked, clip for clip, and 44 of the 157 calls past the mean stage no
longer first play a 200-arc wandering mean rollout (about 25 ms each; docs/best_of_n.md, 2026-12-06 evening)."""

PRESETS: dict[str, NeuralParkerConfig] = {"paper": PAPER, "footprint_best_of_n": FOOTPRINT_BEST_OF_N,
                                          "footprint_anytime": FOOTPRINT_ANYTIME,
                                          "footprint_search": FOOTPRINT_SEARCH}
"""Named NeuralParker configurations; a variant is ``dataclasses.replace(PRESETS[name], field=value)``."""
