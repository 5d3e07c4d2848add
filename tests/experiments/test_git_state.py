"""`np_sim.provenance`: a result names the commit and any edited Python file it ran with, and the machine."""

import subprocess

import pytest

from np_sim import provenance as common


def _git(repo, *args):
    subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)


@pytest.fixture
def repo(tmp_path, monkeypatch):
    _git(tmp_path, "init", "-q")
    _git(tmp_path, "config", "user.email", "t@example.org")
    _git(tmp_path, "config", "user.name", "t")
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text("x = 1\n")
    (tmp_path / "notes.txt").write_text("n\n")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "commit", "-q", "-m", "c")
    monkeypatch.setattr(common, "REPO_ROOT", tmp_path)
    return tmp_path


def test_a_clean_checkout_names_its_commit_and_no_edits(repo):
    head = subprocess.run(["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True, text=True).stdout
    assert common.git_state() == {"git_commit": head.strip(), "git_modified": []}


def test_edited_python_files_are_listed_and_other_files_are_not(repo):
    (repo / "pkg" / "a.py").write_text("x = 2\n")
    (repo / "notes.txt").write_text("changed\n")
    (repo / "new.py").write_text("y = 1\n")
    (repo / ".gitignore").write_text("scratch.py\n")
    (repo / "scratch.py").write_text("ignored\n")
    assert common.git_state()["git_modified"] == ["new.py", "pkg/a.py"]  # not notes.txt, not the ignored scratch.py


def test_outside_a_checkout_the_state_is_unknown(tmp_path, monkeypatch):
    monkeypatch.setattr(common, "REPO_ROOT", tmp_path)
    monkeypatch.setenv("GIT_CEILING_DIRECTORIES", str(tmp_path.parent))
    assert common.git_state() == {"git_commit": "unknown", "git_modified": None}


def test_a_result_also_names_the_machine_and_the_numeric_libraries_it_ran_on(repo):
    """`provenance` adds the CPU, the CPU numba compiles for and the numeric libraries' versions to `git_state`:
    float results can differ between machines (one held-out clip did)."""
    import numba
    import numpy

    record = common.provenance()
    assert {k: record[k] for k in ("git_commit", "git_modified")} == common.git_state()
    machine = record["machine"]
    assert machine["packages"]["numpy"] == numpy.__version__ and machine["packages"]["numba"] == numba.__version__
    assert machine["cores"] >= 1 and machine["cpu"] and machine["llvm_cpu"]
    assert set(machine["packages"]) == set(common.NUMERIC_PACKAGES)
