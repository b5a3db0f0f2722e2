"""Contact point and line direction estimated jointly over a sliding window (``joint`` mode).

Line-contact model (paper III-A): over a short window the contact point ``r`` and the line
direction ``d`` are fixed and each sample transmits a spin about ``n`` and a moment about
``n × d`` only, so the moment about the contact point has **no component along d**:

``d · (m_k − r × f_k) = 0`` for every sample ``k`` of the window.

softtip minimises ``J(r, d) = Σ_k (d · (m_k − r × f_k))²`` over ``r`` on the skin and unit
``d ⟂ n(r)``. Linearised about a start point, with ``e = n × d``, ``τ_k = e · q_k`` (the
moment about ``n × d``) and ``c_k = f_k · n``, the residual of a rotation ``θ`` of ``d``
about ``n`` and a shift ``s`` of ``r`` along ``e`` (across the line) is
``d · q_k + θ τ_k − s c_k``. A shift **along d** does not change it at all: a line contact
does not say where along the line it is, whatever the forces, so that coordinate is kept at
the latched point. For a given tangent plane the problem is linear: with ``w_k`` the
tangential part of ``q_k`` in a basis ``(t₁, t₂)``, eliminating ``s`` leaves ``uᵀ P u`` with
the 2×2 Schur complement ``P = Σ w wᵀ − (Σ w c)(Σ w c)ᵀ / Σ c²``: ``d`` is its smallest
eigenvector (closed form) and ``s = u · Σ w c / Σ c²``. The new point is put back on the
skin and the step repeated (Gauss–Newton on the curved skin).

Everything comes from 21 window sums of outer products of ``f`` and ``q_A = m − r_A × f``
about an anchor ``r_A`` near the contact (the first soft-finger point of the contact, so
that the sums carry no large cancelling ``r × f`` terms): :func:`joint_products` gives the
per-sample products (cumulated by the batch, kept as running sums by the stream) and
:func:`joint_solve_kernel` the solution from the window sums, component-wise for both
back ends of :mod:`softtip._xp`.

**Identifiability.** ``θ`` and ``s`` are separable only when ``τ_k`` is not proportional to
``c_k`` over the window: a rotated line plus a shifted point explains a window in which the
tangential spin torque scales with the normal force (a grasp squeezing up, or held still)
exactly as well as the true contact. What separates them is a change of the moment about
``n × d`` that the normal force does not follow: a disturbance of the held object, a
tangential load changing at depth, a changing force direction. The Gauss–Newton normal
matrix of ``(θ, s)`` is ``[[Σ τ², −Σ τ c], [−Σ τ c, Σ c²]]``; with ``ρ`` the (uncentred)
correlation of ``τ`` and ``c`` the window reports

* ``conditioning = (1 − |ρ|) / (1 + |ρ|)``: the reciprocal condition number of the
  unit-diagonal normal matrix, in [0, 1];
* ``angle_std = σ / sqrt(Σ τ² (1 − ρ²))`` and ``offset_std = σ / sqrt(Σ c² (1 − ρ²))``: the
  first-order standard deviations of ``θ`` (rad) and ``s`` (m) for a residual noise ``σ``
  per sample (the sensor noise model projected on ``d`` at ``r``);
* ``residual``: the root-mean-square residual of the fit in units of ``σ`` (about 1 when
  the window is a line contact; far above, the window is not one: the contact moved
  within it, or the model's other assumptions fail).

The pipeline accepts a window only when both standard deviations and the residual are
small; noise in
``τ`` alone makes a held grasp look excited, and ``angle_std`` is what tells it apart
(pure noise gives ``angle_std ≈ 1/√N`` rad for ``N`` samples). Samples of a low-pass
filtered log are correlated, so there the standard deviations are optimistic.
"""

from __future__ import annotations

from softtip.noise import SensorNoise, _quad_kernel
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


def _dot(a, x, y, z):
    return a[0] * x + a[1] * y + a[2] * z


def _moments(qq, qf, ff, px, py, pz, ux, uy, uz):
    """``(Σ q_A (u·q), Σ f (u·q), p × u)`` for the moment ``q = q_A − p × f`` about ``p``."""
    hx, hy, hz = _cross(px, py, pz, ux, uy, uz)
    xx, xy, xz, yy, yz, zz = qq
    fxx, fxy, fxz, fyy, fyz, fzz = ff
    # Σ q_A (u·q_A) + Σ q_A fᵀ h, and Σ f q_Aᵀ u + Σ f fᵀ h
    a = (
        xx * ux + xy * uy + xz * uz + qf[0] * hx + qf[1] * hy + qf[2] * hz,
        xy * ux + yy * uy + yz * uz + qf[3] * hx + qf[4] * hy + qf[5] * hz,
        xz * ux + yz * uy + zz * uz + qf[6] * hx + qf[7] * hy + qf[8] * hz,
    )
    b = (
        qf[0] * ux + qf[3] * uy + qf[6] * uz + fxx * hx + fxy * hy + fxz * hz,
        qf[1] * ux + qf[4] * uy + qf[7] * uz + fxy * hx + fyy * hy + fyz * hz,
        qf[2] * ux + qf[5] * uy + qf[8] * uz + fxz * hx + fyz * hy + fzz * hz,
    )
    return a, b, (hx, hy, hz)


def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def joint_solve_kernel(sums, count, r0x, r0y, r0z, ax, ay, az, tip, iterations, noise: SensorNoise, xp):
    """Joint contact point, direction and conditioning from the window sums, component-wise.

    Parameters
    ----------
    sums : sequence of 21 floats or arrays
        Window sums of :func:`joint_products` (about the anchor ``a``).
    count : int or array
        Samples in the window.
    r0x, r0y, r0z : float or array
        Start point on the skin (the latched point), m; its coordinate along the line is
        kept.
    ax, ay, az : float or array
        Anchor ``r_A`` of the sums, m.
    tip : Fingertip
        For the skin normal and the projection onto the skin.
    iterations : int
        Gauss–Newton steps (each: closed-form direction and offset, then projection).
    noise : SensorNoise
        Per-sample noise of the wrench the sums were made from (for the standard
        deviations).
    xp : namespace
        :data:`softtip._xp.NP` or :data:`softtip._xp.PY`.

    Returns
    -------
    tuple
        ``(rx, ry, rz, dx, dy, dz, conditioning, angle_std, offset_std, residual)``: the
        point (m), the window's line direction (unit), the conditioning in [0, 1], the
        standard deviations of the line angle (rad) and of the offset across the line (m),
        and the root-mean-square residual of the fit in units of the noise, all at the last
        linearisation point (NaN or inf when undefined).
    """
    qq, qf, ff = sums[0:6], sums[6:15], sums[15:21]
    rx, ry, rz = r0x, r0y, r0z
    dx = dy = dz = cond = angle_std = offset_std = residual = None
    for _ in range(iterations):
        nx, ny, nz = tip._normal_kernel(rx, ry, rz, xp)
        t1x, t1y, t1z, t2x, t2y, t2z = tangent_frame_kernel(nx, ny, nz, xp)
        px, py, pz = rx - ax, ry - ay, rz - az  # shift of the reference from the anchor

        # for u in (t1, t2): u·q = u·q_A + h·f with h = p × u, so with a = Σ q_A (u·q) and
        # b = Σ f (u·q) every sum needed is a dot product
        a1, b1, h1 = _moments(qq, qf, ff, px, py, pz, t1x, t1y, t1z)
        a2, b2, h2 = _moments(qq, qf, ff, px, py, pz, t2x, t2y, t2z)
        scc = _sym(ff, nx, ny, nz, nx, ny, nz)
        g1 = _dot(b1, nx, ny, nz)
        g2 = _dot(b2, nx, ny, nz)
        q11 = _dot(a1, t1x, t1y, t1z) + _dot(b1, *h1)
        q12 = _dot(a1, t2x, t2y, t2z) + _dot(b1, *h2)
        q22 = _dot(a2, t2x, t2y, t2z) + _dot(b2, *h2)
        p11 = q11 - xp.div(g1 * g1, scc)
        p12 = q12 - xp.div(g1 * g2, scc)
        p22 = q22 - xp.div(g2 * g2, scc)
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
        # conditioning of (angle, offset) at this linearisation point; e = n × d is
        # (−u2, u1) in the tangent basis, so its sums come from those of t1 and t2
        stt = u2 * u2 * q11 - 2.0 * u1 * u2 * q12 + u1 * u1 * q22
        stc = u1 * g2 - u2 * g1
        rho2 = xp.div(stc * stc, stt * scc)
        arho = xp.sqrt(rho2)
        cond = xp.div(1.0 - arho, 1.0 + arho)
        var = _quad_kernel(dx, dy, dz, rx, ry, rz, noise)  # residual noise per sample
        lack = xp.maximum(1.0 - rho2, 0.0)  # ρ² may round above 1
        angle_std = xp.sqrt(xp.div(var, stt * lack))
        offset_std = xp.sqrt(xp.div(var, scc * lack))
        # the cost at the minimum is P's smallest eigenvalue, det / largest (no cancellation)
        cost = xp.div(p11 * p22 - p12 * p12, 0.5 * (p11 + p22) + root)
        residual = xp.sqrt(xp.div(xp.maximum(cost, 0.0), (count - 2.0) * var))
        # step across the line; along it, back to the start's coordinate (not observable)
        mx, my, mz = rx + s * ex, ry + s * ey, rz + s * ez
        along = (mx - r0x) * dx + (my - r0y) * dy + (mz - r0z) * dz
        rx, ry, rz = tip._project_kernel(mx - along * dx, my - along * dy, mz - along * dz, xp)
    return rx, ry, rz, dx, dy, dz, cond, angle_std, offset_std, residual
