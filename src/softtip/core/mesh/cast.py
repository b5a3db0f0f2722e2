"""Step 1 of the mesh contact solve: cast the wrench's central axis against the triangles.

Plücker-coordinate side tests (watertight: a line through a shared edge is never lost
between two triangles) over spatially compact clusters with bounding spheres; the first hit
where the axis enters the skin going along ``+f`` is kept.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["AxisCast"]

_CAST_BLOCK = 256
_ALL_FOUR = np.frombuffer(b"\x01\x01\x01\x01", dtype=np.uint32)[0]  # four True bytes as one word
_WALK = 8  # faces the streaming cast walks from the previous sample's face
_SIDE_TOL = 1e-13  # Plücker side products within this × |f| × size² of zero count as on the edge


def _sides(p, line):
    """Plücker side products of a line with a triangle's three edges, term by term (the same
    operations on floats and on arrays): ``p`` rows (3, 6) (or arrays (n, 3, 6)), ``line`` 6 values."""
    if isinstance(p, np.ndarray):
        p = [[p[:, k, j] for j in range(6)] for k in range(3)]
    return tuple(
        row[0] * line[0] + row[1] * line[1] + row[2] * line[2] + row[3] * line[3] + row[4] * line[4] + row[5] * line[5]
        for row in p
    )


class AxisCast:
    """The axis cast of :class:`~softtip.core.mesh.MeshFingertip` (batch and one sample)."""

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
