"""What decides a simulated log besides the simulator's inputs, as a digest: a key for caches.

The tests and the benchmarks keep simulated logs on disk (``tests/simcache.py``,
``benchmarks/bench_physics.py``); an entry is valid while its inputs and this digest are the
same. The digest covers the sources of :mod:`softtip.sim` and :mod:`softtip.core` (the
simulator and the shapes and kernels it calls), Python's version and the versions of the
libraries that may move the last bits of a result (numpy, scipy, numba, trimesh).
"""

from __future__ import annotations

import hashlib
import sys
from importlib import metadata
from pathlib import Path

__all__ = ["SOURCE_PACKAGES", "NUMERIC_DISTRIBUTIONS", "simulator_digest"]

#: softtip's subpackages whose sources decide what the simulator computes
SOURCE_PACKAGES = ("sim", "core")
#: Libraries whose versions may move the simulator's last bits (numba and trimesh: the mesh tips)
NUMERIC_DISTRIBUTIONS = ("numpy", "scipy", "numba", "trimesh")


def _installed(distribution: str) -> str:
    try:
        return f"{distribution} {metadata.version(distribution)}"
    except metadata.PackageNotFoundError:
        return f"{distribution} absent"


def simulator_digest(root: str | Path | None = None) -> str:
    """The digest of :data:`SOURCE_PACKAGES`' sources (every ``.py`` file, its path and bytes),
    Python's version and :data:`NUMERIC_DISTRIBUTIONS`' versions: 20 hex digits, the same
    wherever they are the same (a checkout, an installed copy).

    Parameters
    ----------
    root : path, optional
        The ``softtip`` package directory whose subpackages are read (default: this one).
    """
    h = hashlib.sha256()
    for part in (sys.version, *map(_installed, NUMERIC_DISTRIBUTIONS)):
        h.update(part.encode() + b"\0")
    root = Path(__file__).resolve().parent.parent if root is None else Path(root)
    for package in SOURCE_PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:20]
