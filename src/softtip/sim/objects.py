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


def _points(points: ArrayLike) -> NDArray[np.float64]:
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must have shape (..., 3), got {p.shape}")
    return p


class RigidObject:
    """Base class: a convex rigid body posed in the sensor frame by ``self.pose``.

    Subclasses implement the ``*_local`` methods on arrays of object-frame points of shape
    ``(M, 3)``; the public methods take sensor-frame arrays of any leading shape.
    """

    kind: ClassVar[str] = ""
    pose: Pose

    # -- local (object-frame) kernels ---------------------------------------------------
    def sdf_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:  # pragma: no cover - abstract
        """Signed distance (m) at object-frame points ``q`` (M, 3); negative inside."""
        raise NotImplementedError

    def normal_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:  # pragma: no cover - abstract
        """Unit gradient of the signed distance (outward normal of the nearest surface), (M, 3)."""
        raise NotImplementedError

    def exit_local(
        self, q: NDArray[np.float64], u: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # pragma: no cover - abstract
        """Where the ray ``q + s u`` (s >= 0) from an interior point leaves the object.

        Returns ``s_exit`` (M,) in units of ``|u|`` (``inf`` if it never leaves) and the
        outward unit normal at the exit point (M, 3). Points outside give ``s_exit = 0``
        or a meaningless value; callers pass interior points only.
        """
        raise NotImplementedError

    def line_direction_local(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Unit line direction (edge/axis/fringe tangent) near ``q``, (M, 3); NaN if none."""
        return np.broadcast_to(np.array([0.0, 0.0, 1.0]), q.shape).copy()

    def params(self) -> dict:  # pragma: no cover - abstract
        """Geometric parameters, SI, JSON-ready."""
        raise NotImplementedError

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
@dataclass(frozen=True, eq=False)
class _Profile:
    """Inner convex polygon ``{p : normals @ p <= offsets}`` dilated by a disc of ``rho``.

    ``vertices`` (J, 2) are the polygon's corners; ``edges`` (J, 2, 2) the unit directions
    from each corner along its two edges (zeros for an isolated point, whose normal cone is
    the whole plane).
    """

    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    vertices: NDArray[np.float64]
    edges: NDArray[np.float64]
    rho: float

    def _cone(self, w: NDArray[np.float64], j: int) -> NDArray[np.bool_]:
        # w - vertex lies in the vertex's normal cone: the vertex is the closest inner point
        ea, eb = self.edges[j]
        return (w @ ea <= 0.0) & (w @ eb <= 0.0)

    def sdf(self, q2: NDArray[np.float64]) -> NDArray[np.float64]:
        if len(self.offsets):
            d = (q2 @ self.normals.T - self.offsets).max(axis=1)
        else:
            d = np.full(q2.shape[0], -np.inf)
        for j in range(len(self.vertices)):
            w = q2 - self.vertices[j]
            cone = self._cone(w, j)
            if cone.any():
                wc = w[cone]
                d[cone] = np.hypot(wc[:, 0], wc[:, 1])
        return d - self.rho

    def grad(self, q2: NDArray[np.float64]) -> NDArray[np.float64]:
        m = q2.shape[0]
        if len(self.offsets):
            g = self.normals[np.argmax(q2 @ self.normals.T - self.offsets, axis=1)]
        else:
            g = np.zeros((m, 2))
        for j in range(len(self.vertices)):
            w = q2 - self.vertices[j]
            cone = self._cone(w, j)
            if cone.any():
                wc = w[cone]
                dist = np.hypot(wc[:, 0], wc[:, 1])
                ok = dist > 0.0
                g[cone] = np.where(ok[:, None], wc / np.where(ok, dist, 1.0)[:, None], [1.0, 0.0])
        return g

    def exit(self, q2: NDArray[np.float64], u2: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        m = q2.shape[0]
        s = np.full(m, np.inf)
        n = np.zeros((m, 2))
        if len(self.offsets):
            nu = u2 @ self.normals.T
            num = self.offsets + self.rho - q2 @ self.normals.T
            with np.errstate(divide="ignore", invalid="ignore"):
                sk = np.where(nu > 1e-15, num / np.where(nu > 1e-15, nu, 1.0), np.inf)
            k = np.argmin(sk, axis=1)
            s = sk[np.arange(m), k]
            n = self.normals[k]
        if self.rho > 0.0:
            a = np.einsum("ij,ij->i", u2, u2)
            for j in range(len(self.vertices)):
                w = q2 - self.vertices[j]
                b = np.einsum("ij,ij->i", w, u2)
                c = np.einsum("ij,ij->i", w, w) - self.rho**2
                disc = b * b - a * c
                ok = (a > _TINY) & (disc >= 0.0)
                s2 = np.where(ok, (-b + np.sqrt(np.where(ok, disc, 0.0))) / np.where(ok, a, 1.0), np.inf)
                s2 = np.maximum(s2, 0.0)
                e = w + np.where(np.isfinite(s2), s2, 0.0)[:, None] * u2
                better = ok & self._cone(e, j) & (s2 < s)
                s = np.where(better, s2, s)
                n = np.where(better[:, None], e / self.rho, n)
        return np.maximum(s, 0.0), n


class _Extruded(RigidObject):
    """An object whose cross-section in the x'y' plane is a :class:`_Profile`, infinite in z'."""

    @cached_property
    def _profile(self) -> _Profile:  # pragma: no cover - abstract
        raise NotImplementedError

    def sdf_local(self, q):
        return self._profile.sdf(q[:, :2])

    def normal_local(self, q):
        g = self._profile.grad(q[:, :2])
        return np.column_stack((g, np.zeros(len(q))))

    def exit_local(self, q, u):
        s, n2 = self._profile.exit(q[:, :2], u[:, :2])
        return s, np.column_stack((n2, np.zeros(len(q))))


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
