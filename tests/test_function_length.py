"""No function in the package sources is longer than 80 lines (the developer guide's limit). A function's length is
counted with ``ast`` from its ``def`` line to its last line (``end_lineno - lineno + 1``, docstring included,
decorators not); methods and nested functions count on their own."""

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("np_sim", "np_policy", "tracking", "experiments", "hope_policy")
MAX_LINES = 80


def long_functions(source: str, filename: str, max_lines: int = MAX_LINES) -> list[str]:
    """'file:name:lines' for each function (methods and nested functions included) of ``source`` longer than
    ``max_lines`` lines."""
    found = []
    for node in ast.walk(ast.parse(source, filename)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines = node.end_lineno - node.lineno + 1
            if lines > max_lines:
                found.append(f"{filename}:{node.name}:{lines}")
    return found


def package_files(package: str) -> list[Path]:
    """Every .py file under the package folder ``package`` of the repository."""
    return sorted((REPO / package).rglob("*.py"))


def _body(n_lines: int, indent: str) -> str:
    return "".join(f"{indent}x{i} = {i}\n" for i in range(n_lines))


def test_scanner_counts_from_def_to_last_line():
    # a def line and 79 statements make 80 lines: allowed; one statement more makes 81
    fits = "@staticmethod\ndef fits():\n" + _body(79, "    ")
    assert long_functions(fits, "a.py") == []
    over = "def over():\n" + _body(80, "    ")
    assert long_functions(over, "a.py") == ["a.py:over:81"]


def test_scanner_finds_methods_and_nested_functions():
    source = ("class C:\n    async def method(self):\n" + _body(81, "        ")
              + "def outer():\n    def inner():\n" + _body(81, "        "))
    # method: 1 + 81 lines; outer: 2 + 81 lines; inner: 1 + 81 lines
    assert sorted(long_functions(source, "b.py")) == ["b.py:inner:82", "b.py:method:82", "b.py:outer:83"]


def test_no_package_function_is_longer_than_80_lines():
    offenders = []
    for package in PACKAGES:
        files = package_files(package)
        assert files, f"no .py files under {package}/"
        for path in files:
            offenders += long_functions(path.read_text(encoding="utf-8"), str(path.relative_to(REPO)))
    assert not offenders, f"functions over {MAX_LINES} lines (file:name:lines):\n" + "\n".join(offenders)
