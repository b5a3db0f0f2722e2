"""Soft-finger contacts on a mesh's sharp features: crease edges and corners.

Where the normal is not continuous (edges sharper than ``crease_angle_deg``, and their
corners) the smooth Newton solve cannot land; these roots are bracketed and bisected along
each crease edge and searched in each corner's cone of normals.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CreaseContact"]

_CREASE_TAN = 6.0  # a crease contact's normal is within atan(6) = 80.5° of −f
_CREASE_COS = 1.0 / math.sqrt(1.0 + _CREASE_TAN**2)
_CREASE_EDGE_TOL = 1e-9  # the crease edge's ends are searched this far (in t) beyond the edge
_CREASE_WEDGE_TOL = 1e-6  # a normal this close (rad) outside a crease's wedge or cone counts as in it (a root
# where the moment only touches the normals' plane is found to the square root of the rounding)
_CREASE_RES_TOL = 1e-9  # a crease edge's moment may leave the normals' plane by this × |f| × size
_CREASE_SPLIT = 16  # intervals bracketing a crease edge's roots
_CREASE_BISECT = 60  # interval halvings: to the last bit of t
_CUBIC_FROM_VALUES = np.linalg.inv(np.vander([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0], 4, increasing=True)).tolist()


class CreaseContact:
    """The crease-edge and corner solve of :class:`~softtip.core.mesh.MeshFingertip`."""

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
