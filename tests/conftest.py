"""Shared test set-up: put ``tests/`` on ``sys.path`` so test modules import the plain-Python oracles that live
here (``reward_oracle``) by name; they are test code, not part of the package."""

import sys
from pathlib import Path

_TESTS = str(Path(__file__).resolve().parent)
if _TESTS not in sys.path:
    sys.path.insert(0, _TESTS)
