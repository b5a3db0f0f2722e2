"""Closest points on a triangle mesh: the signed distance, normal and projection of any point.

The queries behind a mesh fingertip's surface, normal and projection kernels (the shape
protocol, :mod:`softtip.core.shape`) and behind
:meth:`softtip.core.mesh.MeshFingertip.closest`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import PY
from softtip.core.mesh.topology import _LEAF, _NEAR_K

__all__ = ["ClosestPoints"]


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


class ClosestPoints:
    """The closest-point queries of :class:`~softtip.core.mesh.MeshFingertip` (they read the arrays its ``_prepare`` built)."""

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
