"""docs/paper_map.md names, for each equation label of the paper, functions whose docstrings cite that label."""

import importlib
import inspect
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
MAP = (REPO / "docs" / "paper_map.md").read_text()
PACKAGES = ("np_sim", "np_policy", "tracking", "experiments", "hope_policy")


def equation_rows() -> list[tuple[str, list[str]]]:
    """(label, dotted names) of the equation table: the third and fourth columns' code spans."""
    rows = []
    for line in MAP.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`eq:"):
            names = re.findall(r"`([\w.]+)`", cells[2] + " " + cells[3])
            rows.append((cells[0].strip("`"), names))
    return rows


def resolve(dotted: str):
    """The module, class or function a dotted name denotes (longest importable module prefix, then attributes)."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ModuleNotFoundError(dotted)


def cited_labels() -> set[str]:
    """Every eq: label cited in a docstring or comment of the packages' source."""
    found = set()
    for package in PACKAGES:
        for path in (REPO / package).rglob("*.py"):
            found |= set(re.findall(r"eq:[a-z][a-z-]*[a-z]", path.read_text()))
    return found


def test_the_map_has_every_equation_row():
    labels = [label for label, _ in equation_rows()]
    assert len(labels) == len(set(labels)) == 11


@pytest.mark.parametrize("label, names", equation_rows())
def test_each_named_function_cites_its_label(label, names):
    assert names
    for name in names:
        doc = inspect.getdoc(resolve(name)) or ""
        assert re.search(re.escape(label) + r"(?![\w-])", doc), f"{name}'s docstring does not cite {label}"


def test_every_label_the_code_cites_is_mapped():
    assert cited_labels() <= {label for label, _ in equation_rows()}


def test_every_module_of_the_section_table_imports():
    section_rows = re.findall(r"^\| [^`|]+ \| (`[^|]+`) \|$", MAP, flags=re.M)
    assert section_rows
    for cell in section_rows:
        for name in re.findall(r"`([\w.]+)`", cell):
            resolve(name)
