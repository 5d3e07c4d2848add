"""The testbed's planners by name: one registry of factories and display labels, shared by the experiment CLIs
(`experiments.planners`, `experiments.track`, `experiments.closed_loop`).

Every planner follows `np_sim.planners.protocol.Planner` (``plan(scene, start) -> Plan``, ``convention``,
``name``). A CLI picks planners by name and builds them with ``build_planners(names, options)``: one
`PlannerOptions` says which checkpoints the learned planners load, how NeuralParker plays its policy (a
`np_policy.config.NeuralParkerConfig`, by default a named preset) and which convention and margin the searches
use. Learned planners built together share one loaded policy per checkpoint.

Adding a planner is one entry. Write a factory taking the options and the shared policy loader, importing the
planner's module inside it (so a CLI loads only what it runs), and add one line to ``REGISTRY`` (the adapted HOPE
entry, ``_hope``, is an example). The planner class carries ``name`` and its ``convention``; every CLI then offers it
in its planner choices and labels its rows with the entry's label. A planner that needs a setting the options lack
adds one field to `PlannerOptions`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from np_policy.config import FOOTPRINT_ANYTIME, FOOTPRINT_SEARCH, PAPER, NeuralParkerConfig
from np_sim.config import Convention
from np_sim.errors import ConfigError
from np_sim.planners.protocol import CONVENTIONS, Planner
from np_sim.vehicle import VehicleSpec

PolicyLoader = Callable[[Path], object]
"""``load(path) -> np_policy.planner.Policy``: the policy stored in ``path``, loaded once per ``build_planners``."""


@dataclass(frozen=True)
class PlannerOptions:
    """What the registry's factories build planners from (each CLI fills in its own defaults)."""

    checkpoint: Path | None = None
    """Policy checkpoint of the learned planners: NeuralParker, NP-Guided A*'s guide, the staged planner's second
    stage."""
    neuralparker: NeuralParkerConfig = PAPER
    """How those planners play the policy (default the 'paper' preset)."""
    footprint_checkpoint: Path | None = None
    """Checkpoint of 'neuralparker_footprint' and 'neuralparker_search' (the footprint-aware site policy)."""
    neuralparker_footprint: NeuralParkerConfig = FOOTPRINT_ANYTIME
    """How 'neuralparker_footprint' plays its policy (default the 'footprint_anytime' preset: best of N, the mean
    rollout returned at once when it keeps 0.2 m)."""
    neuralparker_search: NeuralParkerConfig = FOOTPRINT_SEARCH
    """How 'neuralparker_search' plays the same policy (default the 'footprint_search' preset: the anytime preset
    with a Hybrid A* search for the grown body between its mean rollouts and its sampled round)."""
    convention: Convention = "reference_point"
    """Collision convention of the searches (Hybrid A*, NP-Guided A*, the staged prefix, OMPL RRT*)."""
    search_margin_m: float = 0.0
    """Hybrid A* and NP-Guided A*'s search plan for the footprint grown by this on every side (m)."""
    search_time_budget_s: float = 1.0
    """Wall-time budget of one search query (s; `HybridAStarConfig.time_budget_s`, also OMPL RRT*'s). A query stops
    at this or at its node budget, whichever comes first: give a budget it never reaches (e.g. 1000) for search
    results that do not depend on the machine's speed or load."""
    ompl_seed: int = 0
    """OMPL's random seed."""
    hope_checkpoint: Path | None = None
    """Checkpoint of 'hope', the adapted HOPE baseline (`hope_policy.train`'s ``final.pt``), also the second stage of
    'staged_astar_hope'."""
    hope_action: str = "sampled"
    """How 'hope' and 'staged_astar_hope' play the adapted HOPE's policy: 'sampled' (HOPE's evaluation protocol, the
    default) or 'mean' (`hope_policy.planner`)."""
    hope_seed: int = 0
    """Seed of the adapted HOPE's sampled actions (each plan's draws also depend on its start pose)."""
    benchmark: str | None = None
    """The scenes the planners will plan ('factorial', 'topology', 'examples', 'site'): a checkpoint of another
    observation layout is refused when loaded; None checks nothing."""
    vehicle: VehicleSpec = field(default_factory=VehicleSpec)
    """The vehicle planned for: the searches' footprint and κ_max; a learned planner's checkpoint trained for
    another vehicle is refused when loaded."""

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise ConfigError(f"PlannerOptions.convention: expected one of {CONVENTIONS}, got {self.convention!r}")
        if not self.search_margin_m >= 0:
            raise ConfigError(f"PlannerOptions.search_margin_m: expected >= 0 m, got {self.search_margin_m!r}")
        if not (isinstance(self.search_time_budget_s, (int, float)) and 0 < self.search_time_budget_s < math.inf):
            raise ConfigError(f"PlannerOptions.search_time_budget_s: expected a finite number of seconds > 0, got "
                              f"{self.search_time_budget_s!r}")


Factory = Callable[[PlannerOptions, PolicyLoader], Planner]
"""``factory(options, load) -> Planner``."""


@dataclass(frozen=True)
class Entry:
    """One planner kind of the registry."""

    label: str
    """Display label of its table rows."""
    factory: Factory
    """Builds the planner."""


def required_checkpoint(path: Path | None, name: str, how: str = "--checkpoint PATH") -> Path:
    """``path`` when it exists; FileNotFoundError naming the planner and how to pass one (``how``) otherwise."""
    if path is None:
        raise FileNotFoundError(f"planner {name} needs a policy checkpoint; pass {how}")
    if not Path(path).exists():
        raise FileNotFoundError(f"planner {name}: its checkpoint {path} does not exist; pass {how} or leave {name} "
                                f"out of the planners")
    return Path(path)


def _search(options: PlannerOptions):
    from np_sim.planners import HybridAStar, HybridAStarConfig

    config = HybridAStarConfig(vehicle=options.vehicle.inflated(options.search_margin_m),
                               time_budget_s=options.search_time_budget_s)
    return HybridAStar(config, convention=options.convention)


def _learned(options: PlannerOptions, load: PolicyLoader, name: str):
    from np_policy.planner import NeuralParkerPlanner

    return NeuralParkerPlanner(load(required_checkpoint(options.checkpoint, name)), options.neuralparker)


def _hybrid_astar(options: PlannerOptions, load: PolicyLoader) -> Planner:
    return _search(options)


def _np_guided_astar(options: PlannerOptions, load: PolicyLoader) -> Planner:
    from np_policy.staged import NPGuidedAStar

    return NPGuidedAStar(_learned(options, load, "np_guided_astar"), _search(options))


def _staged_astar_np(options: PlannerOptions, load: PolicyLoader) -> Planner:
    from np_policy.staged import StagedPlanner

    return StagedPlanner(_learned(options, load, "staged_astar_np"), _search(options))


def _staged_astar_hope(options: PlannerOptions, load: PolicyLoader) -> Planner:
    from np_policy.staged import StagedPlanner

    return StagedPlanner(_hope(options, load), _search(options), name="staged_astar_hope")


def _ompl_rrtstar(options: PlannerOptions, load: PolicyLoader) -> Planner:
    from np_sim.planners.ompl_peer import OmplPeer, OmplPeerConfig

    budget = _search(options).config.time_budget_s
    return OmplPeer(OmplPeerConfig(time_budget_s=budget, seed=options.ompl_seed, vehicle=options.vehicle),
                    options.convention)


def _neuralparker(options: PlannerOptions, load: PolicyLoader) -> Planner:
    return _learned(options, load, "neuralparker")


def _footprint_policy(options: PlannerOptions, load: PolicyLoader, name: str, config: NeuralParkerConfig) -> Planner:
    from np_policy.planner import NeuralParkerPlanner

    path = required_checkpoint(options.footprint_checkpoint, name, "--set planner.footprint_checkpoint=PATH")
    return NeuralParkerPlanner(load(path), config)


def _neuralparker_footprint(options: PlannerOptions, load: PolicyLoader) -> Planner:
    return _footprint_policy(options, load, "neuralparker_footprint", options.neuralparker_footprint)


def _neuralparker_search(options: PlannerOptions, load: PolicyLoader) -> Planner:
    return _footprint_policy(options, load, "neuralparker_search", options.neuralparker_search)


def _hope(options: PlannerOptions, load: PolicyLoader) -> Planner:
    from hope_policy.planner import HopePlanner
    from np_policy.checkpoint import check_vehicle

    path = required_checkpoint(options.hope_checkpoint, "hope", "--hope-checkpoint PATH")
    planner = HopePlanner.from_checkpoint(path, options.hope_action, options.hope_seed)
    check_vehicle(path, planner.config.env.vehicle, options.vehicle)
    return planner


REGISTRY: dict[str, Entry] = {
    "hybrid_astar": Entry("Hybrid A*", _hybrid_astar),
    "np_guided_astar": Entry("NP-Guided A*", _np_guided_astar),
    "ompl_rrtstar": Entry("OMPL RRT*", _ompl_rrtstar),
    "neuralparker": Entry("NeuralParker", _neuralparker),
    "neuralparker_footprint": Entry("NeuralParker (footprint)", _neuralparker_footprint),
    "neuralparker_search": Entry("NeuralParker (footprint) + search", _neuralparker_search),
    "staged_astar_np": Entry("Hybrid A* → NP", _staged_astar_np),
    "hope": Entry("Adapted HOPE", _hope),
    "staged_astar_hope": Entry("Hybrid A* → HOPE", _staged_astar_hope),
}
"""Every planner kind by name (module docstring: how to add one)."""


def label(name: str) -> str:
    """The display label of planner ``name``."""
    return REGISTRY[name].label


def check_names(names, allowed=None) -> list[str]:
    """``names`` as a list; ConfigError naming the unknown ones and the known ones (``allowed``, default all)."""
    allowed = list(REGISTRY if allowed is None else allowed)
    unknown = [n for n in names if n not in allowed]
    if unknown:
        raise ConfigError(f"unknown planner(s) {unknown}; expected some of {allowed}")
    return list(names)


def build_planners(names, options: PlannerOptions) -> dict[str, Planner]:
    """One planner per name, in order (FileNotFoundError when a learned planner's checkpoint is missing,
    CheckpointError when it is broken, of another observation layout than ``options.benchmark``'s or trained for
    another vehicle than ``options.vehicle``)."""
    from np_policy.planner import Policy

    check_names(names)
    load = functools.cache(lambda path: Policy.load(path, options.benchmark, options.vehicle))
    return {name: REGISTRY[name].factory(options, load) for name in names}
