"""experiments.registry: every entry builds a planner that follows the protocol under its own name, the CLIs draw
their planners and labels from it, a new planner registers with one entry, and bad names or checkpoints are
named."""

import re
from pathlib import Path

import numpy as np
import pytest

from experiments import closed_loop, planners, track
from experiments.registry import REGISTRY, Entry, PlannerOptions, build_planners, check_names, label
from np_sim.errors import ConfigError
from np_sim.plan import Plan
from np_sim.planners import Planner

CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")
FOOTPRINT = Path("checkpoints/site_np_footprint.pt")


def test_every_entry_builds_a_planner_of_its_name_and_the_options_convention():
    options = PlannerOptions(checkpoint=CHECKPOINT, footprint_checkpoint=FOOTPRINT, convention="footprint")
    names = [name for name in REGISTRY if "hope" not in name]  # HOPE's: their own checkpoint, below
    built = build_planners(names, options)
    assert list(built) == names
    for name, planner in built.items():
        assert isinstance(planner, Planner), name
        assert planner.name == ("neuralparker" if name in ("neuralparker_footprint", "neuralparker_search") else name)
    searches = ("hybrid_astar", "np_guided_astar", "ompl_rrtstar", "staged_astar_np")
    assert {built[n].convention for n in searches} == {"footprint"}
    assert built["neuralparker"].convention == "reference_point"  # the Factorial checkpoint's own
    assert built["neuralparker_footprint"].convention == "footprint"
    shared = [built[n].learned.policy for n in ("np_guided_astar", "staged_astar_np")]
    assert all(p is built["neuralparker"].policy for p in shared)
    assert built["neuralparker_footprint"].policy is not built["neuralparker"].policy
    assert built["neuralparker_search"].policy is built["neuralparker_footprint"].policy  # one load, two presets
    assert built["neuralparker_search"].config.search_margin_m == 0.2
    assert built["neuralparker_footprint"].config.search_margin_m is None
    assert len({entry.label for entry in REGISTRY.values()}) == len(REGISTRY)


def test_hope_without_its_checkpoint_names_the_flag_that_gives_one():
    for name in ("hope", "staged_astar_hope"):
        with pytest.raises(FileNotFoundError, match="--hope-checkpoint"):
            build_planners([name], PlannerOptions())


def test_the_clis_offer_registered_planners_and_label_rows_from_the_registry():
    for names in (planners.METHODS, track.PLANNERS, closed_loop.PLANNERS):
        assert set(names) <= set(REGISTRY)
    records = [{"scene": "s", "start_id": 0, "method": m, "success": 1, "L": 1.0, "reversals": 0, "delta_kappa": 0.0,
                "plan_time_ms": 1.0, "expanded_nodes": 0, "exact_footprint_valid": 1, "exact_ref_point_valid": 1,
                "scored_valid": 1, "guide_time_ms": 0.5} for m in ("hybrid_astar", "staged_astar_np")]
    table = planners.format_table(records, ["hybrid_astar", "staged_astar_np"])
    assert f"| {label('hybrid_astar')} |" in table and "| Hybrid A* → NP |" in table


def test_a_new_planner_registers_with_one_entry(monkeypatch):
    class Straight:
        """Drives 5 m straight ahead and calls it a plan."""

        name, convention = "straight", "footprint"

        def plan(self, scene, start):
            return Plan(start=np.asarray(start, float), arcs=np.array([[0.0, 5.0]]), success=True)

    monkeypatch.setitem(REGISTRY, "straight", Entry("Straight ahead", lambda options, load: Straight()))
    built = build_planners(["hybrid_astar", "straight"], PlannerOptions())
    assert isinstance(built["straight"], Planner) and label("straight") == "Straight ahead"
    np.testing.assert_array_equal(built["straight"].plan(None, np.zeros(3)).arcs, [[0.0, 5.0]])


def test_unknown_names_and_missing_checkpoints_are_named(tmp_path):
    with pytest.raises(ConfigError, match=re.escape("unknown planner(s) ['astar']; expected some of ['hybrid_astar'")):
        build_planners(["hybrid_astar", "astar"], PlannerOptions())
    with pytest.raises(ConfigError, match=re.escape("unknown planner(s) ['ompl_rrtstar']; expected some of ['a']")):
        check_names(["ompl_rrtstar"], ["a"])
    with pytest.raises(FileNotFoundError, match="planner staged_astar_np needs a policy checkpoint; pass --checkpoint"):
        build_planners(["staged_astar_np"], PlannerOptions())
    with pytest.raises(FileNotFoundError, match=r"planner neuralparker: its checkpoint .*none.pt does not exist"):
        build_planners(["neuralparker"], PlannerOptions(checkpoint=tmp_path / "none.pt"))
    with pytest.raises(ConfigError, match="PlannerOptions.convention: expected one of"):
        PlannerOptions(convention="centre")


def test_the_search_time_budget_reaches_every_search_and_a_bad_one_is_named():
    options = PlannerOptions(checkpoint=CHECKPOINT, search_time_budget_s=1000.0)
    built = build_planners(["hybrid_astar", "np_guided_astar", "staged_astar_np", "ompl_rrtstar"], options)
    budgets = [built["hybrid_astar"].config, built["np_guided_astar"].search.config,
               built["staged_astar_np"].search.config, built["ompl_rrtstar"].config]
    assert [c.time_budget_s for c in budgets] == [1000.0] * 4
    assert PlannerOptions().search_time_budget_s == 1.0  # the default: HybridAStarConfig's own
    for bad in (0.0, -1.0, float("inf"), float("nan"), "1"):
        with pytest.raises(ConfigError, match="PlannerOptions.search_time_budget_s: expected a finite number"):
            PlannerOptions(search_time_budget_s=bad)
