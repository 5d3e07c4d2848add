"""The reproduction report and its figure modules: the paper's numbers against the LaTeX source, claim verdicts and
cohort aggregation against hand-made numbers, run folders read into seeds, and each figure module on a tiny input."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Point

from cli_helpers import one_error_line
from experiments import hermite_case, overview_case, paper, scenes
from experiments.paper import (ARMS, CLAIMS, Arm, ArmResult, Claim, claim_verdict, compare, epoch_hours,
                               evaluation_argv, exact_rule_section, generalisation_lines, measure, read_records,
                               shared_geometry_epochs, summarise)
from experiments.paper_numbers import METRICS, TABLES
from experiments.sweep_plan import PAPER_PLAN, expand
from np_sim.benchmarks import load_benchmark

PAPER = Path(__file__).resolve().parents[3] / "shared" / "paper" / "neuralparker.tex"
CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")
needs_checkpoint = pytest.mark.skipif(not CHECKPOINT.exists(), reason="no shipped NeuralParker checkpoint")


def _latex_table(label: str) -> str:
    text = PAPER.read_text()
    end = text.index(f"\\label{{{label}}}")
    start = text.rindex("\\begin{table}", 0, end)
    return text[start:text.index("\\end{table}", end)]


@pytest.mark.skipif(not PAPER.exists(), reason="the paper's LaTeX source is not in this checkout (../shared)")
@pytest.mark.parametrize("table", TABLES, ids=lambda t: t.label)
def test_transcribed_numbers_match_the_latex_tables(table):
    source = _latex_table(table.label)
    printed = [(float(m), float(s)) for m, s in re.findall(r"\\msd\{([\d.]+)\}\{([\d.]+)\}", source)]
    ours = [row.values[m] for row in table.rows for m in METRICS]
    assert ours == printed
    cohort = re.search(r"\(\$n=([\d/]+)\$\)", source).group(1)
    assert table.cohort == tuple(int(n) for n in cohort.split("/"))


def test_every_claim_names_rows_of_its_table():
    for claim in CLAIMS:
        labels = {arm.label for arm in ARMS[claim.table]}
        for better, worse, _, _ in claim.comparisons:
            assert {better, worse} <= labels, claim.text


def test_compare_against_hand_computed_gaps():
    # L lower is better: means 18.1 and 20.2, sample SDs 0.1414 and 0.2828, gap 2.1 beyond 0.2828
    outcome, text = compare([18.0, 18.2], [20.0, 20.4], "L")
    assert outcome == "agrees" and "-2.1" in text and "0.28" in text
    assert compare([20.0, 20.4], [18.0, 18.2], "L")[0] == "disagrees"
    # success higher is better: means 0.97 and 0.96, gap 0.01 inside the larger SD 0.0283
    assert compare([0.95, 0.99], [0.96, 0.96], "success")[0] == "within noise"
    assert compare([0.95, 0.99], [0.96, 0.96], "success", "similar")[0] == "agrees"
    assert compare([0.97, 0.98], [0.80, 0.81], "success", "similar")[0] == "disagrees"
    with pytest.raises(ValueError, match="two seeds"):
        compare([0.9], [0.8, 0.7], "success")


def test_claim_verdict_combines_metrics_and_names_missing_rows():
    claim = Claim("A beats B and C", "t", (("A", "B", ("success", "L"), "better"), ("A", "C", ("L",), "better")))
    stats = {"A": {"success": [0.99, 0.98], "L": [18.0, 18.2]},
             "B": {"success": [0.90, 0.91], "L": [20.0, 20.4]},
             "C": {"success": [0.95, 0.96], "L": [18.1, 18.3]}}
    assert claim_verdict(claim, stats).startswith("within noise (A vs B: ")  # A vs C: L gap 0.1 < SD 0.14
    stats["C"]["L"] = [17.0, 17.1]
    assert claim_verdict(claim, stats).startswith("disagrees")
    stats["C"]["L"] = [25.0, 25.2]
    assert claim_verdict(claim, stats).startswith("agrees")
    del stats["C"]
    line = claim_verdict(claim, stats, {"C": "0 of 3 seeds: not trained yet (not started)"})
    assert line.startswith("not measurable yet (missing: C: 0 of 3 seeds: not trained yet (not started)); "
                           "measured so far: agrees (A vs B")
    stats["B"] = {"success": [0.9], "L": [20.0]}
    assert claim_verdict(claim, stats) == "not measurable yet (missing: B: fewer than 2 seeds; C: fewer than 2 seeds)"


def _rows(outcomes):
    return [{"key": ("s", j), "success": int(ok), "L": length, "reversals": 1.0, "delta_kappa": 0.5,
             "plan_time_ms": 2.0} for j, (ok, length) in enumerate(outcomes)]


def test_summarise_uses_full_set_success_and_the_within_seed_common_cohort():
    nan = float("nan")
    a = ArmResult(Arm("A", "x"), {0: _rows([(1, 10.0), (1, 20.0), (0, nan)]),
                                  1: _rows([(1, 11.0), (1, 21.0), (1, 5.0)])})
    b = ArmResult(Arm("B", "y"), {0: _rows([(1, 12.0), (0, nan), (1, 30.0)]),
                                  1: _rows([(1, 13.0), (1, 23.0), (0, nan)])})
    stats, cohorts = summarise([a, b])
    assert cohorts == {0: 1, 1: 2}  # seed 0: only start 0 solved by both; seed 1: starts 0 and 1
    assert stats["A"]["success"] == pytest.approx([2 / 3, 1.0])
    assert stats["A"]["L"] == pytest.approx([10.0, 16.0])
    assert stats["B"]["L"] == pytest.approx([12.0, 18.0])


def test_generalisation_table_sets_test_success_beside_the_training_scenes_on_shared_seeds():
    nan = float("nan")
    test = [ArmResult(Arm("A", "x"), {0: _rows([(1, 1.0), (0, nan)]), 1: _rows([(1, 1.0), (1, 1.0)])}),
            ArmResult(Arm("B", "y"), {0: _rows([(1, 1.0), (1, 1.0)])})]
    validation = [ArmResult(Arm("A", "x", "validation"), {0: _rows([(1, 1.0)] * 4), 1: _rows([(1, 1.0), (0, nan)])}),
                  ArmResult(Arm("B", "y", "validation"), missing={0: "trained, not evaluated yet"})]
    lines = generalisation_lines(test, validation)
    # A: test 0.5 and 1.0 (mean 0.75, SD 0.354), training scenes 1.0 and 0.5, gaps -0.5 and +0.5; B: no shared seed
    assert lines[2] == "| A | 0, 1 | 0.750 ± 0.354 | 0.750 ± 0.354 | 0.000 ± 0.707 |"
    assert len(lines) == 4 and lines[3] == ""
    assert generalisation_lines(test[1:], validation[1:])[0].startswith("No row has a seed measured on both sets yet")


def test_exact_rule_section_counts_successes_that_also_pass_the_exact_rule(tmp_path):
    def rows(pairs):  # (success, exact) per episode
        return [{"key": ("s", j), "success": ok, "exact": exact} for j, (ok, exact) in enumerate(pairs)]
    fixed = ArmResult(Arm("Fixed", "f"), {0: rows([(1, 1), (1, 1), (1, 0), (0, 0)]),
                                          1: rows([(1, 1), (1, 1), (1, 1), (0, 0)])})
    old = ArmResult(Arm("Old", "o"), {0: rows([(1, None), (1, None)])})  # records written before the column
    same = ArmResult(Arm("Reference", "f"), fixed.records)  # another table's row on the same records
    lines = exact_rule_section({"tab:a": [fixed, old], "tab:b": [fixed, same]})
    # seed 0: 3/4 sampled, 2/4 exact, 2/3 of the successes; seed 1: 3/4, 3/4, all of them
    assert lines[-2] == "| Fixed / Reference (`f`, own) | 0, 1 | 0.750 ± 0.000 | 0.625 ± 0.177 | 0.833 ± 0.236 |"
    assert sum(line.startswith("| Fixed") for line in lines) == 1 and not any("Old" in line for line in lines)
    record = tmp_path / "records.csv"
    record.write_text("scene,start_id,success,reason,L,reversals,delta_kappa,plan_time_ms,exact_ref_point_valid\n"
                      "a,0,1,,10.0,1,0.5,2.0,0\n")
    assert read_records(record)[0]["exact"] == 0
    record.write_text("scene,start_id,success,reason,L,reversals,delta_kappa,plan_time_ms\na,0,1,,10.0,1,0.5,2.0\n")
    assert read_records(record)[0]["exact"] is None


def _metrics(folder: Path, epochs: int, seconds: float, timed_from: int | None = None) -> None:
    rows = []
    for e in range(1, epochs + 1):
        row = {"epoch": e, "env_steps": 65536 * e, "steps_per_s": 65536 / seconds}
        if timed_from is not None and e >= timed_from:
            row["epoch_s"] = 2 * seconds  # newer rows carry their own epoch time
        rows.append(json.dumps(row))
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "metrics.jsonl").write_text("\n".join(rows) + "\n")


def test_epoch_hours_reads_both_row_formats(tmp_path):
    _metrics(tmp_path, 10, 36.0, timed_from=6)
    assert epoch_hours(tmp_path / "metrics.jsonl") == pytest.approx((5 * 36.0 + 5 * 72.0) / 3600)
    assert epoch_hours(tmp_path / "absent.jsonl") == 0.0


def test_shared_geometry_epochs_read_from_the_metrics_rows(tmp_path):
    metrics = tmp_path / "metrics.jsonl"
    assert shared_geometry_epochs(metrics) == ""  # absent
    flags = [None] * 3 + [True] * 2 + [False] + [True] * 3  # rows without the field predate the flag: off
    metrics.write_text("".join(json.dumps({"epoch": e, **({} if f is None else {"shared_geometry": f})}) + "\n"
                               for e, f in enumerate(flags, start=1)) + '{"epoch": 10, "shared')  # torn last line
    assert shared_geometry_epochs(metrics) == "epochs 4–5, 7–9"
    metrics.write_text("".join(json.dumps({"epoch": e, "shared_geometry": e != 2}) + "\n" for e in (1, 2, 3)))
    assert shared_geometry_epochs(metrics) == "epochs 1, 3"
    metrics.write_text("".join(json.dumps({"epoch": e, "shared_geometry": True}) + "\n" for e in (1, 2)))
    assert shared_geometry_epochs(metrics) == "all epochs"
    result = ArmResult(Arm("A", "x"), shared_geometry={2: "epochs 121–240", 0: "all epochs"})
    assert result.shared_geometry_text() == "seeds 0, 2 (seed 2: epochs 121–240)"
    assert ArmResult(Arm("A", "x")).shared_geometry_text() == "–"


def test_measure_counts_only_finished_evaluated_seeds(tmp_path):
    runs = {(r.config.name, r.seed): r for r in expand(PAPER_PLAN, (0, 1, 2), tmp_path)}
    seed0 = tmp_path / "factorial_np_fixed_seed0_lot"
    _metrics(seed0, 240, 40.0)
    (seed0 / "best.pt").write_bytes(b"")
    (seed0 / "eval_factorial").mkdir()
    (seed0 / "eval_factorial" / "records.csv").write_text(
        "scene,start_id,success,L,reversals,delta_kappa,plan_time_ms\n"
        "a,0,1,10.0,1,0.5,3.0\na,1,0,nan,-1,nan,4.0\n")
    _metrics(tmp_path / "factorial_np_fixed_seed1_lot", 100, 40.0)
    (tmp_path / "factorial_np_fixed_seed1_lot" / "snapshot.pt").write_bytes(b"")
    fixed = measure(Arm("Fixed Hermite", "factorial_np_fixed"), runs, 2, evaluate=False, active={})
    assert sorted(fixed.records) == [0] and fixed.records[0][1]["key"] == ("a", 1)
    assert fixed.shared_geometry == {}  # its rows predate the flag
    rows = (seed0 / "metrics.jsonl").read_text().splitlines()
    (seed0 / "metrics.jsonl").write_text("".join(json.dumps({**json.loads(r), "shared_geometry": True}) + "\n"
                                                 for r in rows))
    measured = measure(Arm("Fixed Hermite", "factorial_np_fixed"), runs, 2, evaluate=False, active={})
    assert measured.shared_geometry == {0: "all epochs"} and measured.shared_geometry_text() == "seed 0"
    assert fixed.seeds_text() == ("1 of 3 (seed 0; seed 1: not trained yet (interrupted, epoch 100 of 240); "
                                  "seed 2: not trained yet (not started))")
    ensemble = measure(Arm("Ensemble, eval. only", "factorial_np_fixed", "ensemble"), runs, 2, False, {})
    assert ensemble.missing[0] == "trained, not evaluated yet"
    wrong_size = measure(Arm("Fixed Hermite", "factorial_np_fixed"), runs, 1080, False, {})
    assert "has 2 episodes, expected 1080" in wrong_size.missing[0]
    hope = measure(Arm("Adapted HOPE", "factorial_hope"), runs, 1080, False, {})
    assert hope.seeds_text() == "0 of 3 seeds: not trained yet (not started)"
    backbone = measure(Arm("HOPE-style, none", "topology_hope_none"), runs, 720, False, {})
    assert backbone.seeds_text() == "0 of 3 seeds: not trained yet (not started)"


def test_a_finished_adapted_hope_run_is_read_from_final_pt_and_its_planner_records(tmp_path):
    runs = {(r.config.name, r.seed): r for r in expand(PAPER_PLAN, (0, 1, 2), tmp_path)}
    seed0 = tmp_path / "factorial_hope_seed0"
    seed0.mkdir()
    rows = [{"update": u, "episodes": 3400 * u, "env_steps": 8192 * u, "collect_s": 10.0, "update_s": 50.0}
            for u in (1, 2, 3)]
    (seed0 / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    (seed0 / "eval_factorial").mkdir()
    (seed0 / "eval_factorial" / "records.csv").write_text(
        "scene,start_id,success,L,reversals,delta_kappa,plan_time_ms\na,0,1,10.0,1,0.5,3.0\n")
    hope = Arm("Adapted HOPE", "factorial_hope")
    assert measure(hope, runs, 1, False, {}).missing[0] == "not trained yet (started, no snapshot, episode 10200 of " \
        "10000)"  # no final.pt: not finished, whatever the episode count
    (seed0 / "final.pt").write_bytes(b"")
    # records without the protocol in config.json were played with the mean action: refused, not mixed in
    assert measure(hope, runs, 1, False, {}).missing[0].endswith(
        "was evaluated with the mean action, this row plays sampled actions (move the folder aside to re-evaluate)")
    (seed0 / "eval_factorial" / "config.json").write_text(json.dumps({"hope": {"action": "sampled", "seed": 0}}))
    measured = measure(hope, runs, 1, False, {})
    assert sorted(measured.records) == [0] and measured.seeds_text().startswith("1 of 3 (seed 0; seed 1: not trained")
    staged_arm = Arm("Hybrid A* → HOPE", "factorial_hope", "staged")
    assert measure(staged_arm, runs, 1, False, {}).missing[0] == "trained, not evaluated yet"
    killed = seed0 / "eval_factorial_staged"  # an experiments.planners run killed mid-way: resumed, not refused
    killed.mkdir()
    (killed / "progress_settings.json").write_text("{}")
    assert measure(staged_arm, runs, 1, False, {}).missing[0] == "trained, evaluation interrupted"
    (killed / "progress_settings.json").unlink()
    (killed / "table.md").write_text("| a |")
    assert measure(staged_arm, runs, 1, False, {}).missing[0].endswith("holds an interrupted evaluation (remove it "
                                                                       "to re-run)")
    (killed / "table.md").unlink()
    killed.rmdir()
    argv = evaluation_argv(staged_arm, runs[("factorial_hope", 0)], seed0 / "eval_factorial_staged")
    assert argv[argv.index("--methods") + 1] == "staged_astar_hope" and "--hope-checkpoint" in argv
    assert measure(Arm("Ensemble", "factorial_hope", "ensemble"), runs, 1, False, {}).missing[0].endswith(
        "the ensemble evaluation of an adapted-HOPE checkpoint is not built yet")
    argv = evaluation_argv(hope, runs[("factorial_hope", 0)], seed0 / "eval_factorial")
    assert argv[1:] == ["-m", "experiments.planners", "--benchmark", "factorial", "--methods", "hope",
                        "--hope-checkpoint", str(seed0 / "final.pt"), "--hope-action", "sampled", "--out",
                        str(seed0 / "eval_factorial")]
    # the mean-action rows (beyond the paper) read the same kind of folder with the other protocol
    mean_arm = Arm("Adapted HOPE", "factorial_hope", "mean")
    (seed0 / "eval_factorial_mean").mkdir()
    (seed0 / "eval_factorial_mean" / "records.csv").write_text((seed0 / "eval_factorial" / "records.csv").read_text())
    assert sorted(measure(mean_arm, runs, 1, False, {}).records) == [0]  # no protocol recorded: the mean action
    (seed0 / "eval_factorial_mean" / "config.json").write_text(json.dumps({"hope": {"action": "sampled"}}))
    assert measure(mean_arm, runs, 1, False, {}).missing[0].endswith("was evaluated with the sampled action, this "
                                                                     "row plays mean actions (move the folder aside "
                                                                     "to re-evaluate)")
    argv = evaluation_argv(Arm("Hybrid A* → HOPE", "factorial_hope", "staged_mean"), runs[("factorial_hope", 0)],
                           seed0 / "eval_factorial_staged_mean")
    assert argv[argv.index("--methods") + 1] == "staged_astar_hope" and argv[argv.index("--hope-action") + 1] == "mean"
    assert epoch_hours(seed0 / "metrics.jsonl") == pytest.approx(3 * 60.0 / 3600)
    argv = evaluation_argv(Arm("Adapted HOPE", "factorial_hope", "validation"), runs[("factorial_hope", 0)],
                           seed0 / "eval_factorial_validation")
    assert argv[-2:] == ["--split", "validation"] and argv[argv.index("--methods") + 1] == "hope"
    argv = evaluation_argv(Arm("Fixed Hermite", "factorial_np_fixed", "validation"),
                           runs[("factorial_np_fixed", 0)], tmp_path / "v")
    assert argv[2] == "experiments.evaluate" and argv[-2:] == ["--split", "validation"]


def test_scene_examples_grid_and_png(tmp_path):
    result = scenes.run("medium", tmp_path / "scenes")
    assert result["png"].stat().st_size > 0
    tags = {s.name: s.tags for s in load_benchmark("factorial", "test") + load_benchmark("topology", "test")}
    for i, row in enumerate(result["scenes"]["factorial"]):
        for j, name in enumerate(row):
            assert (tags[name]["distance"], tags[name]["type"], tags[name]["difficulty"]) == \
                (scenes.DISTANCES[i], scenes.TYPES[j], "medium")
            assert tags[name]["split"] == "test"
    assert [[tags[n]["cell"] for n in row] for row in result["scenes"]["topology"]] == \
        [[f"type{i}-medium", f"type{i}-hard"] for i in (1, 2, 3)]
    assert json.loads((tmp_path / "scenes" / "scenes.json").read_text())["scenes"] == result["scenes"]


@needs_checkpoint
def test_hermite_case_replays_both_connectors_from_the_handoff(tmp_path):
    train = load_benchmark("factorial", "train")
    picked = [s for s in train if s.tags["distance"] == "long" and s.tags["type"] == "random"]
    result = hermite_case.run(CHECKPOINT, 0, tmp_path / "case", scenes=picked)
    case = result["case"]
    assert case.scene.tags["split"] == "train"
    fixed, ensemble = case.connections["fixed"], case.connections["ensemble"]
    # both start at the hand-off; the ensemble's 81 include the fixed nine, so its least cost is no higher
    for c in (fixed, ensemble):
        assert np.allclose(c.points[0], case.pose[:2], atol=1e-9)
    assert ensemble.cost < fixed.cost
    assert fixed.cost == pytest.approx(10 * fixed.delta_kappa + 10 * fixed.length + 5)  # eq:mincost
    assert fixed.scales == (1.0, 1.0)
    assert {p.name for p in (tmp_path / "case").iterdir()} == {"hermite_case.png", "case.md", "case.json"}


@needs_checkpoint
def test_overview_case_hands_over_inside_the_radius(tmp_path):
    train = [s for s in load_benchmark("factorial", "train") if s.tags["cell"] == "long-reverse-easy"]
    result = overview_case.run(CHECKPOINT, 0, tmp_path / "case", scenes=train)
    data = json.loads((tmp_path / "case" / "case.json").read_text())
    scene = next(s for s in train if s.name == data["scene"])
    target = Point(scene.target[:2])
    assert target.distance(Point(data["start"][:2])) > 10.0
    assert data["arms"]["Unified NP"]["success"] and data["arms"]["Hybrid A* → NP"]["success"]
    assert (tmp_path / "case" / "overview_case.png").stat().st_size > 0
    assert math.isfinite(data["arms"]["Unified NP"]["L"])
    # the paper's diagnostic arm, from the shipped adapted-HOPE seed 0, on the same case
    assert "Hybrid A* → HOPE" in data["arms"] and "| Hybrid A* → HOPE |" in result["table"]
    assert "to the adapted HOPE planner" in result["table"]


def test_fig4_moves_to_the_topology_pocket_case_once_the_vertices_run_is_finished(tmp_path):
    runs = {(r.config.name, r.seed): r for r in expand(PAPER_PLAN, (0,), tmp_path)}
    assert paper.overview_arguments(runs) == {"benchmark": "factorial"}
    run = tmp_path / "topology_np_vertices_seed0_lot"
    _metrics(run, 120, 40.0)
    (run / "snapshot.pt").write_bytes(b"")
    assert paper.overview_arguments(runs) == {"benchmark": "factorial"}  # interrupted at epoch 120
    (run / "snapshot.pt").unlink()
    _metrics(run, 240, 40.0)
    (run / "best.pt").write_bytes(b"")
    assert paper.overview_arguments(runs) == {"benchmark": "topology", "checkpoint": run / "best.pt"}
    assert "Topology-Stress pocket (Type 2) training scene" in paper.overview_text("topology")
    assert "--benchmark factorial" in paper.overview_text("factorial")


@pytest.mark.skipif(not overview_case.POCKET_CHECKPOINT.exists(), reason="no Topology-Stress vertices checkpoint")
def test_overview_case_on_topology_pins_a_pocket_scene_without_the_hope_arm(tmp_path):
    train = [s for s in load_benchmark("topology", "train") if s.tags["family"] == "type2"][:4]
    result = overview_case.run(None, 0, tmp_path / "case", scenes=train, benchmark="topology")
    data = json.loads((tmp_path / "case" / "case.json").read_text())
    scene = next(s for s in train if s.name == data["scene"])
    assert data["benchmark"] == "topology" and data["checkpoint"] == str(overview_case.POCKET_CHECKPOINT)
    assert Point(scene.target[:2]).distance(Point(data["start"][:2])) > 10.0
    assert set(data["arms"]) == {"Unified NP", "Hybrid A* → NP"}
    assert all(arm["success"] for arm in data["arms"].values())
    assert "plan time" in result["table"] and "plan time" not in result["path_table"]
    # the path table is the timed table with its last column taken away, row for row
    for timed, untimed in zip(result["table"].splitlines()[3:], result["path_table"].splitlines()[3:]):
        assert timed.rsplit("|", 2)[0] + "|" == untimed
    with pytest.raises(ValueError, match="benchmark must be one of"):
        overview_case.run(benchmark="site")


def test_the_overview_sentence_names_the_metrics_where_unified_is_lower():
    from np_sim.plan import Plan

    def plan(arcs):  # straight or constant-curvature arcs: L = Σ|l|, reversals = sign changes, Δκ = Σ|κ jumps|
        return Plan(start=np.zeros(3), arcs=np.array(arcs, float), success=True)

    unified = plan([[0.0, 10.0], [0.2, 5.0]])               # L 15, 0 reversals, Δκ 0.2
    staged = plan([[0.0, 6.0], [0.0, -2.0], [0.0, 4.0]])   # L 12, 2 reversals, Δκ 0
    text = overview_case.compare_arms({"Unified NP": unified, "Hybrid A* → NP": staged})
    assert text == ("On this case the unified arm's L / reversals / Δκ are 15.00 / 0 / 0.20 against the staged "
                    "arm's 12.00 / 2 / 0.00: lower in reversals, not in L and Δκ.")
    assert overview_case.compare_arms({"Unified NP": staged, "Hybrid A* → NP": staged}).endswith(
        "lower in none of them.")


@pytest.mark.parametrize("argv, words", [(["--out", "report.txt"], "ending in .md"),
                                         (["--runs", "no/such/folder"], "existing folder of run folders")])
def test_paper_cli_refuses_bad_paths_with_one_error_line(capsys, argv, words):
    assert words in one_error_line(capsys, paper.main, argv)


@needs_checkpoint
def test_case_clis_refuse_a_negative_seed_with_one_error_line(capsys):
    for module in (hermite_case, overview_case):
        assert "--start-seed" in one_error_line(capsys, module.main, ["--start-seed", "-1"])


def test_the_paper_success_of_a_row_or_the_bound_its_bar_cohort_implies():
    """Table II prints the staged HOPE row (0.686 ± 0.014); Fig. 3 is bars only, and its common-success cohorts of
    773 / 748 / 790 of 1,080 starts bound the adapted HOPE's success from below (0.716, 0.693, 0.731)."""
    from experiments.paper import paper_success
    from experiments.paper_numbers import MAIN_COMPARISON, TWOSTAGE

    assert paper_success(TWOSTAGE, "Hybrid A* → HOPE") == "0.686 ± 0.014"
    assert paper_success(MAIN_COMPARISON, "Adapted HOPE") == "bars only; its cohort implies ≥ 0.72 / 0.69 / 0.73"
