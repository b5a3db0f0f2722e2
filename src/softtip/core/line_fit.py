"""Contact point and line direction estimated jointly over a sliding window (``line-fit`` mode).

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
that the sums carry no large cancelling ``r × f`` terms): :func:`line_fit_products` gives the
per-sample products (cumulated by the batch, kept as running sums by the stream) and
:func:`line_fit_solve_kernel` the solution from the window sums, component-wise for both
back ends of :mod:`softtip.core._xp`.

**Identifiability.** ``θ`` and ``s`` are separable only when ``τ_k`` is not proportional to
``c_k`` over the window: a rotated line plus a shifted point explains a window in which the
tangential spin torque scales with the normal force (a grasp squeezing up, or held still)
exactly as well as the true contact. What separates them is a change of the moment about
``n × d`` that the normal force does not follow: a disturbance of the held object, a
tangential load changing at depth, a changing force direction. Noise alone also makes
``τ_k`` vary, and at high sample rates a window holds enough samples for that to look like
excitation (errors in variables): the direction would then be the quietest noise direction,
and noise correlated between ``c_k`` and ``τ_k`` (off the sensor's axis, ``q_A`` carries the
force noise through ``r_A × f``) would shift the point. So the solve first subtracts from
all 21 sums ``N`` times the noise covariance of ``(q_A, f)`` from the sensor noise model,
which leaves unbiased second moments of the noise-free wrench. The excitation counted is
the larger eigenvalue of the corrected ``P`` less a margin for what the noise still puts
there: the upper 3 σ tail of its scatter plus :data:`MODEL_MARGIN` of its expected share,
``E = λ_max − σ_τ² (L (χ²_ν − ν) + 0.25 (N − 1))``. Here ``L`` is the number of samples
per independent noise sample (1 unfiltered, ``1 / g²`` after a low-pass of white-noise gain
``g``), ``ν = (N − 1) / L`` the independent samples of the window and ``χ²_ν`` the upper
3 σ quantile of a χ² with ``ν`` degrees of freedom (Wilson–Hilferty; ``≈ ν + 3 √(2ν)``
for large ``ν``, but right-skewed when a low-pass leaves few). A noise model up to about
12 % low in standard deviation is then not taken for excitation. The window reports

* ``conditioning = (1 − |ρ|) / (1 + |ρ|)`` with ``ρ² = 1 − E / Σ τ²``: the reciprocal
  condition number of the unit-diagonal normal matrix of ``(θ, s)``, counting only
  excitation beyond noise, in [0, 1];
* ``angle_std = σ √(κ / E)`` and ``offset_std = σ √(κ Σ τ² / (Σ c² E))``: the first-order
  standard deviations of ``θ`` (rad) and ``s`` (m) for a residual noise ``σ`` per sample
  (the sensor noise model projected on ``d`` at ``r``), inflated by
  ``κ = L (1 + (N − 1) σ_τ² / E)``: for the noise in ``τ`` itself (errors in variables) and
  for the correlation of filtered noise, against which the excitation varies slowly;
  infinite without excitation;
* ``residual``: the root-mean-square residual of the fit in units of ``σ`` (about 1 when
  the window is a line contact; far above, the window is not one: the contact moved
  within it, or the model's other assumptions fail).

The pipeline accepts a window only when both standard deviations and the residual are
small. With a low-pass filter the noise model is the filtered one.
"""

from __future__ import annotations

from softtip.core._jit import jitable
from softtip.core.noise import SensorNoise, noise_quad, noise_variances
from softtip.core.spin import tangent_frame_kernel

__all__ = ["N_SUMS", "line_fit_products", "line_fit_solve_kernel"]

#: Number of window sums: Σ q qᵀ (6, symmetric), Σ q fᵀ (9), Σ f fᵀ (6, symmetric).
N_SUMS = 21


@jitable
def line_fit_products(fx, fy, fz, qx, qy, qz):
    """The 21 per-sample products whose window sums :func:`line_fit_solve_kernel` needs.

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


@jitable
def _sym(s, ux, uy, uz, vx, vy, vz):
    """``uᵀ S v`` for a symmetric S given as (xx, xy, xz, yy, yz, zz)."""
    sxx, sxy, sxz, syy, syz, szz = s
    return (
        ux * (sxx * vx + sxy * vy + sxz * vz)
        + uy * (sxy * vx + syy * vy + syz * vz)
        + uz * (sxz * vx + syz * vy + szz * vz)
    )


#: Share of the noise's expected contribution to a window that must be exceeded besides its
#: scatter: tolerates a sensor noise model up to about 12 % low in standard deviation.
MODEL_MARGIN = 0.25


@jitable
def _without_noise(sums, count, ax, ay, az, variances):
    """The window sums less their expected noise: ``count`` times the noise covariance of
    ``(q_A, f)``, with ``q_A = m − a × f`` (``a`` the anchor), for the unbiased second
    moments of the noise-free wrench (errors in variables); ``variances`` the noise's
    (:func:`~softtip.core.noise.noise_variances`)."""
    fx, fy, fz, mx, my, mz = variances
    # q_A = m − A f with A = [a]× (rows a0*, a1*, a2*): cov(q_A) = Σ_m + A Σ_f Aᵀ, cov(q_A, f) = −A Σ_f
    a00, a01, a02 = 0.0, -az, ay
    a10, a11, a12 = az, 0.0, -ax
    a20, a21, a22 = -ay, ax, 0.0
    n00 = mx + (a00 * a00 * fx + a01 * a01 * fy + a02 * a02 * fz)
    n01 = a00 * a10 * fx + a01 * a11 * fy + a02 * a12 * fz
    n02 = a00 * a20 * fx + a01 * a21 * fy + a02 * a22 * fz
    n11 = my + (a10 * a10 * fx + a11 * a11 * fy + a12 * a12 * fz)
    n12 = a10 * a20 * fx + a11 * a21 * fy + a12 * a22 * fz
    n22 = mz + (a20 * a20 * fx + a21 * a21 * fy + a22 * a22 * fz)
    return (
        (sums[0] - count * n00, sums[1] - count * n01, sums[2] - count * n02, sums[3] - count * n11,
         sums[4] - count * n12, sums[5] - count * n22),
        (sums[6] - count * (-a00 * fx), sums[7] - count * (-a01 * fy), sums[8] - count * (-a02 * fz),
         sums[9] - count * (-a10 * fx), sums[10] - count * (-a11 * fy), sums[11] - count * (-a12 * fz),
         sums[12] - count * (-a20 * fx), sums[13] - count * (-a21 * fy), sums[14] - count * (-a22 * fz)),
        (sums[15] - count * fx, sums[16] - count * 0.0, sums[17] - count * 0.0, sums[18] - count * fy,
         sums[19] - count * 0.0, sums[20] - count * fz),
    )  # fmt: skip


@jitable
def smallest_eigenvector(a11, a12, a22, xp):
    """``(u1, u2, root)``: the unit eigenvector of the smaller eigenvalue of the symmetric
    ``[[a11, a12], [a12, a22]]`` in closed form (square roots only, correctly rounded in both
    back ends; each branch free of cancellation), and ``root``, half the eigenvalues' gap. The
    line fit's and the depth solve's (:mod:`softtip.core.depth`)."""
    half = 0.5 * (a11 - a22)
    root = xp.sqrt(half * half + a12 * a12)
    big = a11 >= a22
    v1 = xp.where(big, a12, half - root)
    v2 = xp.where(big, -half - root, a12)
    vn = xp.sqrt(v1 * v1 + v2 * v2)
    return xp.div(v1, vn), xp.div(v2, vn), root


#: Standard normal quantile of the noise-only excitation that is not counted (≈ 3 σ).
EXCITATION_Z = 3.0


#: Fewest degrees of freedom the Wilson–Hilferty form is used at: below ≈ 0.1 it turns
#: over (its excess per degree of freedom, largest there at 33, falls to 4 at ν = 0.03 and
#: below zero under 0.025, where χ²'s own grows on: 49 at 0.1, 175 at 0.01).
CHI2_MIN_DOF = 0.1


@jitable
def _chi2_excess(nu, xp):
    """Upper :data:`EXCITATION_Z` quantile of a χ² with ``nu`` degrees of freedom less its
    mean (Wilson–Hilferty), ``≈ z √(2ν)`` for large ``nu``: the right-skewed tail matters
    when a low-pass leaves a window few independent samples. A closed form rather than
    ``scipy.stats.chi2.ppf``: the stream calls it per sample, in both back ends alike.

    Below :data:`CHI2_MIN_DOF` (a window shorter than a tenth of the filter's memory, e.g.
    the first samples of a contact at 7 kHz with a 20 Hz low-pass) the excess is held at its
    value there, so that the excess per degree of freedom keeps growing as ``ν`` falls
    (as χ²'s does; the form itself would turn negative and count the noise as signal)."""
    nu = xp.maximum(nu, CHI2_MIN_DOF)
    c = 2.0 / (9.0 * nu)
    b = 1.0 - c + EXCITATION_Z * xp.sqrt(c)
    return nu * (b * b * b - 1.0)


@jitable
def _dot(a, x, y, z):
    return a[0] * x + a[1] * y + a[2] * z


@jitable
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


@jitable
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@jitable
def line_fit_solve_kernel(sums, count, r0x, r0y, r0z, ax, ay, az, tip, iterations, noise: SensorNoise, corr, xp):
    """Joint contact point, direction and conditioning from the window sums, component-wise.

    Parameters
    ----------
    sums : sequence of 21 floats or arrays
        Window sums of :func:`line_fit_products` (about the anchor ``a``).
    count : int or array
        Samples in the window.
    r0x, r0y, r0z : float or array
        Start point on the skin (the latched point), m; its coordinate along the line is
        kept.
    ax, ay, az : float or array
        Anchor ``r_A`` of the sums, m.
    tip : Fingertip
        For the skin normal and the projection onto the skin (its ``_normal_kernel`` and
        ``_project_kernel``; compiled code passes :class:`softtip.estimator.pipeline.ShapeRecord`).
    iterations : int
        Gauss–Newton steps (each: closed-form direction and offset, then projection).
    noise : SensorNoise
        Per-sample noise of the wrench the sums were made from (or a named tuple with its
        ``force_std`` and ``moment_std``, for compiled code).
    corr : float
        Samples per independent noise sample (1 for white noise; ``1 / g²`` after a filter
        of white-noise gain ``g``), for the margin on the noise excitation and the
        standard deviations.
    xp : namespace
        :data:`softtip.core._xp.NP` or :data:`softtip.core._xp.PY`.

    Returns
    -------
    tuple
        ``(rx, ry, rz, dx, dy, dz, conditioning, angle_std, offset_std, residual)``: the
        point (m), the window's line direction (unit), the conditioning in [0, 1], the
        standard deviations of the line angle (rad) and of the offset across the line (m),
        and the root-mean-square residual of the fit in units of the noise, all at the last
        linearisation point (NaN or inf when undefined).
    """
    variances = noise_variances(noise)
    qq, qf, ff = _without_noise(sums, count, ax, ay, az, variances)
    rx, ry, rz = r0x, r0y, r0z
    dx = dy = dz = cond = angle_std = offset_std = residual = xp.nan  # (iterations ≥ 1: replaced)
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
        u1, u2, root = smallest_eigenvector(p11, p12, p22, xp)
        dx, dy, dz = u1 * t1x + u2 * t2x, u1 * t1y + u2 * t2y, u1 * t1z + u2 * t2z
        ex, ey, ez = _cross(nx, ny, nz, dx, dy, dz)
        s = xp.div(u1 * g1 + u2 * g2, scc)
        # conditioning of (angle, offset): the excitation of τ = e·q (the larger eigenvalue,
        # the noise's expected share already removed) less a margin for the noise's own
        # scatter and for a noise model a little low; e = n × d is (−u2, u1) in the basis
        stt = u2 * u2 * q11 - 2.0 * u1 * u2 * q12 + u1 * u1 * q22
        var = noise_quad(dx, dy, dz, rx, ry, rz, *variances)  # residual noise per sample
        var_t = noise_quad(ex, ey, ez, rx, ry, rz, *variances)  # noise of τ per sample
        k = xp.maximum(count - 1.0, 0.0)
        excess = 0.5 * (p11 + p22) + root - var_t * (corr * _chi2_excess(k / corr, xp) + MODEL_MARGIN * k)
        excess = xp.maximum(excess, 0.0)
        arho = xp.sqrt(xp.maximum(1.0 - xp.div(excess, stt), 0.0))
        cond = xp.div(1.0 - arho, 1.0 + arho)
        # first order, inflated by the noise in τ itself (errors in variables) and by the
        # noise's correlation after a low-pass (the regressors vary slowly against it)
        inflate = corr * (1.0 + xp.div(k * var_t, excess))
        angle_std = xp.sqrt(xp.div(var * inflate, excess))
        offset_std = xp.sqrt(xp.div(var * stt * inflate, scc * excess))
        # the fit's residual: the cost of d, plus the noise's share taken out of the sums
        cost = u1 * u1 * p11 + 2.0 * u1 * u2 * p12 + u2 * u2 * p22 + count * var
        residual = xp.where(count > 2.0, xp.sqrt(xp.div(xp.maximum(cost, 0.0), (count - 2.0) * var)), xp.nan)
        # step across the line; along it, back to the start's coordinate (not observable)
        mx, my, mz = rx + s * ex, ry + s * ey, rz + s * ez
        along = (mx - r0x) * dx + (my - r0y) * dy + (mz - r0z) * dz
        rx, ry, rz = tip._project_kernel(mx - along * dx, my - along * dy, mz - along * dz, xp)
    return rx, ry, rz, dx, dy, dz, cond, angle_std, offset_std, residual
