"""Discretisation of the undeformed skin surface into small surface elements.

The hemispherical (or spherical) part is sampled with a Fibonacci spiral lattice, which is
equal-area, quasi-uniform and has no pole: the fingertip's apex, where the papers touch,
is not a singular point of the grid and no direction in the tangent plane is preferred.
The capsule's cylindrical side is a staggered (brick) grid. Only skin that can be touched
is covered: the capsule from ``z = z_min`` (default 0, the sensor flange) up, the sphere
down to 120° from its top.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Capsule, Fingertip, Sphere
from softtip.core.mounting import Mounted

__all__ = ["SkinMesh", "discretise_skin", "discretise_mesh_skin", "DEFAULT_ELEMENTS"]

#: Default number of skin elements (the brief asks for at least 10 000).
DEFAULT_ELEMENTS = 12_000

_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


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


def _fibonacci_cap(n: int, cos_min: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``n`` equal-area unit vectors with ``z`` from 1 down to ``cos_min``, and their areas on the unit sphere."""
    k = np.arange(n) + 0.5
    cz = 1.0 - k * (1.0 - cos_min) / n
    sz = np.sqrt(np.maximum(1.0 - cz * cz, 0.0))
    phi = _GOLDEN_ANGLE * np.arange(n)
    u = np.column_stack((sz * np.cos(phi), sz * np.sin(phi), cz))
    area = np.full(n, 2.0 * math.pi * (1.0 - cos_min) / n)
    return u, area


def discretise_skin(tip: Fingertip, n_elements: int = DEFAULT_ELEMENTS, z_min: float | None = None) -> SkinMesh:
    """Discretise the touchable skin of ``tip`` into about ``n_elements`` surface elements.

    Parameters
    ----------
    tip : Capsule, Sphere, MeshFingertip or Mounted
        The fingertip (sensor frame); a mesh goes to :func:`discretise_mesh_skin`; a
        :class:`~softtip.core.mounting.Mounted` shape is discretised in its own frame and its
        elements placed by the mount (the same skin, moved and rotated).
    n_elements : int
        Target element count (the result is within a few elements of it).
    z_min : float, optional
        Lowest covered height, m. Capsule: default 0 (the whole side from the sensor
        flange up). Sphere: default ``center_z - radius/2`` (120° from the top). For a
        mounted shape, in the shape's own frame.

    Returns
    -------
    SkinMesh
    """
    n_elements = int(n_elements)
    if n_elements < 50:
        raise ValueError(f"n_elements must be at least 50, got {n_elements}")
    if isinstance(tip, Capsule):
        r, length = tip.radius, tip.length
        z0 = 0.0 if z_min is None else float(z_min)
        if z0 > length:
            raise ValueError(f"z_min must not exceed the capsule length {length} m, got {z0}")
        a_cap = 2.0 * math.pi * r * r
        a_side = 2.0 * math.pi * r * (length - z0)
        h = math.sqrt((a_cap + a_side) / n_elements)
        n_cap = max(1, round(a_cap / (h * h)))
        u, w = _fibonacci_cap(n_cap, 0.0)
        ox, oy = tip.axis_offset
        centres = [u * r + np.array([ox, oy, length])]
        normals = [u]
        areas = [w * r * r]
        if a_side > 0.0:
            n_phi = max(3, round(2.0 * math.pi * r / h))
            n_z = max(1, round((length - z0) / h))
            dphi, dz = 2.0 * math.pi / n_phi, (length - z0) / n_z
            j, i = np.meshgrid(np.arange(n_z), np.arange(n_phi), indexing="ij")
            phi = (i + 0.5 * (j % 2)).ravel() * dphi  # staggered rows: a brick pattern
            z = z0 + (j.ravel() + 0.5) * dz
            nrm = np.column_stack((np.cos(phi), np.sin(phi), np.zeros_like(phi)))
            centres.append(np.column_stack((ox + r * nrm[:, 0], oy + r * nrm[:, 1], z)))
            normals.append(nrm)
            areas.append(np.full(len(phi), r * dphi * dz))
        c, n, a = np.concatenate(centres), np.concatenate(normals), np.concatenate(areas)
    elif isinstance(tip, Sphere):
        r = tip.radius
        cen = np.array(tip.center)
        zc = cen[2] - 0.5 * r if z_min is None else float(z_min)
        cos_min = min(max((zc - cen[2]) / r, -1.0), 1.0)
        if cos_min >= 1.0:
            raise ValueError(f"z_min {zc} m leaves no skin on the sphere")
        u, w = _fibonacci_cap(n_elements, cos_min)
        c, n, a = cen + r * u, u, w * r * r
    elif getattr(tip, "kind", "") == "mesh":
        return discretise_mesh_skin(tip, n_elements, z_min)
    elif isinstance(tip, Mounted):
        # the shape's own skin (z_min in its own frame: its flange), placed by the mount
        own = discretise_skin(tip.tip, n_elements, z_min)
        rot, shift = np.array(tip.rotation), np.array(tip.translation)
        return SkinMesh(own.centres @ rot.T + shift, own.normals @ rot.T, own.areas, own.spacing, tip)
    else:
        raise TypeError(
            f"the simulator discretises capsule, sphere and mesh fingertips; got {type(tip).__name__}"
        )
    return SkinMesh(c, n, a, np.sqrt(a), tip)


def discretise_mesh_skin(tip, n_elements: int = DEFAULT_ELEMENTS, z_min: float | None = None) -> SkinMesh:
    """Skin elements of a triangle-mesh fingertip (:class:`softtip.core.mesh.MeshFingertip`).

    Every triangle above ``z_min`` becomes one element or, when it is larger than the target
    element area (the covered area over ``n_elements``), ``k²`` equal sub-triangles on a
    barycentric grid. Element centres lie on the mesh; normals are the mesh's interpolated
    normals there, as the estimator sees them. A mesh finer than ``n_elements`` keeps one
    element per triangle (more elements than asked).

    Parameters
    ----------
    tip : MeshFingertip
    n_elements : int
        Target element count (at least).
    z_min : float, optional
        Lowest covered height, m (default 0: the face where the fingertip is mounted on the
        sensor, and anything below it, is not skin). A triangle is covered when its centroid
        is above ``z_min``.
    """
    n_elements = int(n_elements)
    if n_elements < 50:
        raise ValueError(f"n_elements must be at least 50, got {n_elements}")
    z0 = 0.0 if z_min is None else float(z_min)
    v, f = tip.vertices, tip.faces
    tri = v[f]
    centroid_z = tri[:, :, 2].mean(axis=1)
    keep = np.flatnonzero(centroid_z > z0 + 1e-9 * tip.bounding_sphere[1])
    if keep.size == 0:
        raise ValueError(f"z_min {z0} m leaves no skin on the mesh")
    area = 0.5 * np.linalg.norm(np.cross(tri[keep, 1] - tri[keep, 0], tri[keep, 2] - tri[keep, 0]), axis=1)
    target = area.sum() / n_elements
    k = np.maximum(1, np.ceil(np.sqrt(area / target) - 1e-9)).astype(int)
    faces, b1s, b2s, areas = [], [], [], []
    for kk in np.unique(k):
        sel = keep[k == kk]
        # centroids of the k² sub-triangles, barycentric (b1, b2): upward and downward ones
        i, j = np.meshgrid(np.arange(kk), np.arange(kk), indexing="ij")
        up = (i + j) <= kk - 1
        down = (i + j) <= kk - 2
        sb1 = np.concatenate(((i[up] + 1 / 3) / kk, (i[down] + 2 / 3) / kk))
        sb2 = np.concatenate(((j[up] + 1 / 3) / kk, (j[down] + 2 / 3) / kk))
        faces.append(np.repeat(sel, len(sb1)))
        b1s.append(np.tile(sb1, len(sel)))
        b2s.append(np.tile(sb2, len(sel)))
        areas.append(np.repeat(area[np.searchsorted(keep, sel)] / kk**2, len(sb1)))
    face = np.concatenate(faces)
    centres, normals = tip._interp(face, np.concatenate(b1s), np.concatenate(b2s))
    a = np.concatenate(areas)
    return SkinMesh(centres, normals, a, np.sqrt(a), tip)
