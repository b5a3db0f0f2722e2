"""Reading mesh files (STL, OBJ, PLY; with `trimesh <https://trimesh.org>`_, imported on first use) and placing them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from softtip.errors import InputError

__all__ = ["MESH_SUFFIXES", "MESH_UNITS", "load_mesh", "rotation_from_rpy"]

#: The mesh files a fingertip can be read from
MESH_SUFFIXES = (".stl", ".obj", ".ply")

#: Length units accepted for ``mesh_units`` (metres per unit).
MESH_UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "in": 0.0254}


def rotation_from_rpy(roll: float, pitch: float, yaw: float) -> NDArray[np.float64]:
    """Rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)`` (URDF ``rpy``: fixed axes x, then y, then z), radians."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _import_trimesh():
    try:
        import trimesh
    except ImportError:  # pragma: no cover - trimesh is a dependency
        raise InputError(
            "mesh fingertips need the trimesh package: pip install trimesh"
        ) from None
    return trimesh


def load_mesh(path: str | Path, units: str) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Vertices (m, mesh frame) and faces of an STL, OBJ or PLY file.

    Raises
    ------
    InputError
        Unreadable file, unknown format or units, or a file without triangles.
    """
    path = Path(path)
    if units not in MESH_UNITS:
        raise InputError(f"mesh_units = {units!r}; expected one of {', '.join(MESH_UNITS)}")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(f"{path}: mesh file must be {', '.join(MESH_SUFFIXES[:-1])} or {MESH_SUFFIXES[-1]}")
    if not path.is_file():
        raise InputError(f"{path}: mesh file not found")
    trimesh = _import_trimesh()
    try:
        loaded: Any = trimesh.load(str(path), force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise InputError(f"{path}: cannot read the mesh: {exc}") from None
    faces = np.asarray(getattr(loaded, "faces", np.empty((0, 3))), dtype=np.int64)
    if faces.ndim != 2 or len(faces) == 0:
        raise InputError(f"{path}: the file holds no triangles")
    vertices = np.asarray(loaded.vertices, dtype=float) * MESH_UNITS[units]
    return vertices, faces
