"""Discretisation of the undeformed skin surface into small surface elements.

Each shape discretises its own skin (:meth:`~softtip.core.shape.Fingertip.skin_elements`,
the shape protocol): the sphere's, the capsule's cap and the ellipsoid with a Fibonacci
spiral lattice, which is equal-area, quasi-uniform and has no pole (the fingertip's apex,
where the papers touch, is not a singular point of the grid and no direction in the
tangent plane is preferred); the capsule's cylindrical side with a staggered (brick) grid;
a triangle mesh with its own triangles, subdivided; a mounted shape with its shape's
elements, placed by the mount. Only skin that can be touched is covered: the capsule and
a mesh from ``z = z_min`` (default 0, the sensor flange) up, the sphere and the ellipsoid
down to 120° from their top.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Fingertip

__all__ = ["SkinMesh", "discretise_skin", "DEFAULT_ELEMENTS"]

#: Default number of skin elements (the brief asks for at least 10 000).
DEFAULT_ELEMENTS = 12_000


@dataclass(frozen=True, eq=False)
class SkinMesh:
    """Surface elements of the undeformed skin, sensor frame.

    Attributes
    ----------
    centres : array, shape (N, 3)
        Element centres on the skin surface, m.
    normals : array, shape (N, 3)
        Outward unit normals at the centres.
    areas : array, shape (N,)
        Element areas, m²; they sum to the covered skin area.
    spacing : array, shape (N,)
        Element size ``sqrt(area)``, m (the width of the coverage filter).
    tip : Fingertip
        The fingertip the mesh was built from.
    """

    centres: NDArray[np.float64]
    normals: NDArray[np.float64]
    areas: NDArray[np.float64]
    spacing: NDArray[np.float64]
    tip: Fingertip

    def __post_init__(self) -> None:
        for name in ("centres", "normals", "areas", "spacing"):
            a = np.ascontiguousarray(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    def __len__(self) -> int:
        return len(self.areas)

    @property
    def total_area(self) -> float:
        """Covered skin area, m²."""
        return float(self.areas.sum())


def discretise_skin(tip: Fingertip, n_elements: int = DEFAULT_ELEMENTS, z_min: float | None = None) -> SkinMesh:
    """Discretise the touchable skin of ``tip`` into about ``n_elements`` surface elements.

    Parameters
    ----------
    tip : Fingertip
        The fingertip (sensor frame): any shape that implements
        :meth:`~softtip.core.shape.Fingertip.skin_elements` (sphere, capsule, ellipsoid,
        mesh, and a :class:`~softtip.core.mounting.Mounted` one of them: its shape's skin,
        moved and rotated).
    n_elements : int
        Target element count (the result is within a few elements of it; a mesh finer than
        this keeps one element per triangle).
    z_min : float, optional
        Lowest covered height, m. Capsule and mesh: default 0 (the whole side from the
        sensor flange up). Sphere and ellipsoid: default ``center_z`` minus half the
        vertical semi-axis (120° from the top). For a mounted shape, in the shape's own frame.

    Returns
    -------
    SkinMesh

    Raises
    ------
    TypeError
        The shape has no simulator skin (an :class:`~softtip.core.implicit.ImplicitSurface`).
    """
    n_elements = int(n_elements)
    if n_elements < 50:
        raise ValueError(f"n_elements must be at least 50, got {n_elements}")
    c, n, a = tip.skin_elements(n_elements, z_min)
    return SkinMesh(c, n, a, np.sqrt(a), tip)
