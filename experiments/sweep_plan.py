"""The reproduction sweep's plan and the state of its run folders (no Ray here; `experiments.sweep` runs it).

A **plan** is a list of `Configuration` rows; each expands, per seed, to one `RunSpec`: a (configuration,
benchmark, seed) with its own run folder under the run root. A configuration's training config is a JSON file of
`TrainConfig` overrides in ``checkpoints/configs/``; every NeuralParker row of the Factorial and Topology-Stress
benchmarks merges its file over one shared recipe, ``checkpoints/configs/recipe.json`` (paper Table
``tab:app-ppo`` with the whole-lot reading of the geodesic curriculum, the file the shipped Factorial seeds were
trained with as ``lot.json``). The adapted-HOPE row is trained by ``hope_policy.train`` from a file of
`hope_policy.train.HopeTrainConfig` fields (its progress counted in episodes, its finished checkpoint ``final.pt``;
`TRAINERS`), and so are the three HOPE-style backbones of Table III (``topology_hope_{none,bev,vertices}.json``). A
configuration that cannot be trained today is in the plan with the reason, so it is listed as "not available yet"
and never silently dropped; so is one whose input file (`Configuration.requires`, e.g. a pretrained BEV
autoencoder) does not exist yet, with the command that makes it.

A run's **state** is read from its folder alone (`run_state`), never by loading a checkpoint:

- *finished*: ``metrics.jsonl``'s last complete row is epoch ``ppo.epochs`` of the run's config and ``best.pt``
  exists (the trainer appends the row, then writes ``best.pt`` and the final ``snapshot.pt``); for the adapted
  HOPE, the last row has counted ``episodes`` of its config and ``final.pt`` exists;
- *interrupted*: ``snapshot.pt`` exists but the last row is an earlier epoch; the sweep resumes it (``--resume``);
- *started, no snapshot*: run files (``metrics.jsonl``, ``best.pt``) but no ``snapshot.pt`` (killed before its
  first snapshot): nothing to resume, the sweep trains it from epoch 0 with ``--overwrite`` (which replaces those
  files);
- *not started*: none of the trainer's run files (`holds_run_files`);
- *training now*: a ``np_policy.train`` process on this machine writes the folder (the sweep leaves it alone);
- *config differs*: the folder's ``config.json`` is another configuration (the sweep refuses to touch it);
- *not available yet*: the configuration cannot be trained today, or a file it requires does not exist yet.
"""

from __future__ import annotations

import importlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from np_sim.config import config_from_dict
from np_sim.errors import ConfigError

CONFIG_DIR = Path(__file__).resolve().parent.parent / "checkpoints" / "configs"
"""Where the sweep's configuration files live (committed)."""
RECIPE_FILE = "recipe.json"
"""The one NeuralParker recipe every Factorial and Topology-Stress NeuralParker row merges its overrides over."""
FACTORIAL_EPOCH_S = 75.3
"""Seconds per epoch of the Factorial recipe on this machine, on one thread beside one other one-thread run
(compute estimates): the median ``epoch_s`` of ``factorial_np_fixed_seed0_lot``'s first 29 epochs (66.9 s at
least). The shipped seeds' 46.8 s was the machine's two cores for one run. A run started with ``--shared-geometry``
took a median 54.3 s over its first 5 epochs beside it."""
TOPOLOGY_NP_EPOCH_S = {"none": 41.0, "bev": 88.0, "vertices": 79.0}
"""Seconds per epoch of the NeuralParker-backbone Topology-Stress rows on this machine, each on one thread beside
one other one-thread run (compute estimates): the median ``epoch_s`` of the finished seed-0 runs (none 40.9 s,
vertices 79.3 s: the slot tokens' attention is the update's largest cost) and the BEV seed 0 run's first twelve
epochs (83–92 s: the raster and the frozen encoder at every step)."""
SITE_EPOCH_S = 83.0
"""Seconds per epoch of the site run on this machine: its last ten epochs (65,536 steps each, ``steps_per_s`` of
its ``metrics.jsonl``) took 81–88 s, about 5.5 h per 240-epoch run (compute estimates)."""
HOPE_EPISODE_S = 0.19
"""Seconds per adapted-HOPE training episode on this machine: the first two collects of 8,192 transitions (9.2 and
8.7 s of CPU time) and updates (47.4 and 52.3 s) of a run completed 316 and 310 episodes (compute estimates;
measured as process CPU time with the machine's two cores shared by other jobs, when the wall clock ran about ten
times longer)."""
HOPE_BACKBONE_EPISODE_S = {"none": 0.55, "bev": 0.9, "vertices": 0.34}
"""Seconds per training episode of the HOPE-style backbones of Table III on this machine (compute estimates): the
finished runs' wall-clock seconds (``collect_s + update_s`` summed over ``metrics.jsonl``) over their episodes.
none: 0.46 / 0.61 / 0.58 (seeds 0–2), BEV seed 0: 0.90, all beside other jobs whose threads spun against theirs
(`np_policy.threads`); vertices seed 0 (the attention-based branch): 0.34, on one thread beside a one-thread
training run, 56 min for 10,038 episodes. The backbones have no RS takeover, so their episodes are longer than the
adapted HOPE's (`HOPE_EPISODE_S`)."""
TRAINERS = {"np_policy.train": ("epoch", "best.pt"), "hope_policy.train": ("episodes", "final.pt")}
"""The modules that train a configuration (``python -m``): the ``metrics.jsonl`` field that counts a run's progress
and the file a finished run holds (its output, the checkpoint that is evaluated; `RunSpec.output`)."""
TABLES = {
    "main": "Fig. 3, main comparison on the Factorial benchmark",
    "staged": "Table II, unified versus staged planning",
    "representation": "Table III and Fig. 5, scene representation on Topology-Stress",
    "connector": "Table IV, terminal connector",
    "curriculum": "Table V, start curriculum",
    "site": "delivery-site closed loop (the paper-faithful site planner)",
}
"""``--only`` names: the experiment each group of runs feeds (one `experiments.<name>` module per table)."""


@dataclass(frozen=True)
class Configuration:
    """One row of a plan: a training configuration on one benchmark, run once per seed."""

    name: str
    """Run-name stem, e.g. ``factorial_np_fixed``."""
    benchmark: str
    """``np_policy.train --benchmark``."""
    tables: tuple[str, ...]
    """The `TABLES` this configuration's runs feed."""
    config_file: str | None = None
    """TrainConfig overrides in `CONFIG_DIR`; None when the configuration is not available yet."""
    missing: str = ""
    """Why the configuration is not available yet (with ``config_file`` None)."""
    recipe: bool = True
    """Merge the file over `RECIPE_FILE` (every NeuralParker row but the site's App. C configuration)."""
    seeds: tuple[int, ...] | None = None
    """Only these seeds exist in the plan (None: every requested seed)."""
    run_name: str = "{name}_seed{seed}"
    """Run folder name under the run root."""
    epoch_s: float = FACTORIAL_EPOCH_S
    """Estimated seconds per epoch (per episode for the adapted HOPE) on this machine."""
    trainer: str = "np_policy.train"
    """The module that trains it, a key of `TRAINERS`."""
    requires: tuple[tuple[str, str], ...] = ()
    """(file relative to the repository root, the command that makes it) pairs: inputs the training reads."""


_LOT = "{name}_seed{seed}_lot"
"""Run folders of the recipe's rows: the shipped Factorial seeds were named for the whole-lot curriculum."""
_TOPOLOGY_AE = (("checkpoints/bev/topology_ae_v2.pt",
                 "python -m np_policy.pretrain_bev --benchmark topology --out checkpoints/bev/topology_ae_v2.pt "
                 "--seed 0"),)
"""The BEV rows' autoencoder: ``v2``, pretrained on the raster without the off-image band (``topology_ae.pt`` was
pretrained on the banded one; its runs are kept as ``*_banded_raster``, docs/results/2026-12-08-bev-band)."""
PAPER_PLAN = (
    Configuration("factorial_np", "factorial", ("main", "staged", "connector", "curriculum"), "factorial_np.json",
                  run_name=_LOT),
    Configuration("factorial_np_fixed", "factorial", ("connector",), "factorial_np_fixed.json", run_name=_LOT),
    Configuration("factorial_np_nocurriculum", "factorial", ("curriculum",), "factorial_np_nocurriculum.json",
                  run_name=_LOT),
    Configuration("factorial_hope", "factorial", ("main", "staged"), "factorial_hope.json", recipe=False,
                  epoch_s=HOPE_EPISODE_S, trainer="hope_policy.train"),
    *(Configuration(f"topology_np_{added}", "topology", ("representation",), f"topology_np_{added}.json",
                    run_name=_LOT, epoch_s=TOPOLOGY_NP_EPOCH_S[added],
                    requires=_TOPOLOGY_AE if added == "bev" else ()) for added in ("none", "bev", "vertices")),
    *(Configuration(f"topology_hope_{added}", "topology", ("representation",), f"topology_hope_{added}.json",
                    recipe=False, epoch_s=HOPE_BACKBONE_EPISODE_S[added], trainer="hope_policy.train",
                    requires=_TOPOLOGY_AE if added == "bev" else ()) for added in ("none", "bev", "vertices")),
    Configuration("site_np", "site", ("site",), "site_np.json", recipe=False, seeds=(0,), epoch_s=SITE_EPOCH_S),
)
"""Every training run the paper's simulation tables need (``--plan paper``)."""
PLANS = {"paper": PAPER_PLAN}


def load_plan(plan: str) -> tuple[tuple[Configuration, ...], Path]:
    """``(configurations, config_dir)`` of a named plan (`PLANS`) or of a plan file: a JSON object
    ``{"configurations": [{"name", "benchmark", "tables", "config_file", ...}, ...]}`` with the `Configuration`
    fields, whose configuration files (and ``recipe.json``) lie beside it."""
    if plan in PLANS:
        return PLANS[plan], CONFIG_DIR
    path = Path(plan)
    if path.suffix != ".json":
        raise ConfigError(f"--plan: expected one of {sorted(PLANS)} or a plan .json file, got {plan!r}")
    rows = read_overrides(path).get("configurations")
    if not isinstance(rows, list) or not rows:
        raise ConfigError(f"{path}: expected a non-empty list under 'configurations'")
    configs = tuple(config_from_dict(Configuration, row, f"{path}: configurations[{i}]") for i, row in enumerate(rows))
    for i, config in enumerate(configs):
        where = f"{path}: configurations[{i}]"
        if not (isinstance(config.name, str) and config.name and isinstance(config.tables, tuple) and config.tables
                and all(isinstance(t, str) for t in config.tables)):
            raise ConfigError(f"{where}: expected a non-empty 'name' and a non-empty list of 'tables' (strings)")
        if config.config_file is None and not config.missing:
            raise ConfigError(f"{where}: give 'config_file', or 'missing' (why it is not available yet)")
        if config.trainer not in TRAINERS:
            raise ConfigError(f"{where}.trainer: expected one of {sorted(TRAINERS)}, got {config.trainer!r}")
        if not isinstance(config.run_name, str) or "{seed}" not in config.run_name:
            raise ConfigError(f"{where}.run_name: expected a folder name pattern with {{seed}} (and optionally "
                              f"{{name}}), got {config.run_name!r}")
    folders = [config.run_name.replace("{name}", config.name) for config in configs]
    for i, folder in enumerate(folders):
        if folder in folders[:i]:
            raise ConfigError(f"{path}: configurations[{i}]: its run folders {folder!r} are those of "
                              f"configurations[{folders.index(folder)}] too")
    return configs, path.parent


@dataclass(frozen=True)
class RunSpec:
    """One training run of a plan."""

    config: Configuration
    seed: int
    run_dir: Path
    overrides: dict[str, Any] | None
    """The TrainConfig overrides given to ``np_policy.train --config`` (None: not available yet)."""
    epochs: int | None
    """The recipe's ``ppo.epochs``, the adapted HOPE's ``episodes`` (None: not available yet)."""

    @property
    def name(self) -> str:
        """The run folder's name."""
        return self.run_dir.name

    @property
    def output(self) -> Path:
        """The checkpoint a finished run holds and the reproduction evaluates (`TRAINERS`): NeuralParker's selected
        ``best.pt``, the adapted HOPE's ``final.pt``."""
        return self.run_dir / TRAINERS[self.config.trainer][1]


@dataclass(frozen=True)
class RunState:
    """What a run folder holds (see the module docstring for each ``kind``)."""

    kind: str
    epoch: int = 0
    """Last complete epoch in metrics.jsonl."""
    detail: str = ""
    pid: int | None = None
    """The trainer's process id while the run is "training now"."""


def read_overrides(path: Path) -> dict[str, Any]:
    """A sweep file's JSON object (a configuration's overrides, a plan); a missing or malformed file is a
    ConfigError naming it."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read this sweep file: {exc}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a JSON object, got {type(data).__name__}")
    return data


def resolved_config(benchmark: str, seed: int, overrides: dict[str, Any], trainer: str = "np_policy.train"):
    """The `TrainConfig` ``np_policy.train --benchmark B --seed S --config FILE`` builds from ``overrides`` (the
    `HopeTrainConfig` of ``hope_policy.train`` with ``trainer='hope_policy.train'``)."""
    from np_policy.train import TrainConfig, benchmark_defaults, merge_config

    if trainer == "hope_policy.train":
        from hope_policy.train import HopeTrainConfig

        return HopeTrainConfig.from_dict({**overrides, "benchmark": benchmark, "seed": seed})

    data = merge_config(benchmark_defaults(benchmark), overrides)
    data.update(benchmark=benchmark, seed=seed)
    return TrainConfig.from_dict(data)


def expand(plan, seeds, root: Path, only=None, config_dir: Path = CONFIG_DIR) -> list[RunSpec]:
    """The runs of ``plan`` for ``seeds`` under ``root``, restricted to configurations feeding a table of ``only``
    (None: all); every configuration's file is read and its config validated here, so a bad file fails early."""
    tables = {table for config in plan for table in config.tables}
    unknown = sorted(set(only or ()) - tables)
    if unknown:
        raise ConfigError(f"--only: unknown table(s) {unknown}; expected some of {sorted(tables)}")
    if any(seed < 0 for seed in seeds):
        raise ConfigError(f"--seeds: expected non-negative integers, got {list(seeds)}")
    recipe = None
    runs = []
    for config in plan:
        if only and not set(config.tables) & set(only):
            continue
        overrides = None
        if config.config_file is not None:
            overrides = read_overrides(Path(config_dir) / config.config_file)
            if config.recipe:
                from np_policy.train import merge_config

                recipe = read_overrides(Path(config_dir) / RECIPE_FILE) if recipe is None else recipe
                overrides = merge_config(recipe, overrides)
        for seed in dict.fromkeys(seeds):
            if config.seeds is not None and seed not in config.seeds:
                continue
            epochs = None
            if overrides is not None:
                try:
                    resolved = resolved_config(config.benchmark, seed, overrides, config.trainer)
                    epochs = resolved.episodes if config.trainer == "hope_policy.train" else resolved.ppo.epochs
                except ConfigError as exc:
                    raise ConfigError(f"{Path(config_dir) / config.config_file}: {exc}") from None
            run_dir = Path(root) / config.run_name.format(name=config.name, seed=seed)
            runs.append(RunSpec(config, seed, run_dir, overrides, epochs))
    return runs


def metrics_rows(path: Path) -> list[dict]:
    """The complete rows of a ``metrics.jsonl`` as dicts (none when the file is absent); a torn last line, or any
    line that is not a JSON object, is skipped."""
    if not path.exists():
        return []
    rows = []
    for line in path.read_text(errors="replace").splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        if isinstance(row, dict):
            rows.append(row)
    return rows


def metrics_values(path: Path, key: str, kind: type = float) -> list:
    """``kind(row[key])`` of every complete row of a ``metrics.jsonl`` that has it (none when the file is absent);
    a torn last line is skipped."""
    values = []
    for row in metrics_rows(path):
        try:
            values.append(kind(row[key]))
        except (ValueError, KeyError, TypeError):
            continue
    return values


def metrics_epoch(path: Path, key: str = "epoch") -> int:
    """The ``key`` (epoch; episodes for the adapted HOPE) of the last complete row of a ``metrics.jsonl`` (0 when
    absent or empty); a torn last line is skipped."""
    return (metrics_values(path, key, int) or [0])[-1]


def config_conflicts(run: RunSpec) -> list[str]:
    """Fields where the folder's ``config.json`` differs from the plan's config (empty when it has none)."""
    path = run.run_dir / "config.json"
    if not path.exists():
        return []
    ours = resolved_config(run.config.benchmark, run.seed, run.overrides, run.config.trainer)
    try:
        theirs = type(ours).from_dict(json.loads(path.read_text())).to_dict()
    except (ValueError, ConfigError) as exc:
        return [f"config.json unreadable: {exc}"]
    ours = ours.to_dict()
    return _differences(ours, theirs, "")


def _differences(ours: Any, theirs: Any, where: str) -> list[str]:
    if isinstance(ours, dict) and isinstance(theirs, dict):
        return [d for key in sorted(set(ours) | set(theirs))
                for d in _differences(ours.get(key), theirs.get(key), f"{where}.{key}" if where else key)]
    if isinstance(ours, (list, tuple)) and isinstance(theirs, (list, tuple)):
        ours, theirs = list(ours), list(theirs)
    return [] if ours == theirs else [f"{where}: folder has {theirs!r}, plan has {ours!r}"]


def active_trainers() -> dict[Path, int]:
    """Run folders that a ``np_policy.train`` process on this machine writes now: {resolved --out: pid}."""
    active = {}
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            argv = (proc / "cmdline").read_bytes().decode(errors="replace").split("\0")
            cwd = Path(os.readlink(proc / "cwd"))
        except OSError:
            continue
        if any(trainer in argv for trainer in TRAINERS) and "--out" in argv[:-1]:
            out = Path(argv[argv.index("--out") + 1])
            active[(cwd / out).resolve()] = int(proc.name)
    return active


def run_state(run: RunSpec, active: dict[Path, int] | None = None) -> RunState:
    """The state of ``run``'s folder (see the module docstring)."""
    if run.overrides is None:
        return RunState("not available yet", detail=run.config.missing)
    for path, command in run.config.requires:
        if not (CONFIG_DIR.parent.parent / path).exists():
            return RunState("not available yet", detail=f"it reads {path}, not made yet: {command}")
    epoch = metrics_epoch(run.run_dir / "metrics.jsonl", TRAINERS[run.config.trainer][0])
    pid = (active or {}).get(run.run_dir.resolve())
    if pid is not None:
        return RunState("training now", epoch, f"pid {pid}", pid)
    conflicts = config_conflicts(run)
    if conflicts:
        return RunState("config differs", epoch, "; ".join(conflicts))
    if epoch >= run.epochs and run.output.exists():
        return RunState("finished", epoch)
    if (run.run_dir / "snapshot.pt").exists():
        return RunState("interrupted", epoch)
    if holds_run_files(run.run_dir, run.config.trainer):
        return RunState("started, no snapshot", epoch)
    return RunState("not started")


def holds_run_files(folder: Path, trainer: str = "np_policy.train") -> bool:
    """Whether ``folder`` holds any of the files that make ``trainer`` see a run there (its ``RUN_FILES``)."""
    run_files = importlib.import_module(trainer).RUN_FILES
    return any((Path(folder) / name).exists() for name in run_files)


def epochs_left(run: RunSpec, state: RunState) -> int | None:
    """Epochs still to train (None when unknown): a resume restarts at the last snapshot, which is at least the
    last multiple of ``ppo.snapshot_every_epochs`` reached, so this is an upper bound for an interrupted run."""
    if run.epochs is None or state.kind in ("finished", "config differs"):
        return None if run.epochs is None else 0
    if state.kind in ("interrupted", "training now") and run.config.trainer == "hope_policy.train":
        return run.epochs - min(state.epoch, run.epochs)  # episodes; its last snapshot is a few updates back
    if state.kind in ("interrupted", "training now"):
        every = resolved_config(run.config.benchmark, run.seed, run.overrides).ppo.snapshot_every_epochs
        return run.epochs - min(state.epoch, run.epochs) // every * every
    return run.epochs


MEASURED_EPOCHS = 5
"""An interrupted run with at least this many timed epochs is estimated at its own median epoch time."""


def measured_epoch_s(path: Path) -> float | None:
    """Median ``epoch_s`` of a ``metrics.jsonl``'s complete rows, None with fewer than `MEASURED_EPOCHS` timed ones
    (the adapted HOPE's rows have none)."""
    times = metrics_values(path, "epoch_s")
    return float(np.median(times)) if len(times) >= MEASURED_EPOCHS else None


def configuration_epoch_s(runs: list[RunSpec]) -> dict[str, float]:
    """{configuration name: median ``epoch_s`` over the timed rows of all its runs in ``runs``}, for the
    configurations with at least `MEASURED_EPOCHS` such rows: what its other seeds took, on the machines that
    trained them."""
    times: dict[str, list[float]] = {}
    for run in runs:
        times.setdefault(run.config.name, []).extend(metrics_values(run.run_dir / "metrics.jsonl", "epoch_s"))
    return {name: float(np.median(t)) for name, t in times.items() if len(t) >= MEASURED_EPOCHS}


def estimate_hours(run: RunSpec, state: RunState, measured: dict[str, float] | None = None) -> float | None:
    """Estimated wall-clock hours left on this 2-core machine (None when unknown): an interrupted or running run
    at the median of its own timed epochs (`measured_epoch_s`), any other at its configuration's median in
    ``measured`` (`configuration_epoch_s`: its other seeds) or, without one, at the plan's ``epoch_s``."""
    left = epochs_left(run, state)
    if left is None:
        return None
    own = measured_epoch_s(run.run_dir / "metrics.jsonl") if state.kind in ("interrupted", "training now") else None
    return left * (own or (measured or {}).get(run.config.name) or run.config.epoch_s) / 3600


def describe(state: RunState, unit: str = "epoch") -> str:
    """One phrase for a state: "interrupted at epoch 50", "finished (240 epochs)", ...; ``unit`` is what the run
    counts (the adapted HOPE: "episode")."""
    if state.kind == "finished":
        return f"finished ({state.epoch} {unit}s)"
    if state.kind in ("interrupted", "started, no snapshot", "training now"):
        text = f"{state.kind} at {unit} {state.epoch}"
        return f"{text} ({state.detail})" if state.detail else text
    return f"{state.kind}: {state.detail}" if state.detail else state.kind


def format_table(runs: list[RunSpec], states: list[RunState]) -> str:
    """The dry-run listing: one line per run with its state and estimated hours left, then the total, then how to
    stop the runs training now without losing their epochs (`np_sim.stop_request`)."""
    lines = [f"{'run':<38} {'tables':<34} {'est. h left':>11}  state"]
    measured = configuration_epoch_s(runs)
    hours = [estimate_hours(run, state, measured) for run, state in zip(runs, states)]
    for run, state, left in zip(runs, states, hours):
        shown = "?" if left is None else f"{left:.1f}"
        lines.append(f"{run.name:<38} {','.join(run.config.tables):<34} {shown:>11}  "
                     f"{describe(state, TRAINERS[run.config.trainer][0].rstrip('s'))}")
    total = sum(h for h in hours if h is not None)
    unknown = hours.count(None)
    lines.append(f"estimated compute left: {total:.1f} h on this 2-core machine (an estimate, each run on one thread "
                 "beside another: an interrupted run at the median of its own timed epochs, a run not started at the "
                 "median of its configuration's other seeds listed here, else at the plan's figure: "
                 f"{FACTORIAL_EPOCH_S} s per Factorial epoch, {min(TOPOLOGY_NP_EPOCH_S.values())}–"
                 f"{max(TOPOLOGY_NP_EPOCH_S.values())} s per NeuralParker Topology-Stress epoch, {SITE_EPOCH_S} s "
                 f"per site epoch, {HOPE_EPISODE_S} s per adapted-HOPE episode, "
                 f"{min(HOPE_BACKBONE_EPISODE_S.values())}–{max(HOPE_BACKBONE_EPISODE_S.values())} s per HOPE-style "
                 "backbone episode)" + (f", not counting {unknown} run(s) not available yet" if unknown else ""))
    training = [str(s.pid) for s in states if s.pid is not None]
    if training:
        lines.append("to stop the runs training now after the epoch (update) in progress, with a snapshot the sweep "
                     f"resumes: kill -USR1 {' '.join(training)}")
    return "\n".join(lines)
