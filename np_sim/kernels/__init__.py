"""Compiled numba kernels (``@njit(cache=True, error_model="numpy")``).

numba invalidates a cached function only when its *own* source file changes, not when a kernel it calls from
another module does; a stale cache then runs old machine code against new array layouts. The cache therefore
lives in a directory keyed by a hash of every kernel source file, so any kernel edit starts a fresh cache.
"""

import hashlib
import os
from pathlib import Path

import numba

_HERE = Path(__file__).resolve().parent


def _kernel_source_hash() -> str:
    digest = hashlib.sha256()
    for path in sorted(_HERE.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


_base = os.environ.get("NUMBA_CACHE_DIR") or str(_HERE / "__pycache__" / "numba")
numba.config.CACHE_DIR = os.path.join(_base, _kernel_source_hash())
