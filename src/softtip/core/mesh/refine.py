"""Step 2 of the mesh contact solve: Newton's method in barycentric coordinates, walking across triangles.

``F(b₁, b₂, σ) = r(b) × f + σ n(b) − m`` on the current triangle; a step that leaves it goes
on in the neighbouring triangle. Written once for numpy arrays (batch) and Python floats
(stream), like the closed-form kernels (:mod:`softtip.core._xp`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from softtip.core._xp import NP, PY

__all__ = ["NewtonRefine"]

_MAX_ITER = 30  # Newton steps
_MAX_CROSS = 16  # triangles one Newton step may cross (the next step goes on)
_STEP_TOL = 1e-7  # converged when a step moves the point less than this × the tip's size (the step is taken: the error left is of its square)
_RES_TOL = 1e-6  # and a solution is kept when |F| (before the last step) ≤ this × |f| × size


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


class NewtonRefine:
    """The Newton refinement and triangle walk of :class:`~softtip.core.mesh.MeshFingertip`."""

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
