"""Contact point and line direction estimated jointly over a sliding window (no latching).

Line-contact model (paper III-A): over a short window the contact point ``r`` and the line
direction ``d`` are fixed and each sample transmits a spin about ``n`` and a moment about
``n × d`` only, so the moment about the contact point has **no component along d**:

``d · (m_k − r × f_k) = 0`` for every sample ``k`` of the window.

softtip minimises ``J(r, d) = Σ_k (d · (m_k − r × f_k))²`` over ``r`` on the skin and unit
``d ⟂ n(r)``. Moving ``r`` by ``s`` across the line (along ``e = n × d``) changes the
residual by ``−s (f_k · n)``; moving it along ``d`` does not change it at all (a line
contact does not say where along the line it is), so that coordinate is kept at the
latched point (regularisation toward the latch along the weak direction). For a given
tangent plane the problem is then *linear*: with ``w_k`` the tangential part of
``q_k = m_k − r₀ × f_k`` in a basis ``(t₁, t₂)`` and ``c_k = f_k · n``, eliminating ``s``
leaves ``uᵀ P u`` with the 2×2 Schur complement ``P = Σ w wᵀ − (Σ w c)(Σ w c)ᵀ / Σ c²``:
``d`` is its smallest eigenvector (closed form) and ``s = u · Σ w c / Σ c²``. The new point
is put back on the skin and the step repeated (a Gauss–Newton iteration on the curved skin;
two are plenty for millimetre steps on a 16 mm tip).

Everything comes from 21 window sums of outer products of ``f`` and ``q_A = m − r_A × f``
about an anchor ``r_A`` near the contact (the first soft-finger point of the contact, so
that the sums carry no large cancelling ``r × f`` terms): :func:`joint_products` gives the
per-sample products (cumulated by the batch, kept as running sums by the stream) and
:func:`joint_solve_kernel` the solution from the window sums, component-wise for both
back ends of :mod:`softtip._xp`.

**Identifiability.** The direction and the offset across the line trade off when the
tangential spin torque stays proportional to the normal force over the window (exactly
what a latch absorbs). The window's conditioning is ``(1 − |ρ|) / (1 + |ρ|)``, the ratio of
the eigenvalues of the unit-diagonal Gauss–Newton normal matrix of (direction angle,
offset), where ``ρ`` is the correlation of ``e · q_k`` with ``f_k · n`` over the window; the
pipeline falls back to the latched point (and flags it) below a settable threshold.
"""

from __future__ import annotations

from softtip.spin import tangent_frame_kernel

__all__ = ["N_SUMS", "joint_products", "joint_solve_kernel"]

#: Number of window sums: Σ q qᵀ (6, symmetric), Σ q fᵀ (9), Σ f fᵀ (6, symmetric).
N_SUMS = 21


def joint_products(fx, fy, fz, qx, qy, qz):
    """The 21 per-sample products whose window sums :func:`joint_solve_kernel` needs.

    Parameters
    ----------
    fx, fy, fz : float or array
        Force, N.
    qx, qy, qz : float or array
        Moment about the anchor ``r_A``, ``m − r_A × f``, N·m.

    Returns
    -------
    tuple of 21
        ``qq`` (xx, xy, xz, yy, yz, zz), ``qf`` (row-major 3×3, ``q_i f_j``), ``ff`` (xx, xy,
        xz, yy, yz, zz).
    """
    return (
        qx * qx, qx * qy, qx * qz, qy * qy, qy * qz, qz * qz,
        qx * fx, qx * fy, qx * fz, qy * fx, qy * fy, qy * fz, qz * fx, qz * fy, qz * fz,
        fx * fx, fx * fy, fx * fz, fy * fy, fy * fz, fz * fz,
    )  # fmt: skip


def _sym(s, ux, uy, uz, vx, vy, vz):
    """``uᵀ S v`` for a symmetric S given as (xx, xy, xz, yy, yz, zz)."""
    sxx, sxy, sxz, syy, syz, szz = s
    return (
        ux * (sxx * vx + sxy * vy + sxz * vz)
        + uy * (sxy * vx + syy * vy + syz * vz)
        + uz * (sxz * vx + syz * vy + szz * vz)
    )


def _full(s, ux, uy, uz, vx, vy, vz):
    """``uᵀ S v`` for a full S given row-major."""
    return (
        ux * (s[0] * vx + s[1] * vy + s[2] * vz)
        + uy * (s[3] * vx + s[4] * vy + s[5] * vz)
        + uz * (s[6] * vx + s[7] * vy + s[8] * vz)
    )


def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def joint_solve_kernel(sums, r0x, r0y, r0z, ax, ay, az, tip, iterations, xp):
    """Joint contact point and conditioning from the window sums, component-wise.

    Parameters
    ----------
    sums : sequence of 21 floats or arrays
        Window sums of :func:`joint_products` (about the anchor ``a``).
    r0x, r0y, r0z : float or array
        Start point on the skin (the latched point), m; its coordinate along the line is
        kept.
    ax, ay, az : float or array
        Anchor ``r_A`` of the sums, m.
    tip : Fingertip
        For the skin normal and the projection onto the skin.
    iterations : int
        Gauss–Newton steps (each: closed-form direction and offset, then projection).
    xp : namespace
        :data:`softtip._xp.NP` or :data:`softtip._xp.PY`.

    Returns
    -------
    tuple
        ``(rx, ry, rz, dx, dy, dz, conditioning)``: the point (m), the window's line
        direction (unit) and the conditioning in [0, 1] (NaN when undefined).
    """
    qq, qf, ff = sums[0:6], sums[6:15], sums[15:21]
    rx, ry, rz = r0x, r0y, r0z
    dx = dy = dz = cond = None
    for _ in range(iterations):
        nx, ny, nz = tip._normal_kernel(rx, ry, rz, xp)
        t1x, t1y, t1z, t2x, t2y, t2z = tangent_frame_kernel(nx, ny, nz, xp)
        px, py, pz = rx - ax, ry - ay, rz - az  # shift of the reference from the anchor

        def quad(ux, uy, uz, vx, vy, vz):
            # uᵀ Σ q qᵀ v with q = q_A − p × f: u·q = u·q_A + (p × u)·f
            hux, huy, huz = _cross(px, py, pz, ux, uy, uz)
            hvx, hvy, hvz = _cross(px, py, pz, vx, vy, vz)
            return (
                _sym(qq, ux, uy, uz, vx, vy, vz)
                + _full(qf, ux, uy, uz, hvx, hvy, hvz)
                + _full(qf, vx, vy, vz, hux, huy, huz)
                + _sym(ff, hux, huy, huz, hvx, hvy, hvz)
            )

        def bil(ux, uy, uz, wx, wy, wz):
            # uᵀ Σ q fᵀ w
            hux, huy, huz = _cross(px, py, pz, ux, uy, uz)
            return _full(qf, ux, uy, uz, wx, wy, wz) + _sym(ff, hux, huy, huz, wx, wy, wz)

        scc = _sym(ff, nx, ny, nz, nx, ny, nz)
        g1 = bil(t1x, t1y, t1z, nx, ny, nz)
        g2 = bil(t2x, t2y, t2z, nx, ny, nz)
        p11 = quad(t1x, t1y, t1z, t1x, t1y, t1z) - xp.div(g1 * g1, scc)
        p12 = quad(t1x, t1y, t1z, t2x, t2y, t2z) - xp.div(g1 * g2, scc)
        p22 = quad(t2x, t2y, t2z, t2x, t2y, t2z) - xp.div(g2 * g2, scc)
        # smallest eigenvector of [[p11, p12], [p12, p22]] in closed form (square roots
        # only, correctly rounded in both back ends; each branch free of cancellation)
        half = 0.5 * (p11 - p22)
        root = xp.sqrt(half * half + p12 * p12)
        big = p11 >= p22
        v1 = xp.where(big, p12, half - root)
        v2 = xp.where(big, -half - root, p12)
        vn = xp.sqrt(v1 * v1 + v2 * v2)
        u1, u2 = xp.div(v1, vn), xp.div(v2, vn)
        dx, dy, dz = u1 * t1x + u2 * t2x, u1 * t1y + u2 * t2y, u1 * t1z + u2 * t2z
        ex, ey, ez = _cross(nx, ny, nz, dx, dy, dz)
        s = xp.div(u1 * g1 + u2 * g2, scc)
        # conditioning of (angle, offset) at this linearisation point
        rho = xp.div(bil(ex, ey, ez, nx, ny, nz), xp.sqrt(quad(ex, ey, ez, ex, ey, ez) * scc))
        arho = xp.abs(rho)
        cond = xp.div(1.0 - arho, 1.0 + arho)
        rx, ry, rz = tip._project_kernel(rx + s * ex, ry + s * ey, rz + s * ez, xp)
    return rx, ry, rz, dx, dy, dz, cond
