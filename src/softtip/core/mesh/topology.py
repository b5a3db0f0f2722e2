"""Preparing a triangle mesh for the contact solve: neighbours, corner normals, creases, exposure, clusters.

Run once per :class:`~softtip.core.mesh.MeshFingertip` (in ``_prepare``); the arrays they
return are what the cast, the Newton refinement and the closest-point queries read.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = []

_LEAF = 32  # at most this many triangles per cluster of the cast's pre-filter
_NEAR_K = 32  # nearest triangle centroids tried first by the closest-point query


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


def _bodies(nb_face: NDArray) -> int:
    """How many separate bodies (edge-connected groups of faces) a closed mesh has, from its
    neighbour table (:func:`_edge_neighbours`)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nf = len(nb_face)
    rows = np.repeat(np.arange(nf), 3)
    graph = coo_matrix((np.ones(3 * nf, dtype=np.int8), (rows, nb_face.ravel())), shape=(nf, nf))
    return int(connected_components(graph, directed=False)[0])


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
