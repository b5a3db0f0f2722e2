"""Triangle-mesh fingertips: a CAD mesh of the skin surface as a :class:`~softtip.core.fingertip.Fingertip`.

The skin is the closed triangle mesh; its outward normal ``n(r)`` is the barycentric
interpolation of per-corner normals (angle-weighted averages of the faces around each vertex,
split at crease edges sharper than ``crease_angle_deg``), so ``n`` is continuous across
smooth edges. The soft-finger solution ``m = r × f + σ n(r)`` is found in two
steps:

1. **Cast.** The wrench's central axis (the points ``p`` with ``m = p × f + μ f``) is cast
   against the triangles, all hits, with Plücker-coordinate side tests (watertight: a line
   through a shared edge is never lost between two triangles). The triangles are grouped in
   spatially compact clusters with bounding spheres, the pre-filter. The first hit where the
   axis *enters* the skin going along ``+f`` (``f · n < 0``, the pushing side) is kept.
2. **Refine.** Newton's method on ``F(b₁, b₂, σ) = r(b) × f + σ n(b) − m`` in the
   barycentric coordinates of the current triangle, walking into the neighbouring triangle
   when a step leaves it. It is written once for numpy arrays (batch) and Python floats
   (stream), like the closed-form kernels (:mod:`softtip.core._xp`).

Meshes are loaded with `trimesh <https://trimesh.org>`_ (STL, OBJ, PLY), imported only when a
mesh fingertip is loaded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import NP, PY
from softtip.core.mounting import pose_from_table
from softtip.core.shape import Fingertip
from softtip.errors import InputError

__all__ = [
    "MeshFingertip",
    "MESH_UNITS",
    "capsule_mesh",
    "load_mesh",
    "load_mesh_fingertip",
    "mesh_fingertip_from_table",
    "rotation_from_rpy",
]

#: Length units accepted for ``mesh_units`` (metres per unit).
MESH_UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "in": 0.0254}

#: Plausible fingertip sizes (largest extent of the mesh, m); outside: a units mistake.
_SIZE_RANGE = (0.002, 0.5)

_LEAF = 32  # at most this many triangles per cluster of the cast's pre-filter
_BRANCH = 16  # at most this many clusters per super-cluster
_MAX_ITER = 30  # Newton steps
_MAX_CROSS = 16  # triangles one Newton step may cross (the next step goes on)
_STEP_TOL = 1e-7  # converged when a step moves the point less than this × the tip's size (the step is taken: the error left is of its square)
_RES_TOL = 1e-6  # and a solution is kept when |F| (before the last step) ≤ this × |f| × size
_CAST_BLOCK = 256
_ALL_FOUR = np.frombuffer(b"\x01\x01\x01\x01", dtype=np.uint32)[0]  # four True bytes as one word
_CREASE_TAN = 6.0  # a crease contact's normal is within atan(6) = 80.5° of −f
_CREASE_COS = 1.0 / math.sqrt(1.0 + _CREASE_TAN**2)
_CREASE_EDGE_TOL = 1e-9  # the crease edge's ends are searched this far (in t) beyond the edge
_CREASE_WEDGE_TOL = 1e-6  # a normal this close (rad) outside a crease's wedge or cone counts as in it (a root
# where the moment only touches the normals' plane is found to the square root of the rounding)
_CREASE_RES_TOL = 1e-9  # a crease edge's moment may leave the normals' plane by this × |f| × size
_CREASE_SPLIT = 16  # intervals bracketing a crease edge's roots
_CREASE_BISECT = 60  # interval halvings: to the last bit of t
_CUBIC_FROM_VALUES = np.linalg.inv(np.vander([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0], 4, increasing=True)).tolist()
_WALK = 8  # faces the streaming cast walks from the previous sample's face
_NEAR_K = 32  # nearest triangle centroids tried first by the closest-point query
_SIDE_TOL = 1e-13  # Plücker side products within this × |f| × size² of zero count as on the edge


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


# -- mesh preparation --------------------------------------------------------------------------


def _edge_neighbours(faces: NDArray[np.int64]) -> tuple[NDArray, NDArray, NDArray]:
    """For each face and local edge ``k`` (opposite local vertex ``k``): the neighbouring face,
    and the local indices there of the edge's two vertices (``i = k+1``, ``j = k+2`` here).

    Raises ValueError when an edge is not shared by exactly two faces with opposite
    orientation (open or non-manifold mesh, inconsistent winding).
    """
    nf = len(faces)
    i_loc = np.array([1, 2, 0])
    j_loc = np.array([2, 0, 1])
    a = faces[:, i_loc]  # (F, 3): first vertex of edge k
    b = faces[:, j_loc]
    # a directed edge a→b in one face must meet b→a in exactly one other face
    key = a.astype(np.int64) * (faces.max() + 1) + b
    rkey = b.astype(np.int64) * (faces.max() + 1) + a
    flat, rflat = key.ravel(), rkey.ravel()
    order = np.argsort(flat, kind="stable")
    sorted_keys = flat[order]
    if np.any(sorted_keys[1:] == sorted_keys[:-1]):
        raise ValueError("some edges are used twice in the same direction (inconsistent winding or non-manifold)")
    pos = np.searchsorted(sorted_keys, rflat)
    pos = np.minimum(pos, len(sorted_keys) - 1)
    found = sorted_keys[pos] == rflat
    if not found.all():
        raise ValueError(f"{int((~found).sum())} edges have no opposite neighbour (the mesh is open)")
    other = order[pos]  # flat index (face * 3 + k') of the opposite directed edge
    nb_face = (other // 3).reshape(nf, 3)
    nb_k = (other % 3).reshape(nf, 3)
    # in the neighbour, edge k' runs from local (k'+1) to (k'+2) and is b→a
    li = j_loc[nb_k]  # local index of a (our vertex i) in the neighbour
    lj = i_loc[nb_k]  # local index of b (our vertex j)
    return nb_face, li, lj


def _corner_normals(vertices: NDArray, faces: NDArray, face_normals: NDArray, crease_cos: float) -> NDArray:
    """Per-corner unit normals ``(F, 3, 3)``: angle-weighted face normals around the corner's
    vertex, over the faces within the crease angle of the corner's own face."""
    tri = vertices[faces]  # (F, 3, 3)
    angles = np.empty(faces.shape)
    for k in range(3):
        u = tri[:, (k + 1) % 3] - tri[:, k]
        w = tri[:, (k + 2) % 3] - tri[:, k]
        cosang = np.sum(u * w, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        angles[:, k] = np.arccos(np.clip(cosang, -1.0, 1.0))
    corner_vertex = faces.ravel()
    corner_face = np.repeat(np.arange(len(faces)), 3)
    order = np.argsort(corner_vertex, kind="stable")
    cv = corner_vertex[order]
    starts = np.flatnonzero(np.r_[True, cv[1:] != cv[:-1]])
    counts = np.diff(np.r_[starts, len(cv)])
    # all ordered pairs (c1, c2) of corners at the same vertex
    group_start = np.repeat(starts, counts * counts)
    group_size = np.repeat(counts, counts * counts)
    within = np.arange(len(group_start)) - np.repeat(np.cumsum(counts * counts) - counts * counts, counts * counts)
    c1 = order[group_start + within // group_size]
    c2 = order[group_start + within % group_size]
    f1, f2 = corner_face[c1], corner_face[c2]
    same_group = np.sum(face_normals[f1] * face_normals[f2], axis=1) >= crease_cos
    weight = np.where(same_group, angles.ravel()[c2], 0.0)
    acc = np.zeros((len(corner_vertex), 3))
    np.add.at(acc, c1, weight[:, None] * face_normals[f2])
    acc /= np.linalg.norm(acc, axis=1, keepdims=True)
    return acc.reshape(len(faces), 3, 3)


def _clusters(centroids: NDArray, leaf: int) -> list[NDArray]:
    """Split the face indices into spatially compact groups of at most ``leaf`` faces
    (median cuts along the longest extent)."""
    out, stack = [], [np.arange(len(centroids))]
    while stack:
        idx = stack.pop()
        if len(idx) <= leaf:
            out.append(idx)
            continue
        c = centroids[idx]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        order = np.argsort(c[:, axis], kind="stable")
        half = len(idx) // 2
        stack.append(idx[order[:half]])
        stack.append(idx[order[half:]])
    return out


def _near_classes(centroids: NDArray, corners: NDArray) -> list:
    """KD-trees of face centroids in two size classes, for :meth:`MeshFingertip._near`."""
    from scipy.spatial import cKDTree  # imported here: `import softtip` stays light
    reach = np.max(np.linalg.norm(corners - centroids, axis=2), axis=0) * (1 + 1e-9)
    small = reach <= 1.5 * np.median(reach)
    out = []
    for sel in (small, ~small):
        members = np.flatnonzero(sel)
        if members.size == 0:
            continue
        k = _NEAR_K if sel is small else _NEAR_K // 4
        out.append((cKDTree(centroids[members]), members, float(reach[members].max()), min(k, members.size)))
    return out


def _exposure(vertices: NDArray, faces: NDArray, face_n: NDArray, v0: NDArray, centroids: NDArray,
              extent: float) -> list[tuple[float, float]]:
    """Per face ``(h, e)``: how far the mesh rises in front of the face's plane (m; 0 for a
    face on the convex hull, within ``1e-6 × extent``, above the rounding of a mesh stored in
    single precision, as STL is), and a lower bound on the distance from any point of the
    face to any point of the mesh in front of its plane (m).

    A line entering the skin through the face along ``f`` meets nothing before it when
    ``h < e c`` with ``c = −n·f/|f|``: a point of the mesh on the line before the face would
    be within ``h / c`` of it.
    """
    from scipy import sparse
    from scipy.spatial import ConvexHull, cKDTree  # imported here: `import softtip` stays light

    tol = 1e-6 * extent
    nf, nv = len(face_n), len(vertices)
    hull = ConvexHull(vertices)
    offset = np.sum(face_n * v0, axis=1)
    # a face whose plane passes through a hull vertex that no hull neighbour rises above is
    # on the hull (a linear function's local maximum over a convex polytope is its maximum)
    s = hull.simplices
    e = np.concatenate((s[:, [0, 1]], s[:, [1, 2]], s[:, [2, 0]]))
    adj = sparse.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(nv, nv))
    adj = (adj + adj.T).tocsr()
    on_hull = np.zeros(nv, dtype=bool)
    on_hull[hull.vertices] = True
    rise = np.full(nf, np.inf)
    for k in range(3):
        vk = faces[:, k]
        cand = np.flatnonzero(on_hull[vk] & ~(rise <= tol))
        count = np.diff(adj.indptr)[vk[cand]]
        rows = np.repeat(np.arange(len(cand)), count)
        pos = np.repeat(adj.indptr[vk[cand]] - np.cumsum(count) + count, count) + np.arange(count.sum())
        h = np.einsum("ij,ij->i", vertices[adj.indices[pos]] - vertices[vk[cand[rows]]], face_n[cand[rows]])
        worst = np.full(len(cand), -np.inf)
        np.maximum.at(worst, rows, h)
        rise[cand[worst <= tol]] = 0.0
    # the others: the support function over the hull's vertices
    rest = np.flatnonzero(rise > tol)
    hv = np.ascontiguousarray(vertices[hull.vertices].T)
    for start in range(0, len(rest), 512):
        blk = rest[start : start + 512]
        rise[blk] = (face_n[blk] @ hv).max(axis=1) - offset[blk]
    tri = vertices[faces]
    edge = max(float(np.max(np.linalg.norm(tri[:, k] - tri[:, (k + 1) % 3], axis=1))) for k in range(3))
    circum = np.max(np.linalg.norm(tri - centroids[:, None, :], axis=2), axis=1)
    # clearance: the nearest vertex in front of the plane among the 64 nearest of the centroid
    # (none: farther than the 64th, a lower bound)
    clear = np.full(nf, np.inf)
    inner = np.flatnonzero(rise > tol)
    if inner.size:
        k = min(64, nv)
        dist, near = cKDTree(vertices).query(centroids[inner], k=k)
        dist, near = dist.reshape(len(inner), k), near.reshape(len(inner), k)
        height = np.einsum("ikj,ij->ik", vertices[near], face_n[inner]) - offset[inner][:, None]
        first = np.where(height > tol, dist, np.inf).min(axis=1)
        clear[inner] = np.minimum(first, dist[:, -1]) - edge - circum[inner]
    rise = np.where(rise > tol, rise, 0.0)
    return [(h, e) for h, e in zip(rise.tolist(), np.maximum(clear, 0.0).tolist())]


def _creases(vertices, faces, face_n, cn, nb_face, li, lj, extent) -> tuple[dict, dict]:
    """The sharp features for :meth:`MeshFingertip._crease_contact`: convex crease edges (the
    corner normals of the two faces differ along them) and convex corners (three or more
    distinct corner normals), as columns of float arrays."""
    nf = len(faces)
    rows = []
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        u, ui, uj = nb_face[:, k], li[:, k], lj[:, k]
        na_a, na_b = cn[:, i], cn[:, j]
        nb_a, nb_b = cn[u, ui], cn[u, uj]
        differ = (np.sum(na_a * nb_a, axis=1) < 1.0 - 1e-12) | (np.sum(na_b * nb_b, axis=1) < 1.0 - 1e-12)
        a, b = vertices[faces[:, i]], vertices[faces[:, j]]
        far = vertices[faces[u, 3 - ui - uj]]
        convex = np.sum(face_n * (far - a), axis=1) < -1e-9 * extent
        t = np.flatnonzero(differ & (np.arange(nf) < u))
        rows.append((t, a[t], b[t], na_a[t], na_b[t], nb_a[t], nb_b[t], convex[t], faces[t, i], faces[t, j]))
    t, a, b, na_a, na_b, nb_a, nb_b, convex, va, vb = (np.concatenate(x) for x in zip(*rows))
    keep = convex
    mid = 0.5 * (a + b)
    edges = {"ax": a[:, 0], "ay": a[:, 1], "az": a[:, 2]}
    u = b - a
    edges.update(ux=u[:, 0], uy=u[:, 1], uz=u[:, 2], mx=mid[:, 0], my=mid[:, 1], mz=mid[:, 2])
    edges["half"] = 0.5 * np.linalg.norm(u, axis=1)
    for name, p0, p1 in (("A", na_a, na_b), ("B", nb_a, nb_b)):
        for c, axis in enumerate("xyz"):
            edges[f"{name}0{axis}"] = p0[:, c]
            edges[f"{name}1{axis}"] = p1[:, c] - p0[:, c]
    edges = {key: np.ascontiguousarray(val[keep]) for key, val in edges.items()}
    # corners: the ends of crease edges with three or more distinct normals, all edges convex
    concave_ends = set(va[~convex].tolist()) | set(vb[~convex].tolist())
    ends = sorted((set(va.tolist()) | set(vb.tolist())) - concave_ends)
    corner_vertex = faces.ravel()
    order = np.argsort(corner_vertex, kind="stable")
    starts = np.searchsorted(corner_vertex[order], ends)
    stops = np.searchsorted(corner_vertex[order], ends, side="right")
    flat_cn = cn.reshape(-1, 3)
    cones = []
    for vtx, lo, hi in zip(ends, starts, stops):  # a few corners per mesh
        normals: list[NDArray] = []
        for c in flat_cn[order[lo:hi]]:
            if all(float(c @ e) < 1.0 - 1e-9 for e in normals):
                normals.append(c)
        if not 3 <= len(normals) <= 8:
            continue
        for x in range(len(normals)):
            for y in range(x + 1, len(normals)):
                for z in range(y + 1, len(normals)):
                    c0, c1, c2 = normals[x], normals[y], normals[z]
                    det = float(c0 @ np.cross(c1, c2))
                    if abs(det) < 1e-9:
                        continue
                    sgn = 1.0 if det > 0 else -1.0
                    planes = [sgn * np.cross(p, q) for p, q in ((c1, c2), (c2, c0), (c0, c1))]
                    cones.append((vertices[vtx], *(p / np.linalg.norm(p) for p in planes)))
    corners: dict = {}
    arr = [np.array([cone[i] for cone in cones]).reshape(-1, 3) for i in range(4)]
    for c, axis in enumerate("xyz"):
        corners[f"v{axis}"] = np.ascontiguousarray(arr[0][:, c])
        for k in range(3):
            corners[f"p{k}{axis}"] = np.ascontiguousarray(arr[k + 1][:, c])
    return edges, corners


def _closest_on_triangles(p: NDArray, v0: NDArray, v1: NDArray, v2: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Closest points of triangles to points (pairwise, shape (P, 3) each).

    Returns the squared distance (P,), and the barycentric coordinates ``b1, b2`` (P,) of
    the closest point. Works in cache-sized blocks on per-axis components.
    """
    n = len(p)
    dist, b1, b2 = np.empty(n), np.empty(n), np.empty(n)
    for start in range(0, n, 8192):
        sl = slice(start, start + 8192)
        dist[sl], b1[sl], b2[sl] = _closest_block(*p[sl].T, *v0[sl].T, *v1[sl].T, *v2[sl].T)
    return dist, b1, b2


def _closest_block(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    e1x, e1y, e1z = bx - ax, by - ay, bz - az
    e2x, e2y, e2z = cx - ax, cy - ay, cz - az
    dx, dy, dz = px - ax, py - ay, pz - az
    a11 = e1x * e1x + e1y * e1y + e1z * e1z
    a12 = e1x * e2x + e1y * e2y + e1z * e2z
    a22 = e2x * e2x + e2y * e2y + e2z * e2z
    r1 = e1x * dx + e1y * dy + e1z * dz
    r2 = e2x * dx + e2y * dy + e2z * dz
    det = a11 * a22 - a12 * a12
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (a22 * r1 - a12 * r2) / det
        v = (a11 * r2 - a12 * r1) / det
    inside = (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (det > 0.0)
    bu = np.where(inside, u, 0.0)
    bv = np.where(inside, v, 0.0)
    qx, qy, qz = dx - bu * e1x - bv * e2x, dy - bu * e1y - bv * e2y, dz - bu * e1z - bv * e2z
    best = np.where(inside, qx * qx + qy * qy + qz * qz, np.inf)
    # the three edges: v0→v1 (b = (s, 0)), v0→v2 (b = (0, s)), v1→v2 (b = (1 − s, s))
    e3x, e3y, e3z = cx - bx, cy - by, cz - bz
    for ex, ey, ez, ox, oy, oz, kind in (
        (e1x, e1y, e1z, dx, dy, dz, 0),
        (e2x, e2y, e2z, dx, dy, dz, 1),
        (e3x, e3y, e3z, px - bx, py - by, pz - bz, 2),
    ):
        ee = ex * ex + ey * ey + ez * ez
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip((ox * ex + oy * ey + oz * ez) / ee, 0.0, 1.0)
        t = np.where(ee > 0.0, t, 0.0)
        qx, qy, qz = ox - t * ex, oy - t * ey, oz - t * ez
        dd = qx * qx + qy * qy + qz * qz
        closer = dd < best
        best = np.where(closer, dd, best)
        if kind == 0:
            bu, bv = np.where(closer, t, bu), np.where(closer, 0.0, bv)
        elif kind == 1:
            bu, bv = np.where(closer, 0.0, bu), np.where(closer, t, bv)
        else:
            bu, bv = np.where(closer, 1.0 - t, bu), np.where(closer, t, bv)
    return best, bu, bv


@dataclass(frozen=True, eq=False)
class MeshFingertip(Fingertip):
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
        lo, hi = _SIZE_RANGE
        if extent > hi:
            raise ValueError(
                f"the mesh is {extent:.4g} m across, {extent / 0.03:.0f}× a fingertip's size: "
                "wrong mesh_units (a mesh drawn in mm read as m is 1000× too large)?"
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
    def closest(self, points: ArrayLike) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """The closest point of the mesh to each point.

        Parameters
        ----------
        points : array-like, shape (..., 3)
            Points, m.

        Returns
        -------
        face : array of int, shape (...,)
            The triangle of the closest point.
        b1, b2 : array, shape (...,)
            Its barycentric coordinates on that triangle (weights of the 2nd and 3rd vertex).
        distance : array, shape (...,)
            Unsigned distance, m.
        """
        p = np.asarray(points, dtype=float)
        shape = p.shape[:-1]
        p = p.reshape(-1, 3)
        n = len(p)
        face = np.zeros(n, dtype=np.int64)
        b1 = np.zeros(n)
        b2 = np.zeros(n)
        dist = np.full(n, np.nan)
        d = self._d
        ok = np.all(np.isfinite(p), axis=1)
        # fast path: the triangles with the K nearest centroids; the answer is certain when no
        # other triangle can come closer (its centroid is farther than the K-th by more than
        # any triangle's reach)
        k = min(_NEAR_K, len(self.faces))
        safe = np.where(ok[:, None], p, 0.0)
        best = np.empty(n)
        sure = np.zeros(n, dtype=bool)
        for start in range(0, n, 1024):
            blk = slice(start, start + 1024)
            nb = len(safe[blk])
            ik, bound = self._near(safe[blk])
            k = ik.shape[1]
            flat = ik.ravel()
            t9 = d["tri9"][flat]
            dd, bb1, bb2 = _closest_on_triangles(np.repeat(safe[blk], k, axis=0), t9[:, 0:3], t9[:, 3:6], t9[:, 6:9])
            dd, bb1, bb2 = dd.reshape(nb, k), bb1.reshape(nb, k), bb2.reshape(nb, k)
            j = np.argmin(dd, axis=1)
            rows = np.arange(nb)
            bst = dd[rows, j]
            sb = ok[blk] & (np.sqrt(bst) <= bound)
            best[blk], sure[blk] = bst, sb
            out = start + np.flatnonzero(sb)
            face[out], b1[out], b2[out], dist[out] = ik[rows, j][sb], bb1[rows, j][sb], bb2[rows, j][sb], np.sqrt(bst[sb])
        todo = np.flatnonzero(ok & ~sure)
        for start in range(0, len(todo), 256):
            pts = todo[start : start + 256]
            pb = p[pts]
            # upper bound: the nearest of the K triangles; then every cluster that can hold a
            # closer point
            upper = np.sqrt(best[pts])
            dc = np.sqrt(np.maximum(d["cl_centre2"][None] - 2.0 * (pb @ d["cl_centre"].T) + np.sum(pb * pb, axis=1)[:, None], 0.0))
            ray, cl = np.nonzero((dc - d["cl_radius"][None]) <= upper[:, None] * (1 + 1e-9) + 1e-12 * d["extent"])
            tris = d["members"][cl].ravel()
            who = np.repeat(ray, _LEAF)
            real = tris < len(self.faces)
            tris, who = tris[real], who[real]
            dd, bb1, bb2 = _closest_on_triangles(pb[who], d["v0"][tris], d["v1"][tris], d["v2"][tris])
            order = np.lexsort((tris, dd, who))
            first = np.r_[True, who[order][1:] != who[order][:-1]]
            sel = order[first]
            rows = pts[who[sel]]
            face[rows], b1[rows], b2[rows], dist[rows] = tris[sel], bb1[sel], bb2[sel], np.sqrt(dd[sel])
        return face.reshape(shape), b1.reshape(shape), b2.reshape(shape), dist.reshape(shape)

    def _near(self, pts: NDArray) -> tuple[NDArray, NDArray]:
        """Candidate faces (n, K) for the closest point of each of ``pts`` (n, 3), and a
        distance below which the best of them is certainly the closest of the mesh.

        The faces are split by size (their reach: centroid to farthest vertex); each class
        gives its nearest centroids, and no face outside them is nearer than its K-th
        centroid less the class's largest reach.
        """
        ids, bound = [], np.full(len(pts), np.inf)
        for tree, members, reach, k in self._d["near_classes"]:
            if k >= len(members):  # a small class: all of its faces
                ids.append(np.broadcast_to(members, (len(pts), len(members))))
                continue
            dk, ik = tree.query(pts, k=k)
            ids.append(members[ik.reshape(len(pts), k)])
            bound = np.minimum(bound, dk.reshape(len(pts), k)[:, -1] - reach)
        return np.concatenate(ids, axis=1), bound

    def _closest_one(self, x: float, y: float, z: float):
        """:meth:`closest` for one point given as floats, as arrays of length 1 (fewest numpy calls)."""
        d = self._d
        if not math.isfinite(x + y + z):
            return self.closest(np.array([[x, y, z]]))
        ik, bound = self._near(np.array([[x, y, z]]))
        ik = ik[0]
        t9 = d["tri9"][ik].T
        dd, bb1, bb2 = _closest_block(x, y, z, *t9)
        j = int(np.argmin(dd))
        upper = math.sqrt(dd[j])
        if upper <= bound[0]:
            return ik[j : j + 1], bb1[j : j + 1], bb2[j : j + 1], np.sqrt(dd[j : j + 1])
        # every cluster that can hold a point nearer than the best so far (as in closest())
        pb = np.array([[x, y, z]])
        dc = np.sqrt(np.maximum(d["cl_centre2"] - 2.0 * (d["cl_centre"] @ pb[0]) + (x * x + y * y + z * z), 0.0))
        cl = np.flatnonzero((dc - d["cl_radius"]) <= upper * (1 + 1e-9) + 1e-12 * d["extent"])
        tris = d["members"][cl].ravel()
        tris = tris[tris < len(self.faces)]
        dd, bb1, bb2 = _closest_on_triangles(np.repeat(pb, len(tris), axis=0), *np.split(d["tri9"][tris], 3, axis=1))
        j = np.lexsort((tris, dd))[0]
        return tris[j : j + 1], bb1[j : j + 1], bb2[j : j + 1], np.sqrt(dd[j : j + 1])

    def _interp(self, face: NDArray, b1: NDArray, b2: NDArray) -> tuple[NDArray, NDArray]:
        g = self._d["geom"][face]
        b1, b2 = b1[..., None], b2[..., None]
        point = g[..., 0:3] + b1 * g[..., 3:6] + b2 * g[..., 6:9]
        nrm = g[..., 9:12] + b1 * g[..., 12:15] + b2 * g[..., 15:18]
        return point, nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)

    def _query(self, x, y, z, xp, what: str):
        """Shared body of the normal / projection / surface kernels; scalar calls are cached."""
        if xp is PY:
            key = (x, y, z)
            cached_key, value = self._d["last_" + what] if what != "surface" else (None, None)
            if cached_key == key:
                return value
            face, b1, b2, dist = self._closest_one(x, y, z)
            point, nrm = self._interp(face, b1, b2)
            if what == "surface":
                side = (x - point[0, 0]) * nrm[0, 0] + (y - point[0, 1]) * nrm[0, 1] + (z - point[0, 2]) * nrm[0, 2]
                return -float(dist[0]) if side < 0.0 else float(dist[0])
            out = nrm if what == "normal" else point
            value = (float(out[0, 0]), float(out[0, 1]), float(out[0, 2]))
            self._d["last_" + what] = (key, value)
            return value
        else:
            pts = np.stack(np.broadcast_arrays(x, y, z), axis=-1).astype(float)
        shape = pts.shape[:-1]
        flat = pts.reshape(-1, 3)
        # one query per distinct point (the batch estimator asks for the latched point per sample)
        uniq, inverse = np.unique(flat, axis=0, return_inverse=True)
        face, b1, b2, dist = self.closest(uniq)
        point, nrm = self._interp(face, b1, b2)
        if what == "normal":
            out = nrm[inverse.ravel()]
        elif what == "project":
            out = point[inverse.ravel()]
        else:
            side = np.sum((uniq - point) * nrm, axis=1)
            out = np.where(side < 0.0, -dist, dist)[inverse.ravel()]
        if xp is PY:
            value = float(out[0]) if what == "surface" else (float(out[0, 0]), float(out[0, 1]), float(out[0, 2]))
            if what != "surface":
                self._d["last_" + what] = (key, value)
            return value
        if what == "surface":
            return out.reshape(shape)
        out = out.reshape(*shape, 3)
        return out[..., 0], out[..., 1], out[..., 2]

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

    def to_toml(self) -> str:
        if self.source is None:
            raise ValueError("a mesh fingertip built from arrays has no file to name in TOML; save the mesh first")
        t = ", ".join(repr(float(x)) for x in self.translation)
        r = ", ".join(repr(math.degrees(float(x))) for x in self.rpy)
        lines = [
            "[fingertip]",
            'shape = "mesh"',
            f"mesh = {_toml_str(str(Path(self.source).resolve()))}",
            f'mesh_units = "{self.mesh_units}"',
            f"crease_angle_deg = {float(self.crease_angle_deg)!r}",
        ]
        if self.skin_thickness is not None:
            lines.append(f"skin_thickness = {self.skin_thickness!r}")
        lines += ["", "[fingertip.mount]", f"translation = [{t}]", f"rpy_deg = [{r}]"]
        return "\n".join(lines) + "\n"

    # -- contact location -------------------------------------------------------------------------
    def _cast(self, f: NDArray, m: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """First entering hit of each wrench axis: face (−1 for none), b1, b2; shapes (N,)."""
        n = len(f)
        face = np.full(n, -1, dtype=np.int64)
        b1 = np.zeros(n)
        b2 = np.zeros(n)
        d = self._d
        nf = len(self.faces)
        cc, cc2, rho2 = d["sup_centre"], d["sup_centre2"], d["sup_radius2"]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # term by term, in the order of _cast_one (batch and stream agree to the last bit)
            fx, fy, fz, mx, my, mz = f[:, 0], f[:, 1], f[:, 2], m[:, 0], m[:, 1], m[:, 2]
            f2 = fx * fx + fy * fy + fz * fz
            inv = 1.0 / np.sqrt(f2)
            fh = np.column_stack((fx * inv, fy * inv, fz * inv))
            mu = (fx * mx + fy * my + fz * mz) / f2
            line = np.column_stack((fx, fy, fz, mx - mu * fx, my - mu * fy, mz - mu * fz))  # Plücker (d, p × d)
            base = np.column_stack(((fy * mz - fz * my) / f2, (fz * mx - fx * mz) / f2, (fx * my - fy * mx) / f2))
            bb = np.einsum("ij,ij->i", base, base)
            bf = base[:, 0] * fh[:, 0] + base[:, 1] * fh[:, 1] + base[:, 2] * fh[:, 2]
            for start in range(0, n, _CAST_BLOCK):
                sl = slice(start, start + _CAST_BLOCK)
                # squared distance of the super-cluster centres from the axis, (rays, supers)
                along = fh[sl] @ cc.T - bf[sl, None]
                dist2 = cc2[None] - 2.0 * (base[sl] @ cc.T) + bb[sl, None] - along * along
                ray, sup = np.nonzero(dist2 <= rho2)
                if ray.size == 0:
                    continue
                # then their clusters, (pairs, branch)
                cls = d["sup_members"][sup]
                q = d["cl_centre_p"][cls] - base[sl][ray][:, None, :]
                along = np.einsum("pbj,pj->pb", q, fh[sl][ray])
                dist2 = np.einsum("pbj,pbj->pb", q, q) - along * along
                pi, bi = np.nonzero(dist2 <= d["cl_radius2_p"][cls])
                if pi.size == 0:
                    continue
                ray, cl = ray[pi], cls[pi, bi]
                tris = d["members"][cl]  # (pairs, leaf), padded with the dummy face nf
                s = np.einsum("pqkj,pj->pqk", d["plucker"][tris], line[sl][ray])
                s0, s1, s2 = s[..., 0], s[..., 1], s[..., 2]
                total = s0 + s1 + s2
                # a rounding-size margin: a line exactly through a vertex is not lost in its fan
                tol = (_SIDE_TOL * d["radius"] ** 2) * np.sqrt(f2[sl][ray])[:, None]
                hit = (np.maximum(np.maximum(s0, s1), s2) <= tol) & (total < 0.0)
                pi, qi = np.nonzero(hit)
                if pi.size == 0:
                    continue
                who, tris = ray[pi], tris[pi, qi]
                s0, s1, s2 = _sides(d["plucker"][tris], line[sl][who].T)
                total = s0 + s1 + s2
                enters = total < 0.0  # not grazing the face (in its plane), as in _first_hit
                if not enters.all():
                    who, tris, s0, s1, s2, total = (x[enters] for x in (who, tris, s0, s1, s2, total))
                    if who.size == 0:
                        continue
                w1, w2 = s1 / total, s2 / total
                g = d["geom"][tris].T
                bw, hw = base[sl][who].T, fh[sl][who].T
                t = (
                    (g[0] + w1 * g[3] + w2 * g[6] - bw[0]) * hw[0]
                    + (g[1] + w1 * g[4] + w2 * g[7] - bw[1]) * hw[1]
                    + (g[2] + w1 * g[5] + w2 * g[8] - bw[2]) * hw[2]
                )
                if len(t) == 1:
                    sel = np.zeros(1, dtype=np.int64)
                else:
                    order = np.lexsort((tris, t, who))
                    first = np.r_[True, who[order][1:] != who[order][:-1]]
                    sel = order[first]
                rows = start + who[sel]
                face[rows], b1[rows], b2[rows] = tris[sel], w1[sel], w2[sel]
        del nf
        return face, b1, b2

    def _cast_one(self, fx: float, fy: float, fz: float, mx: float, my: float, mz: float) -> tuple[int, float, float]:
        """:meth:`_cast` for one wrench given as floats (the streaming path: fewest numpy calls).

        Contacts move continuously, so the cast first walks over the faces from the previous
        sample's hit toward the axis; where it arrives is kept when it is certainly the first
        entering hit of the whole mesh (see :meth:`_unoccluded`): the same face and numbers as
        the full cast. Otherwise (a walk of more than a few faces, an axis through an edge or
        a vertex, a face that something may hide) the full cast runs.
        """
        d = self._d
        f2 = fx * fx + fy * fy + fz * fz
        if not (f2 > 0.0 and math.isfinite(f2 + mx + my + mz)):
            return -1, 0.0, 0.0
        inv = 1.0 / math.sqrt(f2)
        hx, hy, hz = fx * inv, fy * inv, fz * inv
        mu = (fx * mx + fy * my + fz * mz) / f2
        line = np.array((fx, fy, fz, mx - mu * fx, my - mu * fy, mz - mu * fz))
        bx, by, bz = (fy * mz - fz * my) / f2, (fz * mx - fx * mz) / f2, (fx * my - fy * mx) / f2
        tol = (_SIDE_TOL * d["radius"] ** 2) * math.sqrt(f2)
        axis = (line, bx, by, bz, hx, hy, hz, tol)
        face = d["hint"]
        if face >= 0:
            cx, cy, cz = d["centroids_py"][face]
            qx, qy, qz = cx - bx, cy - by, cz - bz
            along = qx * hx + qy * hy + qz * hz
            if qx * qx + qy * qy + qz * qz - along * along > d["walk_reach2"]:
                face = -1  # the axis has jumped: no walk
        if face >= 0:
            # walk from the previous sample's face toward the axis, across the edge the axis
            # passes beyond; a face the axis enters clear of its edges, with nothing before it,
            # is the first entering hit of the whole mesh (no other face is hit there, none before)
            lf = (fx, fy, fz, mx - mu * fx, my - mu * fy, mz - mu * fz)
            plucker, nb = d["plucker_py"], d["nb_py"]
            for _ in range(_WALK):
                s0, s1, s2 = _sides(plucker[face], lf)
                if s0 < -tol and s1 < -tol and s2 < -tol:
                    if self._unoccluded(face, hx, hy, hz):
                        total = s0 + s1 + s2
                        d["hint"] = face
                        return face, s1 / total, s2 / total
                    break
                k = 0 if s0 >= s1 and s0 >= s2 else 1 if s1 >= s2 else 2
                if (s0, s1, s2)[k] <= 0.0:
                    break  # on an edge or a vertex: the full cast decides
                face = nb[face][k]
        # the clusters whose bounding sphere the axis meets: |c − b|² − ((c − b)·h)² ≤ ρ², a
        # quadratic form in the centre c (b ⟂ h), one product with its monomials
        quad = np.array((
            1.0 - hx * hx, 1.0 - hy * hy, 1.0 - hz * hz, -2.0 * hx * hy, -2.0 * hx * hz, -2.0 * hy * hz,
            -2.0 * bx, -2.0 * by, -2.0 * bz, bx * bx + by * by + bz * bz, 1.0,
        ))  # fmt: skip
        cl = np.flatnonzero(d["cl_quad"] @ quad <= 0.0)
        tris = d["members"][cl].ravel()
        # per face: the three side products and their sum; a hit (entering) has the three
        # ≤ 0 (within the rounding margin) and the sum < 0, tested as one 4-byte word per face
        s = (d["cl_plucker"][cl].reshape(-1, 6) @ line).reshape(-1, 4)
        hit = np.flatnonzero((s < np.array((tol, tol, tol, 0.0))).view(np.uint32).ravel() == _ALL_FOUR)
        face, w1, w2, _ = self._first_hit(tris, hit, *axis)
        d["hint"] = face
        return face, w1, w2

    def _unoccluded(self, face: int, hx: float, hy: float, hz: float) -> bool:
        """True when a line along the unit vector ``h`` entering through ``face`` certainly
        meets no other part of the mesh before it (see :func:`_exposure`)."""
        rise, clear = self._d["exposure"][face]
        if rise == 0.0:
            return True
        g = self._d["face_n_py"][face]
        return rise < clear * -(g[0] * hx + g[1] * hy + g[2] * hz)

    def _first_hit(self, tris: NDArray, hit: NDArray, line: NDArray, bx: float, by: float, bz: float,
                   hx: float, hy: float, hz: float, tol: float) -> tuple[int, float, float, int]:
        """The first entering hit of the axis among the faces ``tris[hit]`` (the faces it
        enters): face (−1 for none), its barycentric coordinates, and its position in ``tris``."""
        d = self._d
        best = (math.inf, -1, 0.0, 0.0, -1)
        lf = line.tolist()
        for j in hit.tolist():  # one hit on a convex patch, a few where the axis crosses the skin again
            face = int(tris[j])
            s0, s1, s2 = _sides(d["plucker"][face].tolist(), lf)
            total = s0 + s1 + s2
            if not total < 0.0:  # the axis grazes the face (in its plane): no entry
                continue
            w1, w2 = s1 / total, s2 / total
            g = d["geom_py"][face]
            t = (
                (g[0] + w1 * g[3] + w2 * g[6] - bx) * hx
                + (g[1] + w1 * g[4] + w2 * g[7] - by) * hy
                + (g[2] + w1 * g[5] + w2 * g[8] - bz) * hz
            )
            if (t, face) < best[:2]:
                best = (t, face, w1, w2, j)
        return best[1], best[2], best[3], best[4]

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

    def _crease_contact(self, fx, fy, fz, mx, my, mz):
        """Soft-finger contact on the sharp features: crease edges and corners (arrays (n,)).

        Where the skin has a crease (faces meeting at more than ``crease_angle_deg``) the
        normal is not continuous: every normal between the two faces' (on an edge), or in the
        cone of the corner normals (at a corner), is a normal of the surface there. Newton on
        the smooth patches cannot reach these contacts; they are solved here directly. On a
        crease edge ``r(t)`` the moment ``q = m − r × f = σ n`` must lie in the plane of the
        two faces' normals (``g(t) = q · (n_A × n_B) = 0``, a cubic): its sign changes on 16
        intervals are bisected, and its smallest values where it touches zero without
        crossing are refined (on a straight edge ``q`` stays in that plane all along: the
        point along the edge is then barely determined by the wrench); at a corner ``v``,
        ``n = ±(m − v × f) / |m − v × f|`` must lie in the corner's normal cone. Of the
        solutions within 80° of the force (``f · n < 0``), the one with the least ``|σ|`` is
        kept. Elementwise operations only: one sample or many give the same numbers.

        Returns ``(rx, ry, rz, nx, ny, nz, sigma, valid)``, arrays (n,).
        """
        d = self._d
        n = len(fx)
        f2 = fx * fx + fy * fy + fz * fz
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            mf = fx * mx + fy * my + fz * mz
            mu = mf / f2
            inv = 1.0 / np.sqrt(f2)
            hx, hy, hz = fx * inv, fy * inv, fz * inv
            bx, by, bz = (fy * mz - fz * my) / f2, (fz * mx - fx * mz) / f2, (fx * my - fy * mx) / f2
            reach = np.abs(mu) * _CREASE_TAN + 1e-9 * d["radius"]  # r lies this close to the axis
            cands = []  # (sample, |σ|, point, normal, σ)

            def near(px, py, pz, extra):
                """(sample, feature) pairs whose point passes within reach (+ extra) of the axis."""
                qx, qy, qz = px[None] - bx[:, None], py[None] - by[:, None], pz[None] - bz[:, None]
                along = qx * hx[:, None] + qy * hy[:, None] + qz * hz[:, None]
                dist2 = qx * qx + qy * qy + qz * qz - along * along
                lim = reach[:, None] + extra[None]
                return np.nonzero(dist2 <= lim * lim)

            e = d["crease_edges"]
            if len(e["ax"]):
                si, ei = near(e["mx"], e["my"], e["mz"], e["half"])
                if si.size:
                    cands.append(self._crease_edge_roots(si, ei, fx, fy, fz, mx, my, mz))
            c = d["crease_corners"]
            if len(c["vx"]):
                si, ci = near(c["vx"], c["vy"], c["vz"], np.zeros(len(c["vx"])))
                if si.size:
                    cands.append(self._crease_corner_roots(si, ci, fx, fy, fz, mx, my, mz, mf))
        out = [np.full(n, np.nan) for _ in range(7)] + [np.zeros(n, dtype=bool)]
        if not cands:
            return tuple(out)
        # each candidate: sample, |σ|, rx, ry, rz, nx, ny, nz, σ
        cols = [np.concatenate([cd[k] for cd in cands]) for k in range(9)]
        who = cols[0].astype(np.int64)
        if who.size == 0:
            return tuple(out)
        order = np.lexsort((np.arange(len(who)), cols[1], who))
        first = order[np.r_[True, who[order][1:] != who[order][:-1]]]
        rows = who[first]
        for k in range(7):
            out[k][rows] = cols[k + 2][first]
        out[7][rows] = True
        return tuple(out)

    def _crease_edge_roots(self, si, ei, fx, fy, fz, mx, my, mz):
        """Contacts on crease edges for (sample, edge) pairs: see :meth:`_crease_contact`."""
        e = self._d["crease_edges"]
        Fx, Fy, Fz, Mx, My, Mz = fx[si], fy[si], fz[si], mx[si], my[si], mz[si]
        ax, ay, az, ux, uy, uz = (e[k][ei] for k in ("ax", "ay", "az", "ux", "uy", "uz"))
        # q(t) = m − (a + t u) × f = q0 + t q1; the faces' normals nA(t), nB(t), linear in t
        c = [
            Mx - (ay * Fz - az * Fy), My - (az * Fx - ax * Fz), Mz - (ax * Fy - ay * Fx),
            -(uy * Fz - uz * Fy), -(uz * Fx - ux * Fz), -(ux * Fy - uy * Fx),
        ] + [e[k][ei] for k in ("A0x", "A0y", "A0z", "A1x", "A1y", "A1z", "B0x", "B0y", "B0z", "B1x", "B1y", "B1z")]  # fmt: skip

        def parts(t, c):
            return [c[i] + t * c[i + 3] for i in (0, 1, 2, 6, 7, 8, 12, 13, 14)]

        def g(t, c):  # q · (nA × nB): zero where q lies in the plane of the two normals
            qx, qy, qz, nax, nay, naz, nbx, nby, nbz = parts(t, c)
            return qx * (nay * nbz - naz * nby) + qy * (naz * nbx - nax * nbz) + qz * (nax * nby - nay * nbx)

        # g is a cubic in t: its coefficients from four values, then Horner's rule (cheap in
        # the search below)
        y = [g(x, c) for x in (0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0)]
        cubic = [y[0] * v0 + y[1] * v1 + y[2] * v2 + y[3] * v3 for v0, v1, v2, v3 in _CUBIC_FROM_VALUES]

        def g(t, cb):  # noqa: F811 - the same function, from its coefficients
            return ((cb[3] * t + cb[2]) * t + cb[1]) * t + cb[0]

        c_full = c
        c = cubic
        k = _CREASE_SPLIT
        # the ends reach a little past the edge: a root at a vertex is not lost to rounding
        knots = [-_CREASE_EDGE_TOL] + [j / k for j in range(1, k)] + [1.0 + _CREASE_EDGE_TOL]
        grid = [g(x, c) for x in knots]
        pair, lo, hi, kind = [], [], [], []
        for j in range(k):
            # a sign change: a root to bisect
            sel = np.flatnonzero((grid[j] <= 0.0) != (grid[j + 1] <= 0.0))
            pair.append(sel)
            lo.append(np.full(len(sel), knots[j]))
            hi.append(np.full(len(sel), knots[j + 1]))
            kind.append(np.zeros(len(sel), dtype=bool))
            # a smallest |g| of the grid: where g touches zero without crossing (on a straight
            # edge, q stays in the normals' plane along it), to minimise
            if 0 < j:
                sel = np.flatnonzero((np.abs(grid[j]) <= np.abs(grid[j - 1])) & (np.abs(grid[j]) <= np.abs(grid[j + 1])))
                pair.append(sel)
                lo.append(np.full(len(sel), knots[j - 1]))
                hi.append(np.full(len(sel), knots[j + 1]))
                kind.append(np.ones(len(sel), dtype=bool))
        pair = np.concatenate(pair)
        lo, hi, touch = np.concatenate(lo), np.concatenate(hi), np.concatenate(kind)
        c = [x[pair] for x in c]
        glo = g(lo, c)
        for _ in range(_CREASE_BISECT):
            # bisection on g for crossings; for touches, the same interval halving on the sign
            # of the slope (a golden-free ternary step: compare g at two inner points)
            mid = 0.5 * (lo + hi)
            gm = g(mid, c)
            quarter = 0.25 * (hi - lo)
            slope_up = np.abs(g(mid + 0.5 * quarter, c)) >= np.abs(g(mid - 0.5 * quarter, c))
            left = np.where(touch, ~slope_up, (gm <= 0.0) == (glo <= 0.0))
            lo = np.where(left, np.where(touch, mid - quarter, mid), lo)
            hi = np.where(left, hi, np.where(touch, mid + quarter, mid))
            glo = g(lo, c)
        t = np.clip(0.5 * (lo + hi), 0.0, 1.0)
        qx, qy, qz, nax, nay, naz, nbx, nby, nbz = parts(t, [x[pair] for x in c_full])
        # q = α nA + β nB with α, β of one sign: q is σ n for a normal between the two faces'
        g11 = nax * nax + nay * nay + naz * naz
        g12 = nax * nbx + nay * nby + naz * nbz
        g22 = nbx * nbx + nby * nby + nbz * nbz
        r1 = qx * nax + qy * nay + qz * naz
        r2 = qx * nbx + qy * nby + qz * nbz
        alpha = g22 * r1 - g12 * r2  # × det > 0
        beta = g11 * r2 - g12 * r1
        sign = np.where(alpha + beta > 0.0, 1.0, -1.0)
        qn = np.sqrt(qx * qx + qy * qy + qz * qz)
        s_, e_ = si[pair], ei[pair]
        Fx, Fy, Fz = fx[s_], fy[s_], fz[s_]
        fn_ = np.sqrt(Fx * Fx + Fy * Fy + Fz * Fz)
        tiny = _CREASE_RES_TOL * fn_ * self._d["radius"]
        # no spin (q = 0): the force alone passes through the edge; the normal is then the
        # wedge's normal nearest −f
        pa, pb = -(Fx * nax + Fy * nay + Fz * naz), -(Fx * nbx + Fy * nby + Fz * nbz)
        wa = np.maximum(g22 * pa - g12 * pb, 0.0)
        wb = np.maximum(g11 * pb - g12 * pa, 0.0)
        wa = np.where(wa + wb > 0.0, wa, 1.0)
        px, py, pz = wa * nax + wb * nbx, wa * nay + wb * nby, wa * naz + wb * nbz
        pn = np.sqrt(px * px + py * py + pz * pz)
        still = qn <= tiny
        nx = np.where(still, px / pn, sign * qx / qn)
        ny = np.where(still, py / pn, sign * qy / qn)
        nz = np.where(still, pz / pn, sign * qz / qn)
        fdotn = Fx * nx + Fy * ny + Fz * nz
        both = np.abs(alpha) + np.abs(beta)
        same_side = (alpha * sign >= -_CREASE_WEDGE_TOL * both) & (beta * sign >= -_CREASE_WEDGE_TOL * both)
        cx, cy, cz = nay * nbz - naz * nby, naz * nbx - nax * nbz, nax * nby - nay * nbx
        cn_ = np.sqrt(cx * cx + cy * cy + cz * cz)
        off_plane = np.abs(qx * cx + qy * cy + qz * cz) / np.where(cn_ > 0.0, cn_, 1.0)
        same_side &= cn_ > _CREASE_EDGE_TOL * np.sqrt(g11 * g22)  # a wedge, not one normal
        ok = (same_side | still) & (fdotn < -_CREASE_COS * fn_) & (off_plane <= tiny)
        rx = e["ax"][e_] + t * e["ux"][e_]
        ry = e["ay"][e_] + t * e["uy"][e_]
        rz = e["az"][e_] + t * e["uz"][e_]
        sigma = np.where(still, qx * nx + qy * ny + qz * nz, sign * qn)
        return tuple(x[ok] for x in (s_.astype(float), qn, rx, ry, rz, nx, ny, nz, sigma))

    def _crease_corner_roots(self, si, ci, fx, fy, fz, mx, my, mz, mf):
        """Contacts at corners for (sample, corner cone) pairs: see :meth:`_crease_contact`."""
        c = self._d["crease_corners"]
        Fx, Fy, Fz, Mx, My, Mz = fx[si], fy[si], fz[si], mx[si], my[si], mz[si]
        vx, vy, vz = c["vx"][ci], c["vy"][ci], c["vz"][ci]
        qx, qy, qz = Mx - (vy * Fz - vz * Fy), My - (vz * Fx - vx * Fz), Mz - (vx * Fy - vy * Fx)
        qn = np.sqrt(qx * qx + qy * qy + qz * qz)
        sign = np.where(mf[si] > 0.0, -1.0, 1.0)  # f · n < 0: n · f = σ⁻¹ m · f
        nx, ny, nz = sign * qx / qn, sign * qy / qn, sign * qz / qn
        # n in the cone of three of the corner's normals: non-negative weights
        inside = np.ones(len(si), dtype=bool)
        for k in range(3):
            px, py, pz = (c[f"p{k}{j}"][ci] for j in "xyz")  # the cone's face normals, inward
            inside &= nx * px + ny * py + nz * pz >= -_CREASE_WEDGE_TOL  # on the cone's boundary too
        fn_ = np.sqrt(Fx * Fx + Fy * Fy + Fz * Fz)
        ok = inside & (qn > 0.0) & (mf[si] != 0.0) & (Fx * nx + Fy * ny + Fz * nz < -_CREASE_COS * fn_)
        sigma = sign * qn
        return tuple(x[ok] for x in (si.astype(float), qn, vx, vy, vz, nx, ny, nz, sigma))

    def _walk_one(self, face: int, b1: float, b2: float, db1: float, db2: float) -> tuple[int, float, float]:
        """Follow a barycentric step from ``(face, b1, b2)`` across edges into the neighbours
        (the rest of the step, as a displacement in space, projected onto each new triangle)."""
        d = self._d
        geom, nb, conv = d["geom_py"], d["nb_py"], d["conv_py"]
        for _ in range(_MAX_CROSS):
            k, t = _exit(b1, b2, db1, db2, PY)
            if t >= 1.0:
                return face, b1 + db1, b2 + db2
            e1 = b1 + t * db1
            e2 = b2 + t * db2
            e0 = 1.0 - e1 - e2
            bi, bj = (e1, e2) if k == 0 else (e2, e0) if k == 1 else (e0, e1)
            tot = bi + bj
            bi, bj = bi / tot, bj / tot
            g = geom[face]
            rest = 1.0 - t
            dx = rest * (db1 * g[3] + db2 * g[6])
            dy = rest * (db1 * g[4] + db2 * g[7])
            dz = rest * (db1 * g[5] + db2 * g[8])
            c1i, c1j, c2i, c2j = conv[face][k]
            face = nb[face][k]
            b1, b2 = c1i * bi + c1j * bj, c2i * bi + c2j * bj
            g = geom[face]
            p1 = g[3] * dx + g[4] * dy + g[5] * dz
            p2 = g[6] * dx + g[7] * dy + g[8] * dz
            db1 = g[18] * p1 - g[19] * p2
            db2 = g[20] * p2 - g[19] * p1
        return face, b1, b2

    def _walk(self, face: NDArray, b1: NDArray, b2: NDArray, db1: NDArray, db2: NDArray):
        """:meth:`_walk_one` over arrays (the same operations, masked)."""
        d = self._d
        geom, nb, conv = d["geom"], d["nb"], d["conv"]
        face, b1, b2, db1, db2 = face.copy(), b1.copy(), b2.copy(), db1.copy(), db2.copy()
        act = np.arange(len(face))
        for _ in range(_MAX_CROSS):
            k, t = _exit(b1[act], b2[act], db1[act], db2[act], NP)
            stay = t >= 1.0
            i = act[stay]
            b1[i] += db1[i]
            b2[i] += db2[i]
            act, k, t = act[~stay], k[~stay], t[~stay]
            if act.size == 0:
                break
            fa, ab1, ab2, ad1, ad2 = face[act], b1[act], b2[act], db1[act], db2[act]
            e1 = ab1 + t * ad1
            e2 = ab2 + t * ad2
            e0 = 1.0 - e1 - e2
            bi = np.where(k == 0, e1, np.where(k == 1, e2, e0))
            bj = np.where(k == 0, e2, np.where(k == 1, e0, e1))
            tot = bi + bj
            bi, bj = bi / tot, bj / tot
            g = geom[fa]
            rest = 1.0 - t
            dx = rest * (ad1 * g[:, 3] + ad2 * g[:, 6])
            dy = rest * (ad1 * g[:, 4] + ad2 * g[:, 7])
            dz = rest * (ad1 * g[:, 5] + ad2 * g[:, 8])
            c = conv[fa, k]
            nf = nb[fa, k]
            face[act] = nf
            b1[act] = c[:, 0] * bi + c[:, 1] * bj
            b2[act] = c[:, 2] * bi + c[:, 3] * bj
            g = geom[nf]
            p1 = g[:, 3] * dx + g[:, 4] * dy + g[:, 5] * dz
            p2 = g[:, 6] * dx + g[:, 7] * dy + g[:, 8] * dz
            db1[act] = g[:, 18] * p1 - g[:, 19] * p2
            db2[act] = g[:, 20] * p2 - g[:, 19] * p1
        return face, b1, b2

    def _refine(self, face, b1, b2, fx, fy, fz, mx, my, mz, xp):
        """Newton on ``r(b) × f + σ n(b) − m = 0`` walking over the triangles (arrays or floats)."""
        d = self._d
        size = d["radius"]
        if xp is PY:
            if face < 0:
                nan = math.nan
                return nan, nan, nan, nan, nan, nan, nan, False
            geom = d["geom_py"]
        else:
            geom = d["geom"]
        fnorm = xp.sqrt(fx * fx + fy * fy + fz * fz)
        step_tol = _STEP_TOL * size
        sig = None
        # state of the active samples; outputs written when a sample stops
        if xp is PY:
            state = [face, b1, b2]
        else:
            n = len(face)
            idx = np.arange(n)
            out = [np.full(n, np.nan) for _ in range(8)]
            act_f, act_b1, act_b2 = face.copy(), b1.copy(), b2.copy()
            af = [fx, fy, fz, mx, my, mz]
            act_sig = None
        for it in range(_MAX_ITER + 1):
            if xp is PY:
                t_face, cb1, cb2 = state
                g = geom[t_face]
                Fx, Fy, Fz, Mx, My, Mz = fx, fy, fz, mx, my, mz
            else:
                t_face, cb1, cb2 = act_f, act_b1, act_b2
                g = geom[t_face].T
                Fx, Fy, Fz, Mx, My, Mz = af
            (v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z, n0x, n0y, n0z, d1x, d1y, d1z, d2x, d2y, d2z) = g[:18]
            rx = v0x + cb1 * e1x + cb2 * e2x
            ry = v0y + cb1 * e1y + cb2 * e2y
            rz = v0z + cb1 * e1z + cb2 * e2z
            ux = n0x + cb1 * d1x + cb2 * d2x
            uy = n0y + cb1 * d1y + cb2 * d2y
            uz = n0z + cb1 * d1z + cb2 * d2z
            inv_len = 1.0 / xp.sqrt(ux * ux + uy * uy + uz * uz)
            nx, ny, nz = ux * inv_len, uy * inv_len, uz * inv_len
            if it == 0:  # least-squares spin at the start: σ = n · (m − r × f)
                s = nx * (Mx - (ry * Fz - rz * Fy)) + ny * (My - (rz * Fx - rx * Fz)) + nz * (Mz - (rx * Fy - ry * Fx))
            else:
                s = sig if xp is PY else act_sig
            # residual F = r × f + σ n − m
            Rx = ry * Fz - rz * Fy + s * nx - Mx
            Ry = rz * Fx - rx * Fz + s * ny - My
            Rz = rx * Fy - ry * Fx + s * nz - Mz
            # Jacobian columns: ∂/∂b1, ∂/∂b2, ∂/∂σ
            sl = s * inv_len
            p1 = nx * d1x + ny * d1y + nz * d1z
            p2 = nx * d2x + ny * d2y + nz * d2z
            ax = e1y * Fz - e1z * Fy + sl * (d1x - nx * p1)
            ay = e1z * Fx - e1x * Fz + sl * (d1y - ny * p1)
            az = e1x * Fy - e1y * Fx + sl * (d1z - nz * p1)
            bx = e2y * Fz - e2z * Fy + sl * (d2x - nx * p2)
            by = e2z * Fx - e2x * Fz + sl * (d2y - ny * p2)
            bz = e2x * Fy - e2y * Fx + sl * (d2z - nz * p2)
            # Cramer on [a b n] δ = −R
            bcx, bcy, bcz = by * nz - bz * ny, bz * nx - bx * nz, bx * ny - by * nx  # b × n
            det = ax * bcx + ay * bcy + az * bcz
            rcx, rcy, rcz = Ry * nz - Rz * ny, Rz * nx - Rx * nz, Rx * ny - Ry * nx  # R × n
            abx, aby, abz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx  # a × b
            db1 = xp.div(-(Rx * bcx + Ry * bcy + Rz * bcz), det)
            db2 = xp.div(-(ax * rcx + ay * rcy + az * rcz), det)
            dsig = xp.div(-(Rx * abx + Ry * aby + Rz * abz), det)
            # step length in space, and where the step leaves the triangle
            sx = db1 * e1x + db2 * e2x
            sy = db1 * e1y + db2 * e2y
            sz = db1 * e1z + db2 * e2z
            step = xp.sqrt(sx * sx + sy * sy + sz * sz)
            k, tmin = _exit(cb1, cb2, db1, db2, xp)
            # the step clipped to this triangle (used when it is the last one)
            tt = xp.where(tmin >= 1.0, 1.0, tmin)
            eb1, eb2 = cb1 + tt * db1, cb2 + tt * db2
            s_new = s + dsig
            done = xp.logical_or(step <= step_tol, it == _MAX_ITER)
            if xp is PY:
                done = done or not math.isfinite(step)
                if done:
                    # the last (tiny) step is taken: the point is exact to its square
                    rx = v0x + eb1 * e1x + eb2 * e2x
                    ry = v0y + eb1 * e1y + eb2 * e2y
                    rz = v0z + eb1 * e1z + eb2 * e2z
                    ux = n0x + eb1 * d1x + eb2 * d2x
                    uy = n0y + eb1 * d1y + eb2 * d2y
                    uz = n0z + eb1 * d1z + eb2 * d2z
                    inv_len = 1.0 / xp.sqrt(ux * ux + uy * uy + uz * uz)
                    nx, ny, nz = ux * inv_len, uy * inv_len, uz * inv_len
                    sf = s + tt * dsig
                    rnorm = math.sqrt(Rx * Rx + Ry * Ry + Rz * Rz)
                    fn_dot = Fx * nx + Fy * ny + Fz * nz
                    valid = rnorm <= _RES_TOL * fnorm * size and fn_dot < 0.0 and it < _MAX_ITER
                    if not valid:
                        nan = math.nan
                        return nan, nan, nan, nan, nan, nan, nan, False
                    return rx, ry, rz, nx, ny, nz, sf, True
            else:
                done = done | ~np.isfinite(step)
                if done.any():
                    q = done
                    fb1, fb2 = eb1[q], eb2[q]
                    frx = v0x[q] + fb1 * e1x[q] + fb2 * e2x[q]
                    fry = v0y[q] + fb1 * e1y[q] + fb2 * e2y[q]
                    frz = v0z[q] + fb1 * e1z[q] + fb2 * e2z[q]
                    ux = n0x[q] + fb1 * d1x[q] + fb2 * d2x[q]
                    uy = n0y[q] + fb1 * d1y[q] + fb2 * d2y[q]
                    uz = n0z[q] + fb1 * d1z[q] + fb2 * d2z[q]
                    inv_len = 1.0 / np.sqrt(ux * ux + uy * uy + uz * uz)
                    fnx, fny, fnz = ux * inv_len, uy * inv_len, uz * inv_len
                    fq = [c[q] for c in af]
                    sf = (s + tt * dsig)[q]
                    rnorm = np.sqrt(Rx[q] * Rx[q] + Ry[q] * Ry[q] + Rz[q] * Rz[q])
                    fn_dot = fq[0] * fnx + fq[1] * fny + fq[2] * fnz
                    fn_a = np.sqrt(fq[0] * fq[0] + fq[1] * fq[1] + fq[2] * fq[2])
                    valid = (rnorm <= _RES_TOL * fn_a * size) & (fn_dot < 0.0) & (it < _MAX_ITER)
                    rows = idx[q]
                    for dst, src in zip(out, (frx, fry, frz, fnx, fny, fnz, sf, valid)):
                        dst[rows] = src
                    keep = ~done
                    if not keep.any():
                        break
                    idx = idx[keep]
                    af = [c[keep] for c in af]
                    (t_face, cb1, cb2, db1, db2, s_new) = (a[keep] for a in (t_face, cb1, cb2, db1, db2, s_new))
            # walk the whole step over the triangles it crosses
            if xp is PY:
                state = list(self._walk_one(t_face, cb1, cb2, db1, db2))
                sig = s_new
            else:
                act_f, act_b1, act_b2 = self._walk(t_face, cb1, cb2, db1, db2)
                act_sig = s_new
        return tuple(out[:7]) + (out[7] == 1.0,)


def _sides(p, line):
    """Plücker side products of a line with a triangle's three edges, term by term (the same
    operations on floats and on arrays): ``p`` rows (3, 6) (or arrays (n, 3, 6)), ``line`` 6 values."""
    if isinstance(p, np.ndarray):
        p = [[p[:, k, j] for j in range(6)] for k in range(3)]
    return tuple(
        row[0] * line[0] + row[1] * line[1] + row[2] * line[2] + row[3] * line[3] + row[4] * line[4] + row[5] * line[5]
        for row in p
    )


def _exit(b1, b2, db1, db2, xp):
    """Where a barycentric step leaves its triangle: the edge ``k`` (opposite local vertex
    ``k``) and the fraction ``t`` of the step (``≥ 1``: it stays inside)."""
    b0 = 1.0 - b1 - b2
    n1, n2 = b1 + db1, b2 + db2
    n0 = 1.0 - n1 - n2
    # a step that starts on (or a rounding error beyond) an edge and goes out leaves at once
    t0 = xp.where(n0 < 0.0, xp.where(b0 > 0.0, xp.div(b0, b0 - n0), 0.0), 2.0)
    t1 = xp.where(n1 < 0.0, xp.where(b1 > 0.0, xp.div(b1, b1 - n1), 0.0), 2.0)
    t2 = xp.where(n2 < 0.0, xp.where(b2 > 0.0, xp.div(b2, b2 - n2), 0.0), 2.0)
    k = xp.where(t1 < t0, xp.where(t2 < t1, 2, 1), xp.where(t2 < t0, 2, 0))
    return k, xp.where(k == 0, t0, xp.where(k == 1, t1, t2))


def _cross_rows(a: NDArray, b: NDArray) -> NDArray:
    """Row-wise cross product of (N, 3) arrays (np.cross is slow on small arrays)."""
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


# -- loading -----------------------------------------------------------------------------------


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
    if path.suffix.lower() not in (".stl", ".obj", ".ply"):
        raise InputError(f"{path}: mesh file must be .stl, .obj or .ply")
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
    rpy = tuple(float(a) for a in rotation.as_euler("xyz"))
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

    table = read_toml(path, "fingertip").get("fingertip")
    if not isinstance(table, dict):
        raise InputError(f"{path}: expected a [fingertip] table")
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


# -- generated meshes --------------------------------------------------------------------------


def capsule_mesh(
    radius: float,
    length: float,
    *,
    segments: int = 160,
    spacing: float | None = None,
    nail_height: float = 0.0,
    nail_half_width_deg: float = 50.0,
    nail_z: tuple[float, float] = (0.008, 0.0),
    nail_edge: float = 0.0015,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A closed triangle mesh of a capsule fingertip, optionally with a nail (sensor frame, m).

    The capsule of :class:`~softtip.core.fingertip.Capsule` (cylinder of ``radius`` along +z from
    ``z = 0``, hemisphere at ``(0, 0, length)``), closed by a flat base at ``z = 0``. A nail
    is a raised plate of ``nail_height`` (m) on the back (``−x`` side), ``nail_half_width_deg``
    to either side, from ``z = nail_z[0]`` to ``nail_z[1]`` m past the cap's equator along the
    surface, with smooth edges of width ``nail_edge`` (m).

    Parameters
    ----------
    radius, length : float
        Capsule radius and cylinder length, m.
    segments : int
        Vertices around the axis.
    spacing : float, optional
        Target edge length along the profile, m (default: the spacing around the axis).

    Returns
    -------
    vertices : array, shape (V, 3)
    faces : array of int, shape (F, 3), counter-clockwise seen from outside.
    """
    h = spacing if spacing is not None else 2.0 * math.pi * radius / segments
    # profile arc length s: base disc (ρ 0→R), side (z 0→L), cap (angle 0→π/2)
    s_base, s_side, s_cap = radius, length, 0.5 * math.pi * radius
    n_base = max(2, round(s_base / (2.0 * h)))
    n_side = max(1, round(s_side / h))
    n_cap = max(2, round(s_cap / h))
    s_list = np.concatenate(
        (
            np.linspace(0.0, s_base, n_base + 1)[1:],
            s_base + np.linspace(0.0, s_side, n_side + 1)[1:],
            s_base + s_side + np.linspace(0.0, s_cap, n_cap + 1)[1:-1],
        )
    )
    phi = 2.0 * math.pi * np.arange(segments) / segments
    rings = []
    for s in s_list:
        if s <= s_base:
            rho, z, nr, nz = s, 0.0, 0.0, -1.0
        elif s <= s_base + s_side:
            rho, z, nr, nz = radius, s - s_base, 1.0, 0.0
        else:
            a = (s - s_base - s_side) / radius
            rho, z, nr, nz = radius * math.cos(a), length + radius * math.sin(a), math.cos(a), math.sin(a)
        x, y = rho * np.cos(phi), rho * np.sin(phi)
        ring = np.column_stack((x, y, np.full(segments, z)))
        if nail_height > 0.0 and nz > -0.5:
            w = _nail_weight(phi, s - s_base, radius, length, nail_half_width_deg, nail_z, nail_edge)
            ring = ring + nail_height * w[:, None] * np.column_stack((nr * np.cos(phi), nr * np.sin(phi), np.full(segments, nz)))
        rings.append(ring)
    bottom = np.array([[0.0, 0.0, 0.0]])
    top = np.array([[0.0, 0.0, length + radius + nail_height * float(
        _nail_weight(np.array([math.pi]), s_side + s_cap, radius, length, nail_half_width_deg, nail_z, nail_edge)[0]
    )]])
    vertices = np.concatenate([bottom] + rings + [top])
    nr_rings = len(rings)
    j = np.arange(segments)
    jn = (j + 1) % segments
    faces = []
    # base fan (outward normal −z): seen from below, counter-clockwise is decreasing φ
    first = 1
    faces.append(np.column_stack((np.zeros(segments, dtype=np.int64), first + jn, first + j)))
    for r in range(nr_rings - 1):
        a = 1 + r * segments
        b = a + segments
        faces.append(np.column_stack((a + j, a + jn, b + jn)))
        faces.append(np.column_stack((a + j, b + jn, b + j)))
    last = 1 + (nr_rings - 1) * segments
    apex = len(vertices) - 1
    faces.append(np.column_stack((last + j, last + jn, np.full(segments, apex))))
    return vertices, np.concatenate(faces).astype(np.int64)


def _nail_weight(phi, s_side, radius, length, half_width_deg, nail_z, edge):
    """0..1 height profile of the nail over (azimuth, arc length from the base rim)."""
    # angular distance from the back (φ = π), as arc length on the skin
    dphi = np.abs(np.angle(np.exp(1j * (phi - math.pi))))
    across = radius * (math.radians(half_width_deg) - dphi)
    z0, past = nail_z
    s_end = length + past
    along = np.minimum(s_side - z0, s_end - s_side)

    def smooth(x):
        u = np.clip(x / edge + 0.5, 0.0, 1.0)
        return u * u * (3.0 - 2.0 * u)

    return smooth(across) * smooth(along)
