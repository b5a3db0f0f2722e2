"""The triangle-mesh fingertip: a CAD mesh of the skin surface as a :class:`~softtip.core.shape.Fingertip`, and its TOML table.

The contact solve is split by step: :mod:`~softtip.core.mesh.topology` prepares the mesh,
:mod:`~softtip.core.mesh.cast` finds where the wrench's axis enters the skin,
:mod:`~softtip.core.mesh.refine` refines that point by Newton's method,
:mod:`~softtip.core.mesh.crease` solves on the sharp features and
:mod:`~softtip.core.mesh.closest` answers closest-point queries; this module holds the
class that ties them together.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import NP, PY
from softtip.core.mesh.cast import _WALK, AxisCast
from softtip.core.mesh.closest import ClosestPoints
from softtip.core.mesh.crease import CreaseContact
from softtip.core.mesh.files import MESH_UNITS, load_mesh
from softtip.core.mesh.refine import NewtonRefine
from softtip.core.mesh.topology import (
    _LEAF,
    _bodies,
    _clusters,
    _corner_normals,
    _creases,
    _edge_neighbours,
    _exposure,
    _near_classes,
)
from softtip.core.mounting import pose_from_table, rpy_of
from softtip.core.shape import SIZE_RANGE, Fingertip, fingertip_table
from softtip.errors import InputError

__all__ = ["MeshFingertip", "load_mesh_fingertip", "mesh_fingertip_from_table"]

_BRANCH = 16  # at most this many clusters per super-cluster


@dataclass(frozen=True, eq=False)
class MeshFingertip(ClosestPoints, AxisCast, CreaseContact, NewtonRefine, Fingertip):
    """A fingertip whose skin is a closed triangle mesh (sensor frame, metres).

    Parameters
    ----------
    vertices : array-like, shape (V, 3)
        Vertex positions, m, sensor frame.
    faces : array-like of int, shape (F, 3)
        Triangles, counter-clockwise seen from outside (outward normals).
    crease_angle_deg : float
        Edges whose faces meet at more than this angle keep a sharp normal; smoother edges
        get a continuous interpolated normal.
    skin_thickness : float, optional
        Thickness of the soft skin over the rigid core, m (used by the simulator).
    source : str, optional
        Where the mesh came from (file), for messages and :meth:`to_toml`.
    mesh_units, translation, rpy
        How the file was placed in the sensor frame (for :meth:`to_toml`): units of the
        file, translation (m) and roll-pitch-yaw (rad) of the mesh frame in the sensor frame.

    Raises
    ------
    ValueError
        The mesh is not closed, not consistently wound, wound inward (inverted normals), has
        degenerate triangles, or is not of a fingertip's size.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    crease_angle_deg: float = 40.0
    skin_thickness: float | None = None
    source: str | None = None
    mesh_units: str = "m"
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    _d: dict = field(default_factory=dict, init=False, repr=False)
    kind: ClassVar[str] = "mesh"
    implied_by: ClassVar[str | None] = "mesh"
    reads_mount: ClassVar[bool] = True
    calibrates: ClassVar[str | None] = "placement"

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, dtype=float)
        f = np.ascontiguousarray(self.faces, dtype=np.int64)
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.all(np.isfinite(v)):
            raise ValueError(f"vertices must be finite, shape (V >= 4, 3); got {v.shape}")
        if f.ndim != 2 or f.shape[1] != 3 or len(f) < 4 or f.min() < 0 or f.max() >= len(v):
            raise ValueError(f"faces must be vertex indices, shape (F >= 4, 3); got {f.shape}")
        if not (0.0 < float(self.crease_angle_deg) <= 180.0):
            raise ValueError(f"crease_angle_deg must be in (0, 180], got {self.crease_angle_deg!r}")
        if self.skin_thickness is not None:
            t = float(self.skin_thickness)
            if not (math.isfinite(t) and t > 0.0):
                raise ValueError(f"skin_thickness must be a positive length in metres, got {self.skin_thickness!r}")
            object.__setattr__(self, "skin_thickness", t)
        v.setflags(write=False)
        f.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        self._prepare()

    # -- preparation ----------------------------------------------------------------------
    def _prepare(self) -> None:
        v, f = self.vertices, self.faces
        extent = float(np.max(v.max(axis=0) - v.min(axis=0)))
        lo, hi = SIZE_RANGE  # a mesh drawn in mm read as cm is 10× too large: 200 mm for a 20 mm tip
        if extent > hi:
            raise ValueError(
                f"the mesh is {extent:.4g} m across, {extent / 0.03:.0f}× a fingertip's size: "
                "wrong mesh_units (a mesh drawn in mm read as m is 1000× too large, read as cm 10×)?"
            )
        if extent < lo:
            raise ValueError(
                f"the mesh is {extent * 1e3:.4g} mm across, {0.03 / extent:.0f}× smaller than a fingertip: "
                "wrong mesh_units (a mesh drawn in m read as mm is 1000× too small)?"
            )
        v0, v1, v2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        cross = np.cross(v1 - v0, v2 - v0)
        dbl_area = np.linalg.norm(cross, axis=1)
        bad = dbl_area <= 1e-12 * extent * extent
        if bad.any():
            raise ValueError(f"{int(bad.sum())} degenerate (zero-area) triangles, e.g. face {int(np.argmax(bad))}")
        face_n = cross / dbl_area[:, None]
        nb_face, li, lj = _edge_neighbours(f)
        bodies = _bodies(nb_face)
        if bodies > 1:  # a contact could land on the other body (a loose part of a CAD export)
            raise ValueError(
                f"the mesh has {bodies} separate closed surfaces; expected one, the fingertip's outer surface (remove "
                "the others, e.g. keep the largest of trimesh's mesh.split(); a hollow solid's inner surface is one)"
            )
        volume = float(np.sum(v0 * np.cross(v1, v2)) / 6.0)
        if volume <= 0.0:
            raise ValueError(
                f"the mesh's signed volume is {volume:.3g} m³: its faces are wound inward (inverted normals); "
                "flip them (e.g. trimesh's mesh.invert())"
            )
        cn = _corner_normals(v, f, face_n, math.cos(math.radians(self.crease_angle_deg)))
        centroids = (v0 + v1 + v2) / 3.0
        groups = _clusters(centroids, _LEAF)
        n_cl = len(groups)
        members = np.full((n_cl, _LEAF), len(f), dtype=np.int64)  # padded with a dummy face
        cl_centre = np.empty((n_cl, 3))
        cl_radius = np.empty(n_cl)
        face_cluster = np.empty(len(f), dtype=np.int64)
        for c, idx in enumerate(groups):
            members[c, : len(idx)] = idx
            face_cluster[idx] = c
            pts = np.concatenate((v0[idx], v1[idx], v2[idx]))
            centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
            cl_centre[c] = centre
            cl_radius[c] = np.sqrt(np.max(np.sum((pts - centre) ** 2, axis=1)))
        # super-clusters of clusters: the first level of the pre-filter
        sgroups = _clusters(cl_centre, _BRANCH)
        n_sup = len(sgroups)
        sup_members = np.full((n_sup, _BRANCH), n_cl, dtype=np.int64)  # padded with a dummy cluster
        sup_centre = np.empty((n_sup, 3))
        sup_radius = np.empty(n_sup)
        for c, idx in enumerate(sgroups):
            sup_members[c, : len(idx)] = idx
            lo_c = np.min(cl_centre[idx] - cl_radius[idx, None], axis=0)
            hi_c = np.max(cl_centre[idx] + cl_radius[idx, None], axis=0)
            centre = 0.5 * (lo_c + hi_c)
            sup_centre[c] = centre
            sup_radius[c] = np.max(np.linalg.norm(cl_centre[idx] - centre, axis=1) + cl_radius[idx])
        # Plücker rows of the edges, one per unique undirected edge (same numbers in both faces)
        plucker = np.zeros((len(f) + 1, 3, 6))  # the last row: a dummy face that no line hits
        for k in range(3):
            a = v[f[:, (k + 1) % 3]]
            b = v[f[:, (k + 2) % 3]]
            swap = f[:, (k + 1) % 3] > f[:, (k + 2) % 3]
            lo_p = np.where(swap[:, None], b, a)
            hi_p = np.where(swap[:, None], a, b)
            sign = np.where(swap, -1.0, 1.0)[:, None]
            # side(line (d, m), edge a→b) = d · (a × b) + (b − a) · m
            plucker[:-1, k, :3] = sign * np.cross(lo_p, hi_p)
            plucker[:-1, k, 3:] = sign * (hi_p - lo_p)
        centre_bb = 0.5 * (v.min(axis=0) + v.max(axis=0))
        radius_bb = float(np.sqrt(np.max(np.sum((v - centre_bb) ** 2, axis=1))))
        # per-face rows for the refinement kernel: v0, e1, e2, n0, n1 − n0, n2 − n0
        e1, e2 = v1 - v0, v2 - v0
        g11, g12, g22 = np.sum(e1 * e1, axis=1), np.sum(e1 * e2, axis=1), np.sum(e2 * e2, axis=1)
        gdet = g11 * g22 - g12 * g12
        # columns 18-20: the inverse Gram matrix [[g22, -g12], [-g12, g11]] / det (in-plane
        # displacement → barycentric step)
        geom = np.concatenate(
            (v0, e1, e2, cn[:, 0], cn[:, 1] - cn[:, 0], cn[:, 2] - cn[:, 0],
             np.column_stack((g22 / gdet, g12 / gdet, g11 / gdet))),
            axis=1,
        )  # fmt: skip
        # crossing edge k of face t: the neighbour and its (b1, b2) from our (b_i, b_j)
        c1i = (li == 1).astype(float)
        c1j = (lj == 1).astype(float)
        c2i = (li == 2).astype(float)
        c2j = (lj == 2).astype(float)
        d = self._d
        d.update(
            extent=extent,
            face_n=face_n,
            cn=cn,
            v0=v0,
            v1=v1,
            v2=v2,
            centroids=centroids,
            members=members,
            cl_centre=cl_centre,
            cl_radius=cl_radius,
            cl_centre2=np.sum(cl_centre * cl_centre, axis=1),
            cl_radius2=(cl_radius * (1.0 + 1e-9) + 1e-12 * extent) ** 2,
            # padded with a dummy cluster that no line reaches
            cl_centre_p=np.concatenate((cl_centre, np.zeros((1, 3)))),
            cl_radius2_p=np.concatenate(((cl_radius * (1.0 + 1e-9) + 1e-12 * extent) ** 2, [-1.0])),
            sup_members=sup_members,
            sup_centre=sup_centre,
            sup_centre2=np.sum(sup_centre * sup_centre, axis=1),
            sup_radius2=(sup_radius * (1.0 + 1e-9) + 1e-12 * extent) ** 2,
            face_cluster=face_cluster,
            plucker=plucker,
            plucker18=plucker.reshape(-1, 18),
            geom=geom,
            geom_py=[tuple(row) for row in geom.tolist()],
            nb=nb_face,
            nb_py=nb_face.tolist(),
            conv=np.stack((c1i, c1j, c2i, c2j), axis=-1),
            conv_py=[[tuple(e) for e in row] for row in np.stack((c1i, c1j, c2i, c2j), axis=-1).tolist()],
            centre=centre_bb,
            radius=radius_bb,
            volume=volume,
            near_classes=_near_classes(centroids, np.stack((v0, v1, v2))),
            tri9=np.concatenate((v0, v1, v2), axis=1),
            last_normal=(None, None),
            last_project=(None, None),
        )
        edges, corners = _creases(v, f, face_n, cn, nb_face, li, lj, extent)
        d.update(crease_edges=edges, crease_corners=corners, crease_any=bool(len(edges["ax"]) or len(corners["vx"])))
        # the streaming cast's warm start: a walk from the previous sample's face
        d.update(
            exposure=_exposure(v, f, face_n, v0, centroids, extent),
            plucker_py=[tuple(tuple(e) for e in row) for row in plucker[:-1].tolist()],
            face_n_py=[tuple(r) for r in face_n.tolist()],
            centroids_py=[tuple(r) for r in centroids.tolist()],
            # per cluster: the monomials of its centre for the axis test, its faces' Plücker rows
            cl_quad=np.column_stack((
                cl_centre ** 2, cl_centre[:, 0] * cl_centre[:, 1], cl_centre[:, 0] * cl_centre[:, 2],
                cl_centre[:, 1] * cl_centre[:, 2], cl_centre, np.ones(n_cl), -d["cl_radius2"],
            )),  # fmt: skip
            cl_plucker=np.ascontiguousarray(
                np.concatenate((plucker, plucker.sum(axis=1, keepdims=True)), axis=1)[members].reshape(n_cl, -1)
            ),
            walk_reach2=(0.5 * _WALK * float(np.max(np.linalg.norm(np.concatenate((e1, e2)), axis=1)))) ** 2,
            hint=-1,
        )

    # -- geometry queries ---------------------------------------------------------------------
    def _surface_kernel(self, x, y, z, xp):
        """Signed distance to the mesh (m): negative inside (sign from the interpolated normal)."""
        return self._query(x, y, z, xp, "surface")

    def _normal_kernel(self, x, y, z, xp):
        """Interpolated outward normal at the closest point of the mesh."""
        return self._query(x, y, z, xp, "normal")

    def _project_kernel(self, x, y, z, xp):
        """Closest point of the mesh."""
        return self._query(x, y, z, xp, "project")

    def winding_number(self, points: ArrayLike) -> NDArray[np.float64]:
        """Generalised winding number of the mesh at ``points`` (..., 3): 1 inside, 0 outside."""
        p = np.asarray(points, dtype=float)
        shape = p.shape[:-1]
        p = p.reshape(-1, 3)
        d = self._d
        out = np.empty(len(p))
        for i, q in enumerate(p):  # a few validation points, not a per-sample path
            a, b, c = d["v0"] - q, d["v1"] - q, d["v2"] - q
            la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
            num = np.sum(a * np.cross(b, c), axis=1)
            den = la * lb * lc + np.sum(a * b, axis=1) * lc + np.sum(b * c, axis=1) * la + np.sum(c * a, axis=1) * lb
            out[i] = np.sum(2.0 * np.arctan2(num, den)) / (4.0 * math.pi)
        return out.reshape(shape)

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return self._d["centre"].copy(), self._d["radius"]

    @property
    def face_normals(self) -> NDArray[np.float64]:
        """Geometric unit normals of the triangles, shape (F, 3)."""
        return self._d["face_n"]

    @property
    def corner_normals(self) -> NDArray[np.float64]:
        """Interpolation normals at the triangles' corners, shape (F, 3, 3)."""
        return self._d["cn"]

    @property
    def volume(self) -> float:
        """Enclosed volume, m³."""
        return self._d["volume"]

    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """Every triangle above ``z_min`` as one element or, when it is larger than the target
        element area (the covered area over ``n_elements``), ``k²`` equal sub-triangles on a
        barycentric grid.

        Element centres lie on the mesh; normals are the mesh's interpolated normals there, as
        the estimator sees them. A mesh finer than ``n_elements`` keeps one element per
        triangle (more elements than asked). ``z_min``: lowest covered height, m (default 0:
        the face where the fingertip is mounted on the sensor, and anything below it, is not
        skin); a triangle is covered when its centroid is above it. See
        :meth:`Fingertip.skin_elements`.
        """
        z0 = 0.0 if z_min is None else float(z_min)
        v, f = self.vertices, self.faces
        tri = v[f]
        centroid_z = tri[:, :, 2].mean(axis=1)
        keep = np.flatnonzero(centroid_z > z0 + 1e-9 * self.bounding_sphere[1])
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
        centres, normals = self._interp(face, np.concatenate(b1s), np.concatenate(b2s))
        return centres, normals, np.concatenate(areas)

    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        """The mesh's own triangles, with vertex normals for shading (the corner normals
        around each vertex, averaged); ``n_around`` and ``n_along`` are not used.
        See :meth:`Fingertip.surface_mesh`."""
        acc = np.zeros((len(self.vertices), 3))
        np.add.at(acc, self.faces.ravel(), self.corner_normals.reshape(-1, 3))
        normals = acc / np.linalg.norm(acc, axis=1, keepdims=True)
        return self.vertices.copy(), self.faces.astype(np.int32), normals

    @classmethod
    def from_table(cls, table: dict, source: str) -> Fingertip:
        """See :func:`mesh_fingertip_from_table`."""
        return mesh_fingertip_from_table(table, source)

    def to_toml(self, folder: str | os.PathLike[str] | None = None) -> str:
        """The fingertip file's text; the mesh named by its path relative to ``folder`` (the file's
        own folder, as a fingertip file's paths are read), else absolute."""
        if self.source is None:
            raise ValueError("a mesh fingertip built from arrays has no file to name in TOML; save the mesh first")
        t = ", ".join(repr(float(x)) for x in self.translation)
        r = ", ".join(repr(math.degrees(float(x))) for x in self.rpy)
        mesh = Path(self.source).resolve()
        if folder is not None:
            try:
                mesh = Path(os.path.relpath(mesh, Path(folder).resolve()))
            except ValueError:  # another drive (Windows): absolute
                pass
        lines = [
            "[fingertip]",
            'shape = "mesh"',
            f"mesh = {_toml_str(mesh.as_posix())}",
            f'mesh_units = "{self.mesh_units}"',
            f"crease_angle_deg = {float(self.crease_angle_deg)!r}",
        ]
        if self.skin_thickness is not None:
            lines.append(f"skin_thickness = {self.skin_thickness!r}")
        lines += ["", "[fingertip.mount]", f"translation = [{t}]", f"rpy_deg = [{r}]"]
        return "\n".join(lines) + "\n"

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp=NP):
        """Soft-finger contact on the mesh, component-wise (see :func:`softtip.core.location.contact_kernel`).

        Returns ``(rx, ry, rz, nx, ny, nz, sigma, valid)``.
        """
        if xp is PY:
            face, b1, b2 = self._cast_one(fx, fy, fz, mx, my, mz)
            res = self._refine(face, b1, b2, fx, fy, fz, mx, my, mz, PY)
            if res[7] or face < 0 or not self._d["crease_any"]:
                return res
            # no smooth root: the contact sits on a sharp edge or corner (the same numpy code
            # as the batch path, on one sample)
            one = self._crease_contact(*(np.array([c]) for c in (fx, fy, fz, mx, my, mz)))
            return tuple(float(c[0]) for c in one[:7]) + (bool(one[7][0]),)
        comps = np.broadcast_arrays(*(np.asarray(c, dtype=float) for c in (fx, fy, fz, mx, my, mz)))
        shape = comps[0].shape
        w = np.stack([c.ravel() for c in comps], axis=-1)
        face, b1, b2 = self._cast(w[:, :3], w[:, 3:])
        out = [np.full(len(w), np.nan) for _ in range(7)] + [np.zeros(len(w), dtype=bool)]
        has = np.flatnonzero(face >= 0)
        if has.size:
            res = self._refine(face[has], b1[has], b2[has], *(w[has, i] for i in range(6)), NP)
            for dst, src in zip(out, res):
                dst[has] = src
        again = np.flatnonzero((face >= 0) & ~out[7])
        if again.size and self._d["crease_any"]:
            res = self._crease_contact(*(np.ascontiguousarray(w[again, i]) for i in range(6)))
            for dst, src in zip(out, res):
                dst[again] = src
        return tuple(o.reshape(shape) for o in out)


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


_MESH_KEYS = {"shape", "mesh", "mesh_units", "crease_angle_deg", "skin_thickness", "mount"}


def mesh_fingertip_from_table(table: dict, source: str = "<fingertip>") -> MeshFingertip:
    """A :class:`MeshFingertip` from a parsed ``[fingertip]`` TOML table with ``mesh = "…"``.

    The mesh path is relative to the TOML file's folder. Keys: ``mesh``, ``mesh_units``
    (required: ``m``, ``cm``, ``mm``, ``um`` or ``in``), ``crease_angle_deg`` (default 40),
    ``skin_thickness`` (m), and a ``[fingertip.mount]`` table with ``translation`` (m)
    and ``rpy_deg`` (roll, pitch, yaw in degrees, fixed axes x-y-z) placing the mesh frame in
    the sensor frame: ``p_sensor = R p_mesh + translation``.
    """
    unknown = sorted(set(table) - _MESH_KEYS)
    if unknown:
        raise InputError(
            f"{source}: [fingertip] unknown key(s) {', '.join(unknown)} for a mesh; expected "
            f"{', '.join(sorted(_MESH_KEYS - {'shape'}))}"
        )
    mesh = table.get("mesh")
    if not isinstance(mesh, str) or not mesh:
        raise InputError(f"{source}: [fingertip] mesh must be a file name (STL, OBJ or PLY), got {mesh!r}")
    units = table.get("mesh_units")
    if units is None:
        raise InputError(
            f"{source}: [fingertip] mesh_units is required (mesh files carry no units); "
            f"expected one of {', '.join(MESH_UNITS)}"
        )
    if units not in MESH_UNITS:
        raise InputError(f"{source}: [fingertip] mesh_units = {units!r}; expected one of {', '.join(MESH_UNITS)}")

    def number(key: str, value, positive: bool = True) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(f"{source}: [fingertip] {key} = {value!r} is not a number")
        if positive and value <= 0:
            raise InputError(f"{source}: [fingertip] {key} = {value!r} must be positive")
        return float(value)

    crease = number("crease_angle_deg", table.get("crease_angle_deg", 40.0))
    thickness = table.get("skin_thickness")
    thickness = None if thickness is None else number("skin_thickness", thickness)
    # the mesh frame's pose in the sensor frame: the [fingertip.mount] of every shape
    rotation, translation = pose_from_table(table.get("mount", {}), f"{source}: [fingertip.mount]")
    rpy = rpy_of(rotation)
    base = Path(source).parent if source and not source.startswith("<") else Path(".")
    path = Path(mesh)
    if not path.is_absolute():
        path = base / path
    try:
        vertices, faces = load_mesh(path, units)
    except InputError as exc:
        raise InputError(f"{source}: [fingertip] mesh: {exc}") from None
    vertices = vertices @ rotation.as_matrix().T + np.asarray(translation)
    try:
        tip = MeshFingertip(
            vertices,
            faces,
            crease_angle_deg=crease,
            skin_thickness=thickness,
            source=str(path),
            mesh_units=units,
            translation=translation,
            rpy=rpy,  # type: ignore[arg-type]
        )
    except ValueError as exc:
        raise InputError(f"{source}: [fingertip] mesh {path}: {exc}") from None
    _check_origin(tip, f"{source}: [fingertip] mesh {path}")
    return tip


def load_mesh_fingertip(path: str | Path) -> MeshFingertip:
    """A mesh fingertip from a TOML fingertip file (see :func:`mesh_fingertip_from_table`)."""
    from softtip.tomlfile import read_toml

    table = fingertip_table(read_toml(path, "fingertip"), str(path))
    shape = table.get("shape", MeshFingertip.kind if MeshFingertip.implied_by in table else None)
    if shape != MeshFingertip.kind:
        raise InputError(f"{path}: not a mesh fingertip (shape = {shape!r})")
    return mesh_fingertip_from_table(table, str(path))


def _check_origin(tip: MeshFingertip, where: str) -> None:
    """The sensor origin must lie inside the skin or close to it (the tip is mounted on it)."""
    inside = tip.winding_number(np.zeros(3)) > 0.5
    if inside:
        return
    dist = float(tip.closest(np.zeros(3))[3])
    extent = tip._d["extent"]
    if dist > extent:
        raise InputError(
            f"{where}: the sensor origin is {dist * 1e3:.1f} mm outside the fingertip surface, more than the "
            f"fingertip's own size ({extent * 1e3:.1f} mm): the mesh is not placed on the sensor. Give "
            "[fingertip.mount] translation (m) and rpy_deg (mesh frame → sensor frame), and check mesh_units"
        )
