"""Contact location from a wrench: Bicchi's intrinsic contact sensing (soft-finger model).

Assume the moment about the contact point is a pure spin about the skin normal,
``q = σ n(r)``, and solve ``m = r × f + σ n(r)``, ``S(r) = 0`` for ``r`` and ``σ``
(manual §3.2). Of the two roots the one where the force pushes in (``f · n < 0``) is kept;
a sample with no pushing root on the skin is reported as invalid, not raised.

Closed forms for the sphere (exact to rounding), the capsule (hemisphere, then the cylinder
side) and the axis-aligned ellipsoid (mapped onto the unit sphere); a damped Newton solver
for any :class:`~softtip.core.fingertip.ImplicitSurface`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._vec import cross as _cross
from softtip.core._vec import skew as _skew
from softtip.core._xp import NP
from softtip.core.fingertip import Capsule, Ellipsoid, Fingertip, ImplicitSurface, Sphere, load_fingertip
from softtip.core.mounting import Mounted

__all__ = ["Contact", "SoftFinger", "contact_from_wrench"]


@dataclass(frozen=True)
class Contact:
    """Soft-finger contact solution for a batch of wrenches.

    Attributes
    ----------
    point : array, shape (..., 3)
        Contact point ``r`` on the skin, m (sensor frame). NaN where not ``valid``.
    normal : array, shape (..., 3)
        Outward unit skin normal ``n(r)``.
    sigma : array, shape (...,)
        Spin torque about the normal, ``σ = q · n``, N·m.
    valid : array of bool, shape (...,)
        A root exists on the skin and the force pushes in there (``f · n < 0``).
    """

    point: NDArray[np.float64]
    normal: NDArray[np.float64]
    sigma: NDArray[np.float64]
    valid: NDArray[np.bool_]


# -- closed-form kernels -------------------------------------------------------------------
# Each takes the six wrench components (arrays or floats) and returns
# (rx, ry, rz, nx, ny, nz, sigma, valid).


def sphere_kernel(fx, fy, fz, mx, my, mz, radius, cx, cy, cz, xp):
    """The soft-finger contact on a sphere of ``radius`` (m) centred at ``c`` (m), component-wise: point, normal, ``σ`` and validity."""
    # moment about the centre: m_c = m - c × f
    mx = mx - (cy * fz - cz * fy)
    my = my - (cz * fx - cx * fz)
    mz = mz - (cx * fy - cy * fx)
    r2 = radius * radius
    g = fx * mx + fy * my + fz * mz  # f · m_c
    f2 = fx * fx + fy * fy + fz * fz
    b = r2 * f2 - (mx * mx + my * my + mz * mz)
    g2 = g * g
    disc = xp.sqrt(b * b + 4.0 * r2 * g2)
    # u = k² (k = σ/R) is the positive root of R² u² + b u − g² = 0 and gk = g / k = p · f.
    # With P = (|b| + disc) / 2 (no cancellation): b > 0 gives u = g²/P, gk² = P; b ≤ 0 gives
    # u = P/R², gk² = R²g²/P. Both stay exact as g → 0; the branch is chosen by arithmetic
    # (a 0/1 weight, exact), which is faster than a data-dependent select in numpy.
    big = 0.5 * (xp.abs(b) + disc)
    small = xp.div(g2, big)
    pos = 1.0 * (b > 0.0)
    neg = 1.0 - pos
    u = pos * small + neg * (big / r2)
    gk = -xp.sqrt(pos * big + neg * (r2 * small))
    # the pushing root has p · f = g / k < 0, i.e. k of opposite sign to g
    k = (2.0 * (g < 0.0) - 1.0) * xp.sqrt(u)
    den = k * k + f2
    px = xp.div(k * mx + (fy * mz - fz * my) + gk * fx, den)
    py = xp.div(k * my + (fz * mx - fx * mz) + gk * fy, den)
    pz = xp.div(k * mz + (fx * my - fy * mx) + gk * fz, den)
    valid = xp.logical_and(gk < 0.0, xp.isfinite(gk + px + py + pz))
    inv_r = 1.0 / radius
    return cx + px, cy + py, cz + pz, px * inv_r, py * inv_r, pz * inv_r, k * radius, valid


def _capsule_kernel(fx, fy, fz, mx, my, mz, radius, length, ox, oy, xp):
    # an axis through (ox, oy): solve about that point (m' = m − o × f), then shift back
    mx = mx - oy * fz  # o × f = (oy fz, −ox fz, ox fy − oy fx)
    my = my + ox * fz
    mz = mz - (ox * fy - oy * fx)
    rx, ry, rz, nx, ny, nz, sig, valid = _centred_capsule_kernel(fx, fy, fz, mx, my, mz, radius, length, xp)
    return rx + ox, ry + oy, rz, nx, ny, nz, sig, valid


def _centred_capsule_kernel(fx, fy, fz, mx, my, mz, radius, length, xp):
    # hemisphere first (manual §3.2)
    sx, sy, sz, snx, sny, snz, ssig, sval = sphere_kernel(fx, fy, fz, mx, my, mz, radius, 0.0, 0.0, length, xp)
    on_cap = xp.logical_and(sval, sz >= length)

    # cylinder side x² + y² = R²: m_z fixes the azimuth φ, m_x and m_y give z and σ linearly.
    ft = xp.sqrt(fx * fx + fy * fy)
    s = xp.div(mz, radius * ft)  # sin(α − φ), α the azimuth of the tangential force
    cpsi = -xp.sqrt(1.0 - s * s)  # cos(α − φ) < 0: the pushing root
    cphi = xp.div(fx * cpsi + fy * s, ft)
    sphi = xp.div(fy * cpsi - fx * s, ft)
    det = -ft * cpsi  # = −f · n > 0 when pushing
    ax = mx - radius * sphi * fz
    ay = my + radius * cphi * fz
    cz = xp.div(ax * sphi - cphi * ay, det)
    csig = xp.div(-fy * ay - fx * ax, det)
    cyl_solved = xp.logical_and(det > 0.0, xp.isfinite(cz + csig))
    # a rounding-size margin keeps contacts exactly on the base rim (z = 0)
    tol = 1e-12 * (radius + length)
    on_side = xp.logical_and(cyl_solved, xp.logical_and(cz >= -tol, cz <= length))
    # Near the seam, noise can put the sphere root just below the equator and the cylinder
    # root just above it; the surface is C¹ there, so keep the sphere root.
    seam = xp.logical_and(xp.logical_and(sval, xp.logical_not(on_cap)), xp.logical_and(cyl_solved, cz > length))
    use_cap = xp.logical_or(on_cap, seam)
    use_side = xp.logical_and(xp.logical_not(use_cap), on_side)
    valid = xp.logical_or(use_cap, use_side)
    rx = xp.where(use_cap, sx, radius * cphi)
    ry = xp.where(use_cap, sy, radius * sphi)
    rz = xp.where(use_cap, sz, cz)
    nx = xp.where(use_cap, snx, cphi)
    ny = xp.where(use_cap, sny, sphi)
    nz = xp.where(use_cap, snz, 0.0 * cz)
    sig = xp.where(use_cap, ssig, csig)
    return rx, ry, rz, nx, ny, nz, sig, valid


def _ellipsoid_kernel(fx, fy, fz, mx, my, mz, a, b, c, cx, cy, cz, xp):
    # With p = D s (D = diag(a, b, c)), m_c = p × f + κ D⁻² p becomes the unit-sphere problem
    # D m_c = s × f' + κ s with f' = det(D) D⁻¹ f, since D [f]× D = det(D) [D⁻¹ f]×.
    mx = mx - (cy * fz - cz * fy)
    my = my - (cz * fx - cx * fz)
    mz = mz - (cx * fy - cy * fx)
    sx, sy, sz, _, _, _, kappa, valid = sphere_kernel(
        b * c * fx, a * c * fy, a * b * fz, a * mx, b * my, c * mz, 1.0, 0.0, 0.0, 0.0, xp
    )
    gx, gy, gz = sx / a, sy / b, sz / c  # ∝ gradient of S at p
    gnorm = xp.sqrt(gx * gx + gy * gy + gz * gz)
    # f · n has the sign of f' · s, so the sphere's root choice carries over.
    return (
        cx + a * sx,
        cy + b * sy,
        cz + c * sz,
        xp.div(gx, gnorm),
        xp.div(gy, gnorm),
        xp.div(gz, gnorm),
        kappa * gnorm,
        valid,
    )


class SoftFinger(NamedTuple):
    """The soft-finger solution, component-wise (floats or arrays of one shape), sensor frame."""

    rx: Any  #: contact point, m
    ry: Any
    rz: Any
    nx: Any  #: outward unit normal there
    ny: Any
    nz: Any
    sigma: Any  #: spin torque about the normal, N·m
    valid: Any  #: a pushing solution was found

    @property
    def point(self) -> tuple:
        """``(rx, ry, rz)``."""
        return self[0], self[1], self[2]

    @property
    def normal(self) -> tuple:
        """``(nx, ny, nz)``."""
        return self[3], self[4], self[5]


def contact_kernel(tip: Fingertip, fx, fy, fz, mx, my, mz, xp=NP):
    """Component-wise soft-finger contact for ``tip`` (arrays with ``NP``, floats with ``PY``).

    Returns ``(rx, ry, rz, nx, ny, nz, sigma, valid)``.
    """
    own = getattr(tip, "_contact_kernel", None)
    if own is not None:  # shapes with their own solver (softtip.core.mesh.MeshFingertip)
        return own(fx, fy, fz, mx, my, mz, xp)
    if isinstance(tip, Mounted):
        # the shape's own solution for the wrench in its frame, mapped back to the sensor frame
        rx, ry, rz, nx, ny, nz, sigma, valid = contact_kernel(tip.tip, *tip.wrench_in_tip_frame(fx, fy, fz, mx, my, mz), xp=xp)
        return (*tip._from_tip(rx, ry, rz), *tip._rotate(nx, ny, nz), sigma, valid)
    if isinstance(tip, Capsule):
        return _capsule_kernel(fx, fy, fz, mx, my, mz, tip.radius, tip.length, *tip.axis_offset, xp)
    if isinstance(tip, Sphere):
        return sphere_kernel(fx, fy, fz, mx, my, mz, tip.radius, *tip.center, xp)
    if isinstance(tip, Ellipsoid):
        return _ellipsoid_kernel(fx, fy, fz, mx, my, mz, *tip.semi_axes, *tip.center, xp)
    if isinstance(tip, ImplicitSurface):
        w = np.stack(np.broadcast_arrays(fx, fy, fz, mx, my, mz), axis=-1).astype(float)
        c = _implicit_contact(w, tip)
        out = (*np.moveaxis(c.point, -1, 0), *np.moveaxis(c.normal, -1, 0), c.sigma, c.valid)
        if xp is NP:
            return out
        return tuple(bool(v) if v.dtype == bool else float(v) for v in out)
    raise TypeError(f"no contact solver for {type(tip).__name__}")


# -- general implicit surfaces ---------------------------------------------------------------


def _wrench_axis_start(f: NDArray, m: NDArray, tip: ImplicitSurface, n_grid: int = 129) -> NDArray:
    """Where the wrench axis enters the skin along +f (the pushing side), shape (N, 3)."""
    f2 = np.sum(f * f, axis=-1, keepdims=True)
    fhat = f / np.sqrt(f2)
    base = _cross(f, m) / f2  # point of the wrench axis closest to the origin
    centre, radius = tip.bounding_sphere
    lam_c = np.sum((centre - base) * fhat, axis=-1, keepdims=True)
    closest = base + lam_c * fhat
    # grid along the axis over the bounding sphere; S goes from + to − where f pushes in
    lam = lam_c + radius * np.linspace(-1.05, 1.05, n_grid)
    pts = base[:, None, :] + lam[..., None] * fhat[:, None, :]
    s = np.asarray(tip.function(pts), dtype=float)
    entering = (s[:, :-1] > 0.0) & (s[:, 1:] <= 0.0)
    has = entering.any(axis=1)
    i = np.argmax(entering, axis=1)
    rows = np.arange(len(f))
    s0, s1 = s[rows, i], s[rows, i + 1]
    l0, l1 = lam[rows, i], lam[rows, i + 1]
    frac = s0 / np.where(s0 - s1 == 0.0, 1.0, s0 - s1)
    lam_hit = l0 + frac * (l1 - l0)
    start = base + lam_hit[:, None] * fhat
    # an axis that misses the skin starts from its point nearest the skin's centre
    start = np.where(has[:, None], start, closest)
    return tip.project(start)


def _kappa_at(tip: ImplicitSurface, r: NDArray, f: NDArray, m: NDArray) -> NDArray:
    """Least-squares ``κ`` in ``m − r × f = κ ∇S(r)`` at a starting point."""
    g = tip.grad(r)
    return np.sum(g * (m - _cross(r, f)), axis=-1) / np.sum(g * g, axis=-1)


def _levenberg_marquardt(f, m, r, kappa, tip: ImplicitSurface, max_iter: int, tol: float):
    """Levenberg–Marquardt iterations on the samples still active; returns r, κ, converged."""
    fnorm = np.sqrt(np.sum(f * f, axis=-1))
    scale = tip.bounding_sphere[1]
    wscale = fnorm * scale  # the surface row is scaled to N·m

    def residual(idx, r, kappa):
        g = tip.grad(r)
        gn = np.linalg.norm(g, axis=-1)
        rm = m[idx] - _cross(r, f[idx]) - kappa[:, None] * g
        rs = np.asarray(tip.function(r), dtype=float) * wscale[idx] / gn
        return np.concatenate((rm, rs[:, None]), axis=-1), g, gn

    idx = np.arange(len(f))
    res, g, gn = residual(idx, r, kappa)
    cost = np.sum(res * res, axis=-1)
    mu = np.full(len(f), 1e-6)
    r, kappa = r.copy(), kappa.copy()
    for _ in range(max_iter):
        act = np.flatnonzero(cost > (tol * wscale) ** 2)
        if act.size == 0:
            break
        ra, ka, ga, gna = r[act], kappa[act], g[act], gn[act]
        jac = np.zeros((act.size, 4, 4))
        jac[:, :3, :3] = _skew(f[act]) - ka[:, None, None] * tip.hess(ra)  # ∂(f × r − κ∇S)/∂r
        jac[:, :3, 3] = -ga
        jac[:, 3, :3] = ga * (wscale[act] / gna)[:, None]
        jtj = np.einsum("nki,nkj->nij", jac, jac)
        jtr = np.einsum("nki,nk->ni", jac, res[act])
        diag = np.maximum(np.diagonal(jtj, axis1=1, axis2=2), 1e-30)
        step = np.linalg.solve(jtj + mu[act, None, None] * (np.eye(4) * diag[:, None, :]), -jtr[..., None])[..., 0]
        r_new, k_new = ra + step[:, :3], ka + step[:, 3]
        res_new, g_new, gn_new = residual(act, r_new, k_new)
        cost_new = np.sum(res_new * res_new, axis=-1)
        better = cost_new < cost[act]
        b = act[better]
        r[b], kappa[b], res[b], g[b], gn[b], cost[b] = (
            r_new[better], k_new[better], res_new[better], g_new[better], gn_new[better], cost_new[better]
        )
        mu[act] = np.where(better, np.maximum(mu[act] * 0.1, 1e-12), np.minimum(mu[act] * 10.0, 1e8))
    converged = cost <= (1e-9 * wscale) ** 2
    return r, kappa, g, gn, converged


def _implicit_contact(w: NDArray, tip: ImplicitSurface, max_iter: int = 60, tol: float = 1e-13) -> Contact:
    """Damped Newton (Levenberg–Marquardt) on ``[m − r × f − κ ∇S(r); S(r)] = 0``.

    The unknowns are ``r`` and ``κ = σ / |∇S|``. Started where the wrench axis enters the
    skin; samples that end on no root or on the pulling one are restarted once from the
    closed-form solution for the skin's bounding sphere, projected onto the skin (a large
    spin about a small force puts the wrench axis far from the contact).
    """
    shape = w.shape[:-1]
    w = w.reshape(-1, 6)
    f2 = np.sum(w[:, :3] * w[:, :3], axis=-1)
    ok = f2 > 0.0
    f = np.where(ok[:, None], w[:, :3], np.array([0.0, 0.0, -1.0]))
    m = w[:, 3:]

    r = _wrench_axis_start(f, m, tip)
    r, kappa, g, gn, conv = _levenberg_marquardt(f, m, r, _kappa_at(tip, r, f, m), tip, max_iter, tol)
    good = conv & (np.sum(f * g, axis=-1) < 0.0)
    retry = np.flatnonzero(~good)
    if retry.size:
        (cx, cy, cz), radius = tip.bounding_sphere
        fr, mr = f[retry], m[retry]
        sx, sy, sz = sphere_kernel(*fr.T, *mr.T, radius, cx, cy, cz, NP)[:3]
        r1 = tip.project(np.stack((sx, sy, sz), axis=-1))
        r1, k1, g1, gn1, conv1 = _levenberg_marquardt(fr, mr, r1, _kappa_at(tip, r1, fr, mr), tip, max_iter, tol)
        better = conv1 & (np.sum(fr * g1, axis=-1) < 0.0)
        sel = retry[better]
        r[sel], kappa[sel], g[sel], gn[sel] = r1[better], k1[better], g1[better], gn1[better]
        good[sel] = True
    normal = g / gn[:, None]
    valid = ok & good
    point = np.where(valid[:, None], r, np.nan)
    normal = np.where(valid[:, None], normal, np.nan)
    sigma = np.where(valid, kappa * gn, np.nan)
    return Contact(point.reshape(*shape, 3), normal.reshape(*shape, 3), sigma.reshape(shape), valid.reshape(shape))


def contact_from_wrench(wrench: ArrayLike, tip: Fingertip | str) -> Contact:
    """Contact point, normal and spin of a soft-finger contact from the wrench (manual §3.2).

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m) in the sensor frame, bias removed.
    tip : Fingertip or str
        The fingertip, or a preset name / TOML path for :func:`~softtip.core.fingertip.load_fingertip`.

    Returns
    -------
    Contact
        ``point`` (..., 3) m, ``normal`` (..., 3), ``sigma`` (...) N·m, ``valid`` (...).
        Samples without a pushing root on the skin (or with zero force) are not valid and
        carry NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from softtip import Sphere, contact_from_wrench
    >>> tip = Sphere(0.016)
    >>> c = contact_from_wrench([0.0, 0.0, -2.0, 0.0, 0.0, 0.0], tip)   # press on the top
    >>> np.round(c.point * 1e3, 6).tolist(), bool(c.valid)
    ([0.0, 0.0, 16.0], True)
    """
    tip = load_fingertip(tip)
    w = np.asarray(wrench, dtype=float)
    if w.shape[-1:] != (6,):
        raise ValueError(f"wrench must have shape (..., 6), got {w.shape}")
    if isinstance(tip, ImplicitSurface):
        return _implicit_contact(w, tip)
    shape = w.shape[:-1]
    w2 = w.reshape(-1, 6)
    n = len(w2)
    point, normal = np.empty((n, 3)), np.empty((n, 3))
    sigma, valid = np.empty(n), np.empty(n, dtype=bool)
    for block, out in _blocks(tip, [w2[:, i] for i in range(6)]):
        for i in range(3):
            point[block, i], normal[block, i] = out[i], out[3 + i]
        sigma[block], valid[block] = out[6], out[7]
    invalid = ~valid
    if invalid.any():
        point[invalid] = np.nan
        normal[invalid] = np.nan
        sigma[invalid] = np.nan
    return Contact(point.reshape(*shape, 3), normal.reshape(*shape, 3), sigma.reshape(shape), valid.reshape(shape))


#: Samples per block in batch kernels: the temporaries of a block stay in cache, which
#: doubles the throughput over whole-array evaluation.
CHUNK = 16384


def _blocks(tip: Fingertip, comps: list[NDArray]):
    """Yield ``(block, kernel outputs)`` over cache-sized blocks of 1-D component arrays.

    Each block's components are copied to contiguous arrays first (the columns of an
    ``(N, 6)`` wrench are strided), so the kernel's temporaries stay in cache.
    """
    n = len(comps[0])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for start in range(0, n, CHUNK):
            block = slice(start, start + CHUNK)
            yield block, contact_kernel(tip, *(np.ascontiguousarray(c[block], dtype=float) for c in comps), xp=NP)


def contact_arrays(tip: Fingertip, fx, fy, fz, mx, my, mz) -> tuple[NDArray, ...]:
    """:func:`contact_kernel` over 1-D component arrays of any length, in cache-sized blocks.

    Returns the 8 arrays as a :class:`SoftFinger`; invalid samples are not masked.
    """
    comps = [np.asarray(c, dtype=float) for c in (fx, fy, fz, mx, my, mz)]
    n = len(comps[0])
    out = [np.empty(n) for _ in range(7)] + [np.empty(n, dtype=bool)]
    for block, res in _blocks(tip, comps):
        for dst, src in zip(out, res):
            dst[block] = src
    return SoftFinger(*out)
