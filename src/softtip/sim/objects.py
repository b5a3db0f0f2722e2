"""Rigid touched objects as signed distance functions with analytic normals.

Every object is described in its own **contact frame**: the origin is the point of the
object that first touches the fingertip, ``+x'`` is the object's outward normal there (it
points into the fingertip when the object is placed), and ``+z'`` is the object's *line
direction* (edge, axis or fringe tangent) where one exists. A :class:`~softtip.sim.pose.Pose`
places that frame in the sensor frame. Lengths in metres, angles in radians.

Objects (all convex, which the contact model relies on: a ray leaving an interior point
crosses the boundary exactly once):

* :class:`HalfSpace` — a large flat surface (``x' <= 0``); no line direction.
* :class:`Plate` — the cut edge of a thin plate: the half-infinite slab
  ``|y'| <= thickness/2, x' <= 0``, edge along ``z'``, corners sharp or rounded.
* :class:`Wedge` — a straight edge of apex angle ``apex_angle`` and tip radius
  ``tip_radius`` (the 2004 paper's cube edge is 90°), bisector along ``-x'``.
* :class:`Cylinder` — the side of an infinite solid cylinder of ``diameter`` with its axis
  along ``z'`` (a stick is a thin cylinder, see :func:`stick`).
* :class:`CylinderRim` — the fringe of a solid cylinder's flat end (paper IV-E): the sharp
  circular rim where the side meets the bottom face; ``z'`` is the rim tangent.

Signed distances are negative inside. The plate, wedge and cylinder are extrusions of a 2-D
*rounded convex polygon* (inner polygon ⊕ disc of radius ``rho``), handled by one exact
routine for the distance, the normal and the ray exit.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.sim.pose import Pose

__all__ = [
    "RigidObject",
    "HalfSpace",
    "Plate",
    "Wedge",
    "Cylinder",
    "CylinderRim",
    "stick",
    "make_object",
    "OBJECT_KINDS",
]

_TINY = 1e-30
# Numerical search of RigidObject.segment_min_local (objects without a closed form):
# at most this many steps, stopped once the minimum is known to _SEGMENT_TOL, m.
_SEGMENT_STEPS = 30
_SEGMENT_TOL = 1e-9


def _points(points: ArrayLike) -> NDArray[np.float64]:
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must have shape (..., 3), got {p.shape}")
    return p


class RigidObject(abc.ABC):
    """Base class: a convex rigid body posed in the sensor frame by ``self.pose``.

    Subclasses implement the ``*_local`` methods on arrays of object-frame points of shape
    ``(M, 3)``; the public methods take sensor-frame arrays of any leading shape.
    """

    kind: ClassVar[str] = ""
    pose: Pose

    # -- local (object-frame) kernels ---------------------------------------------------
    @abc.abstractmethod
    def sdf_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Signed distance (m) at object-frame points ``q`` (M, 3); negative inside."""

    @abc.abstractmethod
    def normal_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Unit gradient of the signed distance (outward normal of the nearest surface), (M, 3)."""

    def sdf_normal_local(self, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``sdf_local(q), normal_local(q)`` (subclasses may share the work)."""
        return self.sdf_local(q), self.normal_local(q)

    @abc.abstractmethod
    def exit_local(
        self, q: NDArray[np.float64], u: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Where the ray ``q + s u`` (s >= 0) from an interior point leaves the object.

        Returns ``s_exit`` (M,) in units of ``|u|`` (``inf`` if it never leaves) and the
        outward unit normal at the exit point (M, 3). Points outside give ``s_exit = 0``
        or a meaningless value; callers pass interior points only.
        """

    def line_direction_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Unit line direction (edge/axis/fringe tangent) near ``q``, (M, 3); NaN if none."""
        return np.broadcast_to(np.array([0.0, 0.0, 1.0]), q.shape).copy()

    def segment_min_local(
        self, q: NDArray[np.float64], u: NDArray[np.float64], length: float, sdf0: NDArray[np.float64] | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Deepest point of the segments ``q + s u``, ``0 <= s <= length`` (object frame).

        ``sdf0``, optional: the signed distance at ``q``, if already known.
        Returns ``s_min`` (M,) and the signed distance there (M,): the minimum of the
        signed distance along each segment (for a segment crossing the object, its deepest
        point; otherwise its closest approach). Subclasses override this with closed
        forms; the default is a numerical search, valid because the signed distance of a
        convex object is convex along a line: a bracket ``[lo, hi]`` (slope < 0 at ``lo``,
        >= 0 at ``hi``) refined at the intersection of the tangents at its ends (exact in
        one step at a kink between two flat faces), stopped once the best value is within
        ``_SEGMENT_TOL`` of the tangents' lower bound.
        """
        m = len(q)
        s0 = np.zeros(m)
        f0 = self.sdf_local(q) if sdf0 is None else np.array(sdf0, dtype=float)
        d0 = np.einsum("ij,ij->i", self.normal_local(q), u)
        p1 = q + length * u
        f1 = self.sdf_local(p1)
        d1 = np.einsum("ij,ij->i", self.normal_local(p1), u)
        lo, hi = s0, np.full(m, float(length))
        f_lo, d_lo, f_hi, d_hi = f0, d0, f1, d1
        act = np.flatnonzero((d0 < 0.0) & (d1 >= 0.0))
        for _ in range(_SEGMENT_STEPS):
            if len(act) == 0:
                break
            a0, a1 = lo[act], hi[act]
            den = d_lo[act] - d_hi[act]
            with np.errstate(divide="ignore", invalid="ignore"):
                sx = (f_hi[act] - f_lo[act] + d_lo[act] * a0 - d_hi[act] * a1) / den
            lower = f_lo[act] + d_lo[act] * (sx - a0)
            width = a1 - a0
            sx = np.where(np.isfinite(sx), np.clip(sx, a0 + 1e-3 * width, a1 - 1e-3 * width), 0.5 * (a0 + a1))
            px = q[act] + sx[:, None] * u[act]
            fx = self.sdf_local(px)
            dx = np.einsum("ij,ij->i", self.normal_local(px), u[act])
            neg = dx < 0.0
            lo[act] = np.where(neg, sx, a0)
            f_lo[act] = np.where(neg, fx, f_lo[act])
            d_lo[act] = np.where(neg, dx, d_lo[act])
            hi[act] = np.where(neg, a1, sx)
            f_hi[act] = np.where(neg, f_hi[act], fx)
            d_hi[act] = np.where(neg, d_hi[act], dx)
            best = np.minimum(f_lo[act], f_hi[act])
            done = (best - np.where(np.isfinite(lower), lower, -np.inf) <= _SEGMENT_TOL) | (hi[act] - lo[act] <= _SEGMENT_TOL)
            act = act[~done]
        first = f_lo <= f_hi
        return np.where(first, lo, hi), np.where(first, f_lo, f_hi)

    @abc.abstractmethod
    def params(self) -> dict:
        """Geometric parameters, SI, JSON-ready."""

    # -- sensor-frame API ---------------------------------------------------------------
    def with_pose(self, pose: Pose) -> RigidObject:
        """A copy of the object placed at ``pose``."""
        return replace(self, pose=pose)  # type: ignore[type-var]

    def sdf(self, points: ArrayLike) -> NDArray[np.float64]:
        """Signed distance (m) at sensor-frame ``points`` (..., 3), shape (...,)."""
        p = _points(points)
        q = self.pose.inverse_apply(p.reshape(-1, 3))
        return self.sdf_local(q).reshape(p.shape[:-1])

    def normal(self, points: ArrayLike) -> NDArray[np.float64]:
        """Outward unit normal of the nearest object surface (sensor frame), shape (..., 3)."""
        p = _points(points)
        q = self.pose.inverse_apply(p.reshape(-1, 3))
        return self.pose.rotate(self.normal_local(q)).reshape(p.shape)

    def ray_exit(self, points: ArrayLike, directions: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Exit distance and exit normal of rays from interior sensor-frame points.

        Parameters
        ----------
        points, directions : array-like, shape (..., 3)
            Ray origins (m, inside the object) and directions (any length).

        Returns
        -------
        s : array, shape (...,)
            Ray parameter at the exit (m when ``directions`` are unit).
        normal : array, shape (..., 3)
            Outward object normal at the exit point, sensor frame.
        """
        p = _points(points)
        d = np.broadcast_to(_points(directions), p.shape)
        q = self.pose.inverse_apply(p.reshape(-1, 3))
        u = self.pose.inverse_rotate(d.reshape(-1, 3))
        s, n = self.exit_local(q, u)
        return s.reshape(p.shape[:-1]), self.pose.rotate(n).reshape(p.shape)

    def line_direction(self, points: ArrayLike) -> NDArray[np.float64]:
        """Unit line direction of the object near ``points`` (sensor frame), (..., 3); NaN if none.

        The direction is an axis: ``d`` and ``-d`` are the same.
        """
        p = _points(points)
        q = self.pose.inverse_apply(p.reshape(-1, 3))
        return self.pose.rotate(self.line_direction_local(q)).reshape(p.shape)

    def describe(self) -> dict:
        """Kind, parameters and pose, JSON-ready (SI units)."""
        return {"kind": self.kind, **self.params(), "pose": self.pose.as_dict()}


# -- 2-D rounded convex polygons (extruded along z') -------------------------------------
def _dot(cx: float, cy: float, x: NDArray[np.float64], y: NDArray[np.float64]):
    # cx x + cy y, skipping zero terms (the faces and edges here are mostly axis-aligned)
    if cy == 0.0:
        return cx * x
    if cx == 0.0:
        return cy * y
    return cx * x + cy * y


@dataclass(frozen=True, eq=False)
class _Profile:
    """Inner convex polygon ``{p : normals @ p <= offsets}`` dilated by a disc of ``rho``.

    ``vertices`` (J, 2) are the polygon's corners; ``edges`` (J, 2, 2) the unit directions
    from each corner along its two edges (zeros for an isolated point, whose normal cone is
    the whole plane). The kernels take the two coordinates as separate arrays, stack the
    (at most three) faces and loop over the (at most two) corners: they run on the few
    hundred points of one contact evaluation, where the number of numpy calls matters
    more than their size.
    """

    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    vertices: NDArray[np.float64]
    edges: NDArray[np.float64]
    rho: float

    @cached_property
    def _face_cols(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        return self.normals[:, :1].copy(), self.normals[:, 1:].copy(), self.offsets[:, None].copy()

    @cached_property
    def _pairs(self) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        j, k = np.triu_indices(len(self.offsets), 1)
        return j, k

    @cached_property
    def _corners(self) -> tuple[tuple[float, float, float, float, float, float, bool], ...]:
        # (vx, vy, edge a, edge b, whether the normal cone is the whole plane)
        return tuple(
            (float(v[0]), float(v[1]), float(e[0, 0]), float(e[0, 1]), float(e[1, 0]), float(e[1, 1]), not np.any(e))
            for v, e in zip(self.vertices, self.edges)
        )

    def _faces_at(self, x, y):
        nx, ny, o = self._face_cols
        return nx * x + ny * y - o  # (F, M)

    def _inner(self, x, y, grad: bool):
        # signed distance to the inner polygon (and its gradient): the largest face function,
        # replaced by the distance to a corner inside that corner's normal cone
        m = x.shape[0]
        gx = gy = None
        if len(self.offsets):
            a = self._faces_at(x, y)
            if grad:
                k = a.argmax(axis=0)
                d = a[k, np.arange(m)]
                gx, gy = self.normals[k, 0], self.normals[k, 1]
            else:
                d = a.max(axis=0)
        else:
            d = np.full(m, -np.inf)
            if grad:
                gx, gy = np.zeros(m), np.zeros(m)
        for vx, vy, ax, ay, bx, by, everywhere in self._corners:
            wx, wy = x - vx, y - vy
            dist = np.sqrt(wx * wx + wy * wy)
            if everywhere:
                d = dist
                if grad:
                    gx, gy = np.ones(m), np.zeros(m)
                    np.divide(wx, dist, out=gx, where=dist > 0.0)
                    np.divide(wy, dist, out=gy, where=dist > 0.0)
                continue
            cone = (_dot(ax, ay, wx, wy) <= 0.0) & (_dot(bx, by, wx, wy) <= 0.0)
            np.copyto(d, dist, where=cone)
            if grad:
                np.copyto(gx, 1.0, where=cone)
                np.copyto(gy, 0.0, where=cone)
                ok = cone & (dist > 0.0)
                np.divide(wx, dist, out=gx, where=ok)
                np.divide(wy, dist, out=gy, where=ok)
        return d, gx, gy

    def sdf(self, x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
        return self._inner(x, y, False)[0] - self.rho

    def sdf_grad(self, x: NDArray[np.float64], y: NDArray[np.float64]):
        """Signed distance and its (unit) gradient components ``(d, gx, gy)``."""
        d, gx, gy = self._inner(x, y, True)
        return d - self.rho, gx, gy

    def exit(self, x, y, ux, uy):
        """Ray exit ``s`` and the exit normal ``(nx, ny)`` of rays from interior points."""
        m = x.shape[0]
        rho = self.rho
        if len(self.offsets):
            nx, ny, o = self._face_cols
            nu = nx * ux + ny * uy
            sk = np.full(nu.shape, np.inf)
            np.divide(o + rho - (nx * x + ny * y), nu, out=sk, where=nu > 1e-15)
            k = sk.argmin(axis=0)  # (a ray that never leaves: the first face's normal)
            s = sk[k, np.arange(m)]
            nxo, nyo = self.normals[k, 0], self.normals[k, 1]
        else:
            s, nxo, nyo = np.full(m, np.inf), np.zeros(m), np.zeros(m)
        if rho > 0.0:
            a = ux * ux + uy * uy
            for vx, vy, ax, ay, bx, by, everywhere in self._corners:
                wx, wy = x - vx, y - vy
                b = wx * ux + wy * uy
                c = wx * wx + wy * wy - rho * rho
                disc = b * b - a * c
                ok = (a > _TINY) & (disc >= 0.0)
                s2 = np.full(m, np.inf)
                np.divide(np.sqrt(np.maximum(disc, 0.0)) - b, a, out=s2, where=ok)
                s2 = np.maximum(s2, 0.0)
                s2f = np.where(ok, s2, 0.0)
                ex, ey = wx + s2f * ux, wy + s2f * uy
                better = ok & (s2 < s)
                if not everywhere:
                    better &= (_dot(ax, ay, ex, ey) <= 0.0) & (_dot(bx, by, ex, ey) <= 0.0)
                s = np.where(better, s2, s)
                nxo = np.where(better, ex / rho, nxo)
                nyo = np.where(better, ey / rho, nyo)
        return np.maximum(s, 0.0), nxo, nyo

    def segment_min(self, x, y, ux, uy, length: float, sdf0=None):
        """Minimum of the signed distance along ``(x, y) + s (ux, uy)``, ``0 <= s <= length``.

        Returns ``(s, sdf)``; ``sdf0``, if given, is the signed distance at ``s = 0``.
        Exact, no search: let ``g(s)`` be the largest face function (a lower bound of the
        polygon's signed distance, equal to it inside the polygon). ``g`` is convex and
        piecewise linear, so its minimum over the segment is at an end or where two face
        functions cross. If that minimum is <= 0 the segment enters the polygon there and
        it is the answer. Otherwise the segment misses the polygon, and the closest pair of
        two disjoint convex polygons (the segment is one) involves a vertex of one of
        them: an end of the segment, or a corner of the polygon and its foot on the
        segment. The dilation by ``rho`` subtracts a constant.
        """
        L = float(length)
        m = x.shape[0]
        r = np.arange(m)
        inside = None
        if len(self.offsets):
            nx, ny, _ = self._face_cols
            a = self._faces_at(x, y)
            b = nx * ux + ny * uy
            j, k = self._pairs
            cand = np.zeros((2 + len(j), m))
            cand[1] = L
            if len(j):
                den = b[j] - b[k]
                np.divide(a[k] - a[j], den, out=cand[2:], where=np.abs(den) > 1e-15)
                np.clip(cand[2:], 0.0, L, out=cand[2:])
            val = (a[None, :, :] + cand[:, None, :] * b[None, :, :]).max(axis=1)  # (C, M)
            kc = val.argmin(axis=0)
            g_s, g_f = cand[kc, r], val[kc, r]
            inside = g_f <= 1e-12  # (rounding: a plate with fully rounded corners has no interior)
            if inside.all():
                return g_s, g_f - self.rho
        # ends of the segment (exact signed distance), then the corners' feet on it
        d0 = self._inner(x, y, False)[0] if sdf0 is None else np.asarray(sdf0) + self.rho
        d1 = self._inner(x + L * ux, y + L * uy, False)[0]
        far = d1 < d0
        best_s = far * L
        best_f = np.where(far, d1, d0)
        if len(self._corners):
            uu = ux * ux + uy * uy
            inv = np.zeros(m)
            np.divide(1.0, uu, out=inv, where=uu > _TINY)
            for vx, vy, *_ in self._corners:
                wx, wy = x - vx, y - vy
                sc = np.clip(-(wx * ux + wy * uy) * inv, 0.0, L)
                ex, ey = wx + sc * ux, wy + sc * uy
                dist = np.sqrt(ex * ex + ey * ey)
                better = dist < best_f
                np.copyto(best_s, sc, where=better)
                np.copyto(best_f, dist, where=better)
        if inside is not None:
            np.copyto(best_s, g_s, where=inside)
            np.copyto(best_f, g_f, where=inside)
        return best_s, best_f - self.rho


class _Extruded(RigidObject):
    """An object whose cross-section in the x'y' plane is a :class:`_Profile`, infinite in z'."""

    @property
    @abc.abstractmethod
    def _profile(self) -> _Profile:
        """The cross-section (subclasses cache it)."""

    def sdf_local(self, q):
        return self._profile.sdf(q[:, 0], q[:, 1])

    def normal_local(self, q):
        _, gx, gy = self._profile.sdf_grad(q[:, 0], q[:, 1])
        return np.column_stack((gx, gy, np.zeros(len(q))))

    def sdf_normal_local(self, q):
        d, gx, gy = self._profile.sdf_grad(q[:, 0], q[:, 1])
        return d, np.column_stack((gx, gy, np.zeros(len(q))))

    def exit_local(self, q, u):
        s, nx, ny = self._profile.exit(q[:, 0], q[:, 1], u[:, 0], u[:, 1])
        return s, np.column_stack((nx, ny, np.zeros(len(q))))

    def segment_min_local(self, q, u, length, sdf0=None):
        return self._profile.segment_min(q[:, 0], q[:, 1], u[:, 0], u[:, 1], length, sdf0)


def _positive(value: float, name: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


@dataclass(frozen=True, eq=False)
class HalfSpace(_Extruded):
    """A large flat surface: the half-space ``x' <= 0`` (outward normal ``+x'``)."""

    pose: Pose = field(default_factory=Pose.identity)
    kind: ClassVar[str] = "plane"

    @cached_property
    def _profile(self) -> _Profile:
        return _Profile(np.array([[1.0, 0.0]]), np.zeros(1), np.zeros((0, 2)), np.zeros((0, 2, 2)), 0.0)

    def line_direction_local(self, q):
        return np.full(q.shape, np.nan)

    def params(self) -> dict:
        return {}


@dataclass(frozen=True, eq=False)
class Plate(_Extruded):
    """Cut edge of a thin plate: ``|y'| <= thickness/2``, ``x' <= 0``; the edge runs along ``z'``.

    Parameters
    ----------
    thickness : float
        Plate thickness, m.
    edge_radius : float
        Radius of the two rounded corners of the cut, m, ``0 <= edge_radius <= thickness/2``
        (0: sharp cut, the papers' plates; ``thickness/2``: fully rounded edge).
    pose : Pose
        Placement of the contact frame in the sensor frame.
    """

    thickness: float
    edge_radius: float = 0.0
    pose: Pose = field(default_factory=Pose.identity)
    kind: ClassVar[str] = "plate"

    def __post_init__(self) -> None:
        t = _positive(self.thickness, "thickness")
        rho = float(self.edge_radius)
        if not (0.0 <= rho <= 0.5 * t):
            raise ValueError(f"edge_radius must lie in [0, thickness/2] = [0, {0.5 * t}] m, got {rho!r}")
        object.__setattr__(self, "thickness", t)
        object.__setattr__(self, "edge_radius", rho)

    @cached_property
    def _profile(self) -> _Profile:
        rho, half = self.edge_radius, 0.5 * self.thickness
        normals = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
        offsets = np.array([-rho, half - rho, half - rho])
        vertices = np.array([[-rho, half - rho], [-rho, -(half - rho)]])
        edges = np.array([[[0.0, -1.0], [-1.0, 0.0]], [[0.0, 1.0], [-1.0, 0.0]]])
        return _Profile(normals, offsets, vertices, edges, rho)

    def params(self) -> dict:
        return {"thickness_m": self.thickness, "edge_radius_m": self.edge_radius}


@dataclass(frozen=True, eq=False)
class Wedge(_Extruded):
    """A straight edge: two faces meeting at ``apex_angle``, rounded with ``tip_radius``.

    The bisector of the solid points along ``-x'``; the rounded tip's front is at the
    origin; the edge runs along ``z'``.

    Parameters
    ----------
    apex_angle : float
        Angle between the faces, rad, in (0, π). π/2 is a cube edge.
    tip_radius : float
        Radius of the rounded apex, m (0: sharp).
    pose : Pose
        Placement of the contact frame in the sensor frame.
    """

    apex_angle: float = 0.5 * math.pi
    tip_radius: float = 0.0
    pose: Pose = field(default_factory=Pose.identity)
    kind: ClassVar[str] = "wedge"

    def __post_init__(self) -> None:
        a = float(self.apex_angle)
        if not (0.0 < a < math.pi):
            raise ValueError(f"apex_angle must lie in (0, π) rad, got {self.apex_angle!r}")
        rho = float(self.tip_radius)
        if not (math.isfinite(rho) and rho >= 0.0):
            raise ValueError(f"tip_radius must be a non-negative length in m, got {self.tip_radius!r}")
        object.__setattr__(self, "apex_angle", a)
        object.__setattr__(self, "tip_radius", rho)

    @cached_property
    def _profile(self) -> _Profile:
        s, c = math.sin(0.5 * self.apex_angle), math.cos(0.5 * self.apex_angle)
        rho = self.tip_radius
        apex = np.array([-rho, 0.0])  # inner apex; the disc of rho puts the front at x' = 0
        normals = np.array([[s, c], [s, -c]])
        offsets = normals @ apex
        edges = np.array([[[-c, s], [-c, -s]]])
        return _Profile(normals, offsets, apex[None, :], edges, rho)

    def params(self) -> dict:
        return {"apex_angle_deg": math.degrees(self.apex_angle), "tip_radius_m": self.tip_radius}


@dataclass(frozen=True, eq=False)
class Cylinder(_Extruded):
    """Side of a solid cylinder of ``diameter`` (m), axis along ``z'`` through ``(-D/2, 0, 0)``."""

    diameter: float
    pose: Pose = field(default_factory=Pose.identity)
    kind: ClassVar[str] = "cylinder"

    def __post_init__(self) -> None:
        object.__setattr__(self, "diameter", _positive(self.diameter, "diameter"))

    @cached_property
    def _profile(self) -> _Profile:
        r = 0.5 * self.diameter
        return _Profile(np.zeros((0, 2)), np.zeros(0), np.array([[-r, 0.0]]), np.zeros((1, 2, 2)), r)

    def params(self) -> dict:
        return {"diameter_m": self.diameter}


def stick(diameter: float = 0.004, pose: Pose | None = None) -> Cylinder:
    """A stick: a thin cylinder of ``diameter`` (m, default 4 mm)."""
    return Cylinder(diameter, Pose.identity() if pose is None else pose)


@dataclass(frozen=True, eq=False)
class CylinderRim(RigidObject):
    """Fringe of the flat end of a solid cylinder (sharp rim), paper IV-E.

    The solid is ``{radial distance <= D/2, axial coordinate <= 0}`` about an axis whose
    bottom face has outward normal ``e_ax``. In the contact frame the touched rim point is
    the origin, the rim tangent is ``z'`` and the contact normal ``x' = cos(tilt) e_r +
    sin(tilt) e_ax`` (``e_r``: outward radial direction at that rim point).

    Parameters
    ----------
    diameter : float
        Cylinder diameter, m (the paper: 40 mm).
    tilt : float
        Angle of the contact normal from the side face's normal toward the bottom face's,
        rad, in (0, π/2); π/4 is the bisector of the rim.
    pose : Pose
        Placement of the contact frame in the sensor frame.
    """

    diameter: float = 0.040
    tilt: float = 0.25 * math.pi
    pose: Pose = field(default_factory=Pose.identity)
    kind: ClassVar[str] = "fringe"

    def __post_init__(self) -> None:
        object.__setattr__(self, "diameter", _positive(self.diameter, "diameter"))
        b = float(self.tilt)
        if not (0.0 < b < 0.5 * math.pi):
            raise ValueError(f"tilt must lie in (0, π/2) rad, got {self.tilt!r}")
        object.__setattr__(self, "tilt", b)

    @cached_property
    def _axes(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        c, s = math.cos(self.tilt), math.sin(self.tilt)
        e_r = np.array([c, -s, 0.0])
        e_ax = np.array([s, c, 0.0])
        centre = -0.5 * self.diameter * e_r  # on the axis, in the plane of the bottom face
        return e_r, e_ax, centre

    def _split(self, q):
        e_r, e_ax, centre = self._axes
        qc = q - centre
        w = qc @ e_ax
        radial = qc - w[:, None] * e_ax
        rr = np.linalg.norm(radial, axis=1)
        e_rad = np.where(rr[:, None] > 0.0, radial / np.where(rr > 0.0, rr, 1.0)[:, None], e_r)
        return w, radial, rr, e_rad

    def sdf_local(self, q):
        w, _, rr, _ = self._split(q)
        x = rr - 0.5 * self.diameter
        outside = np.hypot(np.maximum(x, 0.0), np.maximum(w, 0.0))
        return outside + np.minimum(np.maximum(x, w), 0.0)

    def normal_local(self, q):
        e_ax = self._axes[1]
        w, _, rr, e_rad = self._split(q)
        x = rr - 0.5 * self.diameter
        corner = (x > 0.0) & (w > 0.0)
        g_corner = x[:, None] * e_rad + w[:, None] * e_ax
        g_corner /= np.maximum(np.linalg.norm(g_corner, axis=1), _TINY)[:, None]
        return np.where(corner[:, None], g_corner, np.where((x >= w)[:, None], e_rad, e_ax))

    def exit_local(self, q, u):
        e_ax = self._axes[1]
        w, radial, rr, _ = self._split(q)
        a_rad = 0.5 * self.diameter
        uw = u @ e_ax
        up = u - uw[:, None] * e_ax
        a = np.einsum("ij,ij->i", up, up)
        b = np.einsum("ij,ij->i", radial, up)
        c = rr * rr - a_rad * a_rad
        disc = np.maximum(b * b - a * c, 0.0)
        ok = a > _TINY
        s_cyl = np.where(ok, (-b + np.sqrt(disc)) / np.where(ok, a, 1.0), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_pl = np.where(uw > 1e-15, -w / np.where(uw > 1e-15, uw, 1.0), np.inf)
        use_cyl = s_cyl <= s_pl
        s = np.maximum(np.minimum(s_cyl, s_pl), 0.0)
        n_cyl = (radial + np.where(np.isfinite(s_cyl), s_cyl, 0.0)[:, None] * up) / a_rad
        n = np.where(use_cyl[:, None], n_cyl, e_ax)
        return s, n

    def line_direction_local(self, q):
        e_ax = self._axes[1]
        e_rad = self._split(q)[3]
        d = np.cross(e_ax, e_rad)
        return d / np.linalg.norm(d, axis=1)[:, None]

    def params(self) -> dict:
        return {"diameter_m": self.diameter, "tilt_deg": math.degrees(self.tilt)}


#: Object kinds accepted by :func:`make_object` (and the ``simulate`` command).
OBJECT_KINDS = ("plane", "plate", "wedge", "cylinder", "stick", "fringe")


def make_object(
    kind: str,
    size: float | None = None,
    *,
    edge_radius: float = 0.0,
    apex_angle: float = 0.5 * math.pi,
    tilt: float = 0.25 * math.pi,
) -> RigidObject:
    """Build an object (identity pose) from plain parameters.

    Parameters
    ----------
    kind : {"plane", "plate", "wedge", "cylinder", "stick", "fringe"}
        What is touched.
    size : float, optional
        m: plate thickness (default 1 mm), cylinder diameter (default 6 mm), stick
        diameter (default 4 mm), fringe cylinder diameter (default 40 mm). Ignored for
        ``plane`` and ``wedge``.
    edge_radius : float
        m: plate corner radius or wedge tip radius.
    apex_angle : float
        rad, wedge apex angle.
    tilt : float
        rad, fringe contact-normal tilt from the side face (π/4: rim bisector).
    """
    if kind == "plane":
        return HalfSpace()
    if kind == "plate":
        return Plate(0.001 if size is None else size, edge_radius)
    if kind == "wedge":
        return Wedge(apex_angle, edge_radius)
    if kind == "cylinder":
        return Cylinder(0.006 if size is None else size)
    if kind == "stick":
        return stick(0.004 if size is None else size)
    if kind == "fringe":
        return CylinderRim(0.040 if size is None else size, tilt)
    raise ValueError(f"unknown object kind {kind!r}; expected one of {', '.join(OBJECT_KINDS)}")
