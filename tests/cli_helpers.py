"""Shared assertions for the CLI tests: a user's mistake ends in exit status 2 and one ``error:`` line; ``--help``
exits 0."""

import pytest


def one_error_line(capsys, main, argv: list[str]) -> str:
    """Run ``main(argv)``, require exit status 2 and exactly one ``error:`` line on stderr; return that line."""
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def help_text(capsys, main) -> str:
    """Run ``main(["--help"])``, require exit status 0 and return what it printed."""
    with pytest.raises(SystemExit) as exit_info:
        main(["--help"])
    assert exit_info.value.code == 0
    return capsys.readouterr().out
