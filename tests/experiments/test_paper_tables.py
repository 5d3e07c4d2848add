"""The per-table experiment modules (`experiments.paper_table` and its five users): a table built from hand-made run
folders reads as hand-computed means, writes the spec's run folder, and refuses a bad run root in one error line."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from cli_helpers import help_text, one_error_line
from experiments import connector, curriculum, main_comparison, representation, staged
from experiments.paper_numbers import CURRICULUM

EPISODES = CURRICULUM.episodes_per_seed  # 1,080 frozen Factorial starts


def _finished_run(root: Path, name: str, failures: int, length: float) -> None:
    """A NeuralParker run folder that reached 240 epochs, with frozen-start records: the first ``failures`` starts
    fail, every other parks with path length ``length``."""
    folder = root / name
    (folder / "eval_factorial").mkdir(parents=True)
    (folder / "metrics.jsonl").write_text("".join(json.dumps({"epoch": e, "env_steps": 100 * e, "epoch_s": 30.0})
                                                  + "\n" for e in range(1, 241)))
    (folder / "best.pt").write_bytes(b"")
    lines = ["scene,start_id,success,reason,L,reversals,delta_kappa,plan_time_ms"]
    for j in range(EPISODES):
        ok = j >= failures
        lines.append(f"s{j // 40},{j % 40},{int(ok)},{'' if ok else 'collision'},"
                     f"{length if ok else 'nan'},{1 if ok else -1},{0.5 if ok else 'nan'},2.0")
    (folder / "eval_factorial" / "records.csv").write_text("\n".join(lines) + "\n")


def test_curriculum_table_reads_hand_made_runs_as_hand_computed_means(tmp_path, capsys):
    root = tmp_path / "runs"
    _finished_run(root, "factorial_np_seed0_lot", 0, 18.0)
    _finished_run(root, "factorial_np_seed1_lot", 108, 19.0)
    _finished_run(root, "factorial_np_nocurriculum_seed0_lot", 54, 20.0)
    _finished_run(root, "factorial_np_nocurriculum_seed1_lot", 0, 21.0)
    result = curriculum.main(["--runs", str(root), "--out", str(tmp_path / "out"), "--no-evaluate"])
    table = (tmp_path / "out" / "table.md").read_text()
    assert table == result["table"] and table in capsys.readouterr().out
    rows = {line.split(" | ")[0].lstrip("| "): line for line in table.splitlines() if line.startswith("| ")}
    # success over all 1,080: geodesic 1.0 and 0.9, none 0.95 and 1.0; L on the cohorts 1026 / 972 starts
    assert "| 0.950 ± 0.071 |" in rows["Geodesic curriculum"] and "| 18.50 ± 0.71 |" in rows["Geodesic curriculum"]
    assert "| 0.975 ± 0.035 |" in rows["No curriculum"] and "| 20.50 ± 0.71 |" in rows["No curriculum"]
    assert "n = 1026/972 (seeds 0/1)" in table
    assert "2 of 3 (seeds 0, 1; seed 2: not trained yet (not started))" in rows["No curriculum"]
    with (tmp_path / "out" / "records.csv").open() as fh:
        records = list(csv.DictReader(fh))
    assert len(records) == 4 * EPISODES
    assert {r["row"] for r in records} == {"Geodesic curriculum", "No curriculum"}
    assert sum(r["reason"] == "collision" for r in records) == 108 + 54
    assert (tmp_path / "out" / "curriculum.png").stat().st_size > 0
    config = json.loads((tmp_path / "out" / "config.json").read_text())
    assert config["table"] == "tab:app-controls" and config["hope_action"] == "sampled"


def test_a_table_with_no_trained_row_still_writes_its_table(tmp_path):
    root = tmp_path / "runs"
    root.mkdir()
    result = representation.main(["--runs", str(root), "--out", str(tmp_path / "out"), "--no-evaluate"])
    rows = [line for line in result["table"].splitlines() if line.startswith("| ") and "backbone" in line]
    assert len(rows) == 6 and all("| 0 of 3 seeds: " in row for row in rows)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["config.json", "table.md"]


@pytest.mark.parametrize("module", [main_comparison, staged, representation, connector, curriculum],
                         ids=lambda m: m.__name__)
def test_every_table_module_explains_itself_and_refuses_a_missing_run_root(module, capsys, tmp_path):
    assert f"python -m {module.__name__} [--runs DIR]" in help_text(capsys, module.main)
    line = one_error_line(capsys, module.main, ["--runs", str(tmp_path / "absent")])
    assert "expected an existing folder of run folders" in line


def test_family_lines_give_each_measured_rows_per_family_success():
    from experiments.paper import family_lines

    groups = {"A": {"type1": [0.5, 0.7], "type2": [1.0], "type3": []}, "B": {"type1": [], "type2": [], "type3": []}}
    lines = family_lines(groups)
    assert lines[2] == "| A | 0.600 ± 0.141 | 1.000 | – |" and len(lines) == 4  # B has no seed: left out
    assert family_lines({"B": groups["B"]}) == []
