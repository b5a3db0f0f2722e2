"""Rigid poses of the touched object in the sensor frame.

A :class:`Pose` maps object coordinates to sensor coordinates, ``x_s = R x_o + t``.
Composition follows function composition: ``(a @ b).apply(x) == a.apply(b.apply(x))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Pose", "rotation_matrix", "unit"]


def unit(v: ArrayLike, name: str = "vector") -> NDArray[np.float64]:
    """``v`` (shape (3,)) scaled to unit length; raises ``ValueError`` when it is ~0 or not finite."""
    a = np.asarray(v, dtype=float).reshape(3)
    n = float(np.linalg.norm(a))
    if not (math.isfinite(n) and n > 1e-12):
        raise ValueError(f"{name} must be a finite non-zero 3-vector, got {v!r}")
    return a / n


def rotation_matrix(axis: ArrayLike, angle: float) -> NDArray[np.float64]:
    """Right-handed rotation by ``angle`` (rad) about ``axis`` (any non-zero 3-vector), shape (3, 3)."""
    k = unit(axis, "rotation axis")
    c, s = math.cos(angle), math.sin(angle)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * kx + (1.0 - c) * (kx @ kx)


@dataclass(frozen=True, eq=False)
class Pose:
    """Rigid transform from object coordinates to the sensor frame.

    Parameters
    ----------
    rotation : array-like, shape (3, 3)
        Proper rotation ``R``; its columns are the object axes in sensor coordinates.
    translation : array-like, shape (3,)
        Object origin in the sensor frame, m.
    """

    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]

    def __post_init__(self) -> None:
        r = np.array(self.rotation, dtype=float).reshape(3, 3)
        t = np.array(self.translation, dtype=float).reshape(3)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(t))):
            raise ValueError("pose must be finite")
        if np.abs(r.T @ r - np.eye(3)).max() > 1e-9 or np.linalg.det(r) < 0.0:
            raise ValueError("pose rotation must be a proper rotation matrix")
        r.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "rotation", r)
        object.__setattr__(self, "translation", t)

    @classmethod
    def identity(cls) -> Pose:
        """The identity pose."""
        return cls._trusted(np.eye(3), np.zeros(3))

    @classmethod
    def from_translation(cls, offset: ArrayLike) -> Pose:
        """A pure translation by ``offset`` (m, shape (3,))."""
        t = np.asarray(offset, dtype=float).reshape(3)
        if not np.all(np.isfinite(t)):
            raise ValueError(f"offset must be finite, got {offset!r}")
        return cls._trusted(np.eye(3), t)

    @classmethod
    def from_axis_angle(cls, axis: ArrayLike, angle: float, pivot: ArrayLike | None = None) -> Pose:
        """Rotation by ``angle`` (rad) about the line through ``pivot`` (m, default origin) along ``axis``."""
        if not math.isfinite(angle):
            raise ValueError(f"angle must be finite, got {angle!r}")
        r = rotation_matrix(axis, angle)
        p = np.zeros(3) if pivot is None else np.asarray(pivot, dtype=float).reshape(3)
        if not np.all(np.isfinite(p)):
            raise ValueError(f"pivot must be finite, got {pivot!r}")
        return cls._trusted(r, p - r @ p)

    @classmethod
    def from_frame(cls, x_axis: ArrayLike, z_axis: ArrayLike, origin: ArrayLike) -> Pose:
        """Pose whose object x and z axes point along ``x_axis`` and (the part of ``z_axis``
        perpendicular to ``x_axis``), with the object origin at ``origin`` (m)."""
        x = unit(x_axis, "x_axis")
        z = np.asarray(z_axis, dtype=float).reshape(3)
        z = unit(z - (z @ x) * x, "z_axis (perpendicular part)")
        y = np.cross(z, x)
        return cls(np.column_stack((x, y, z)), np.asarray(origin, dtype=float))

    def apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Object coordinates to sensor frame, shape ``(..., 3)``."""
        return np.asarray(points, dtype=float) @ self.rotation.T + self.translation

    def inverse_apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Sensor frame to object coordinates, shape ``(..., 3)``."""
        return (np.asarray(points, dtype=float) - self.translation) @ self.rotation

    def rotate(self, vectors: ArrayLike) -> NDArray[np.float64]:
        """Rotate free vectors from object to sensor axes, shape ``(..., 3)``."""
        return np.asarray(vectors, dtype=float) @ self.rotation.T

    def inverse_rotate(self, vectors: ArrayLike) -> NDArray[np.float64]:
        """Rotate free vectors from sensor to object axes, shape ``(..., 3)``."""
        return np.asarray(vectors, dtype=float) @ self.rotation

    @classmethod
    def _trusted(cls, rotation: NDArray[np.float64], translation: NDArray[np.float64]) -> Pose:
        # products of validated poses: skip the orthogonality check (hot path of the solver)
        p = object.__new__(cls)
        rotation = np.array(rotation, dtype=float)
        translation = np.array(translation, dtype=float)
        rotation.setflags(write=False)
        translation.setflags(write=False)
        object.__setattr__(p, "rotation", rotation)
        object.__setattr__(p, "translation", translation)
        return p

    def __matmul__(self, other: Pose) -> Pose:
        return Pose._trusted(self.rotation @ other.rotation, self.rotation @ other.translation + self.translation)

    def inverse(self) -> Pose:
        """The inverse transform (sensor frame to object coordinates)."""
        return Pose._trusted(self.rotation.T, -(self.rotation.T @ self.translation))

    def as_dict(self) -> dict:
        """JSON-ready form: ``{"rotation": 3x3 list, "translation_m": 3 list}``."""
        return {"rotation": self.rotation.tolist(), "translation_m": self.translation.tolist()}
