"""Small vector helpers on arrays of shape ``(..., 3)``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def cross(a: NDArray, b: NDArray) -> NDArray:
    """``a × b`` component-wise, shape ``(..., 3)`` (faster than ``np.cross`` on small batches)."""
    return np.stack(
        (
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ),
        axis=-1,
    )


def skew(v: NDArray) -> NDArray:
    """The cross-product matrix ``[v]×`` of ``v`` (..., 3), shape ``(..., 3, 3)``."""
    z = np.zeros(v.shape[:-1])
    return np.stack(
        (
            np.stack((z, -v[..., 2], v[..., 1]), axis=-1),
            np.stack((v[..., 2], z, -v[..., 0]), axis=-1),
            np.stack((-v[..., 1], v[..., 0], z), axis=-1),
        ),
        axis=-2,
    )


def tangent_basis(n: NDArray) -> tuple[NDArray, NDArray]:
    """Two unit tangents ``t1, t2`` (..., 3) with ``(t1, t2, n)`` right-handed, for unit ``n`` (..., 3).

    ``t1`` is perpendicular to ``n`` and to +z (to +x where ``n`` is within 26° of ±z).
    """
    ref = np.where(np.abs(n[..., 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t1 = cross(ref, n)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    return t1, cross(n, t1)
