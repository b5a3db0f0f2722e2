"""A general skin ``S(r) = 0`` given as Python callables, and its contact solver.

:class:`ImplicitSurface` takes ``S`` and its gradient as functions of points; the soft-finger
contact ``m = r × f + σ n(r)``, ``S(r) = 0`` is solved by damped Newton iterations
(Levenberg–Marquardt) started where the wrench's central axis enters the skin. The shape has
no file form (its ``S`` is code) and no simulator skin.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._vec import cross as _cross
from softtip.core._vec import skew as _skew
from softtip.core._xp import NP, PY
from softtip.core.shape import Contact, Fingertip, positive, sphere_kernel, vec3

__all__ = ["ImplicitSurface"]


@dataclass(frozen=True)
class ImplicitSurface(Fingertip):
    """A general skin ``S(r) = 0`` given as callables.

    Parameters
    ----------
    function : callable
        ``S(points) -> values``: points shape ``(..., 3)`` (m) to shape ``(...,)``; negative
        inside, positive outside.
    gradient : callable
        ``∇S(points) -> (..., 3)``.
    center, radius : array-like (3,), float
        A sphere (m) that contains the whole skin; it bounds the search for the contact
        solver's starting point.
    hessian : callable, optional
        ``(..., 3) -> (..., 3, 3)``. Central differences of ``gradient`` when absent.
    """

    function: Callable[[NDArray], NDArray]
    gradient: Callable[[NDArray], NDArray]
    center: tuple[float, float, float]
    radius: float
    hessian: Callable[[NDArray], NDArray] | None = field(default=None)
    kind: ClassVar[str] = "implicit"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", vec3(self.center, "center"))
        object.__setattr__(self, "radius", positive(self.radius, "radius"))

    # The implicit surface works on arrays only; scalar (stream) calls go through arrays.
    def _surface_kernel(self, x, y, z, xp):
        v = np.asarray(self.function(np.stack(np.broadcast_arrays(x, y, z), axis=-1)), dtype=float)
        return float(v) if xp is PY else v

    def grad(self, points: ArrayLike) -> NDArray[np.float64]:
        """``∇S`` at ``points``, shape ``(..., 3)``."""
        return np.asarray(self.gradient(np.asarray(points, dtype=float)), dtype=float)

    def hess(self, points: ArrayLike) -> NDArray[np.float64]:
        """Hessian of ``S`` at ``points``, shape ``(..., 3, 3)`` (central differences by default)."""
        p = np.asarray(points, dtype=float)
        if self.hessian is not None:
            return np.asarray(self.hessian(p), dtype=float)
        step = 1e-6 * self.radius
        cols = []
        for i in range(3):
            e = np.zeros(3)
            e[i] = step
            cols.append((self.grad(p + e) - self.grad(p - e)) / (2.0 * step))
        h = np.stack(cols, axis=-1)
        return 0.5 * (h + np.swapaxes(h, -1, -2))

    def _normal_kernel(self, x, y, z, xp):
        p = np.stack(np.broadcast_arrays(x, y, z), axis=-1)
        g = self.grad(p)
        n = g / np.linalg.norm(g, axis=-1, keepdims=True)
        if xp is PY:
            return float(n[0]), float(n[1]), float(n[2])
        return n[..., 0], n[..., 1], n[..., 2]

    def _project_kernel(self, x, y, z, xp):
        p = np.stack(np.broadcast_arrays(x, y, z), axis=-1).astype(float)
        for _ in range(20):
            s = np.asarray(self.function(p), dtype=float)
            g = self.grad(p)
            step = (s / np.sum(g * g, axis=-1))[..., None] * g
            p = p - step
            if np.all(np.abs(s) < 1e-14 * max(1.0, self.radius)):
                break
        if xp is PY:
            return float(p[0]), float(p[1]), float(p[2])
        return p[..., 0], p[..., 1], p[..., 2]

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return np.array(self.center), self.radius

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp=NP):
        # the general solver works on arrays: floats (the stream) go through one-sample arrays
        w = np.stack(np.broadcast_arrays(fx, fy, fz, mx, my, mz), axis=-1).astype(float)
        c = _implicit_contact(w, self)
        out = (*np.moveaxis(c.point, -1, 0), *np.moveaxis(c.normal, -1, 0), c.sigma, c.valid)
        if xp is NP:
            return out
        return tuple(bool(v) if v.dtype == bool else float(v) for v in out)

    def to_toml(self) -> str:
        raise ValueError("an implicit surface given as Python callables has no TOML form")


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
    # a root to 1e-6 of |f| × the tip's size (tens of nm on a fingertip): the iterations aim far
    # tighter (``tol``), but on a seam of a piecewise surface (a capsule's cap on its cylinder)
    # the Hessian changes across it and they can stall a few nm from the root
    converged = cost <= (1e-6 * wscale) ** 2
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
