"""Contact location from a wrench: Bicchi's intrinsic contact sensing (soft-finger model).

Assume the moment about the contact point is a pure spin about the skin normal,
``q = σ n(r)``, and solve ``m = r × f + σ n(r)``, ``S(r) = 0`` for ``r`` and ``σ``
(manual §3.2). Of the two roots the one where the force pushes in (``f · n < 0``) is kept;
a sample with no pushing root on the skin is reported as invalid, not raised.

Each shape solves it in its own module (the shape protocol, :mod:`softtip.core.shape`):
closed forms for the sphere (exact to rounding), the capsule (hemisphere, then the cylinder
side) and the axis-aligned ellipsoid (mapped onto the unit sphere) in
:mod:`softtip.core.fingertip`; a damped Newton solver for any
:class:`~softtip.core.implicit.ImplicitSurface`; a cast and refinement on a triangle mesh
(:mod:`softtip.core.mesh`). This module runs them on batches and single samples.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import NP
from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.shape import Contact, SoftFinger

__all__ = ["Contact", "SoftFinger", "contact_from_wrench", "contact_kernel"]


def contact_kernel(tip: Fingertip, fx, fy, fz, mx, my, mz, xp=NP):
    """Component-wise soft-finger contact for ``tip`` (arrays with ``NP``, floats with ``PY``).

    Returns ``(rx, ry, rz, nx, ny, nz, sigma, valid)``: the shape's own solver
    (:meth:`~softtip.core.shape.Fingertip._contact_kernel`).
    """
    return tip._contact_kernel(fx, fy, fz, mx, my, mz, xp)


def contact_from_wrench(wrench: ArrayLike, tip: Fingertip | str) -> Contact:
    """Contact point, normal and spin of a soft-finger contact from the wrench (manual §3.2).

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m) in the sensor frame, bias removed.
    tip : Fingertip or str
        The fingertip, or a preset name / TOML path for :func:`~softtip.core.fingertip.load_fingertip`.

    Returns
    -------
    Contact
        ``point`` (..., 3) m, ``normal`` (..., 3), ``sigma`` (...) N·m, ``valid`` (...).
        Samples without a pushing root on the skin (or with zero force) are not valid and
        carry NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from softtip import Sphere, contact_from_wrench
    >>> tip = Sphere(0.016)
    >>> c = contact_from_wrench([0.0, 0.0, -2.0, 0.0, 0.0, 0.0], tip)   # press on the top
    >>> np.round(c.point * 1e3, 6).tolist(), bool(c.valid)
    ([0.0, 0.0, 16.0], True)
    """
    tip = load_fingertip(tip)
    w = np.asarray(wrench, dtype=float)
    if w.shape[-1:] != (6,):
        raise ValueError(f"wrench must have shape (..., 6), got {w.shape}")
    shape = w.shape[:-1]
    w2 = w.reshape(-1, 6)
    n = len(w2)
    point, normal = np.empty((n, 3)), np.empty((n, 3))
    sigma, valid = np.empty(n), np.empty(n, dtype=bool)
    for block, out in _blocks(tip, [w2[:, i] for i in range(6)]):
        for i in range(3):
            point[block, i], normal[block, i] = out[i], out[3 + i]
        sigma[block], valid[block] = out[6], out[7]
    invalid = ~valid
    if invalid.any():
        point[invalid] = np.nan
        normal[invalid] = np.nan
        sigma[invalid] = np.nan
    return Contact(point.reshape(*shape, 3), normal.reshape(*shape, 3), sigma.reshape(shape), valid.reshape(shape))


#: Samples per block in batch kernels: the temporaries of a block stay in cache, which
#: doubles the throughput over whole-array evaluation.
CHUNK = 16384


def _blocks(tip: Fingertip, comps: list[NDArray]):
    """Yield ``(block, kernel outputs)`` over cache-sized blocks of 1-D component arrays.

    Each block's components are copied to contiguous arrays first (the columns of an
    ``(N, 6)`` wrench are strided), so the kernel's temporaries stay in cache.
    """
    n = len(comps[0])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for start in range(0, n, CHUNK):
            block = slice(start, start + CHUNK)
            yield block, contact_kernel(tip, *(np.ascontiguousarray(c[block], dtype=float) for c in comps), xp=NP)


def contact_arrays(tip: Fingertip, fx, fy, fz, mx, my, mz) -> tuple[NDArray, ...]:
    """:func:`contact_kernel` over 1-D component arrays of any length, in cache-sized blocks.

    Returns the 8 arrays as a :class:`SoftFinger`; invalid samples are not masked.
    """
    comps = [np.asarray(c, dtype=float) for c in (fx, fy, fz, mx, my, mz)]
    n = len(comps[0])
    out = [np.empty(n) for _ in range(7)] + [np.empty(n, dtype=bool)]
    for block, res in _blocks(tip, comps):
        for dst, src in zip(out, res):
            dst[block] = src
    return SoftFinger(*out)
