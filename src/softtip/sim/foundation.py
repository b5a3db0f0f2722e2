"""Quasi-static elastic-foundation (Winkler) contact of a rigid object with the skin.

Model
-----
The skin is a layer of thickness ``h`` (5 mm) on a rigid shell, discretised into surface
elements (:mod:`softtip.sim.skin`). Each element is an independent pair of springs:

* **Normal.** The element's spring runs along the skin's inward normal ``-n_skin``, as in
  an elastic foundation on a rigid base. Its compression ``δ`` is the distance from the
  element centre, along ``-n_skin``, to where that ray leaves the (convex) object, i.e. to
  the object surface the spring is pressed against. ``δ`` saturates at ``max_depth``
  (default: the skin thickness; the shell itself is not a contact). The pressure
  ``p = E δ / h`` pushes along ``-n_skin``, into the fingertip.
* **Tangential.** An elastic shear layer of stiffness ``k_t = G / h`` per area stores the
  object's displacement ``u`` in the skin's tangent plane at the contact since the
  element's first contact (stick); traction ``k_t u`` is capped at ``μ p`` (Coulomb). When
  the cap is exceeded the element slips and its stored displacement is reset to the cap,
  so the model is path dependent.
* **Coverage.** An element partly inside a thin object (a 1 mm plate spans two elements)
  counts with the fraction ``clip(1/2 - l / a, 0, 1)`` of its area, where ``a`` is the
  element size and ``l`` the signed distance, in the skin's tangent plane, to where the
  object surface cuts the skin (``sdf / |tangential part of the object normal|``): a box
  filter across the silhouette. An element whose centre is just outside takes the
  compression of the nearest object surface point. This makes force and moment smooth in
  the pose and convergent with resolution.

Why not the object's signed distance and normal: inside a 1 mm plate the signed distance
never exceeds 0.5 mm and its gradient points at the side faces; and pressure along the
object normal lets a thin plate tilted by a few degrees about its own edge push sideways
with ``F sin γ``, which then shifts the whole strip across its axis — an artefact of
dropping the skin's resistance to being wrapped around the plate, which the Winkler layer
does not have.

Element forces act at the contact interface (the exit points on the object surface), and
the wrench about the sensor origin is ``[Σ F, Σ x × F]``. Everything is vectorised over the
candidate elements; :meth:`ContactModel.candidates_near` culls the skin to a ball.

By default (``ContactParams(depth_rule="column")``) the skin-point test is replaced by the
elastic-foundation rule proper: each spring is compressed to the deepest object point on
its column, whether or not its skin point lies inside the object; ``"surface"`` keeps the
skin-point test. See :class:`ContactParams` for where the two rules differ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._vec import cross as _cross
from softtip.sim.objects import RigidObject
from softtip.sim.pose import Pose
from softtip.sim.skin import SkinMesh

__all__ = ["DEPTH_RULES", "ContactParams", "FrictionState", "ContactResult", "ContactModel"]

# Projected start points sit this far inside the object, m (keeps them off the boundary).
_INSIDE_EPS = 1e-10
# An element's quadrature points and their coverage filters reach this many element sizes
# from its centre (half a sub-cell diagonal plus half a sub-cell, rounded up).
_REACH = 0.75

#: Values of :attr:`ContactParams.depth_rule`.
DEPTH_RULES = ("surface", "column")


@dataclass(frozen=True)
class ContactParams:
    """Material parameters of the skin, SI.

    Parameters
    ----------
    thickness : float
        Skin thickness ``h``, m (the papers: 5 mm silicone over an 11 mm shell).
    modulus : float
        Effective Winkler modulus ``E``, Pa; normal stiffness per area is ``E / h``.
        Default 0.6 MPa: 0.5 kgf (4.9 N) pushes the cut edge of a 2 mm plate about 2 mm
        into the murakami2006 tip, a 1 mm plate about 3 mm (the brief's 1–3 mm), and the
        value is that of a soft silicone rubber.
    shear_modulus : float, optional
        Shear modulus ``G`` of the tangential layer, Pa; stiffness per area ``G / h``.
        Default ``E / 3`` (incompressible rubber, ν = 0.5).
    friction : float
        Coulomb coefficient μ between skin and object (default 1.0, silicone on metal).
    max_depth : float, optional
        Saturation of the compression, m (default: ``thickness``).
    depth_rule : {"surface", "column"}
        How an element's compression is found. ``"surface"`` (the original rule): only
        elements whose skin point lies inside the object (or within the coverage filter of
        its silhouette on the skin) are compressed, by the distance from that point to
        where the ray along ``-n_skin`` leaves the object. ``"column"`` (default): the
        elastic-foundation rule proper: an element's spring (its column of rubber along
        ``-n_skin``) is compressed to the deepest object point on that
        column, whether or not the skin point itself lies inside the object, and the
        coverage filter uses the distance from the column to the object (the object's
        *shadow* along the column) instead of the distance at the skin point. The deepest
        point of a column is found in closed form
        (:meth:`~softtip.sim.objects.RigidObject.segment_min_local`; a short numerical
        search for the fringe), so the rule costs about 1.1–1.3× the surface rule on
        cylinders and wedges and about 2× on thin plates. The two rules agree on planes,
        cylinders and wedges (to rounding). They differ for overhanging objects, e.g. a
        thin plate tilted about its own edge, whose cut edge lies beside the footprint it
        cuts in the skin (the springs under the cut edge carry the load there), and also
        for an *untilted* thin plate on the curved skin: the columns converge toward the
        shell's centre, so those starting just beside the plate run into its parallel
        faces a little deeper (the shadow is wider by about ``t δ / R``): at the same
        depth a 1–2 mm plate pushes ≈ 14 % harder (1 mm plate at 0.5 kgf: 2.78 instead
        of 3.07 mm deep), independent of the resolution.
    """

    thickness: float = 0.005
    modulus: float = 0.6e6
    shear_modulus: float | None = None
    friction: float = 1.0
    max_depth: float | None = None
    depth_rule: str = "column"

    def __post_init__(self) -> None:
        for name in ("thickness", "modulus"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be positive and finite, got {v!r}")
        if self.shear_modulus is not None and not (math.isfinite(self.shear_modulus) and self.shear_modulus > 0.0):
            raise ValueError(f"shear_modulus must be positive and finite, got {self.shear_modulus!r}")
        if not (math.isfinite(self.friction) and self.friction >= 0.0):
            raise ValueError(f"friction must be non-negative and finite, got {self.friction!r}")
        if self.max_depth is not None and not (math.isfinite(self.max_depth) and self.max_depth > 0.0):
            raise ValueError(f"max_depth must be positive and finite, got {self.max_depth!r}")
        if self.depth_rule not in DEPTH_RULES:
            raise ValueError(f"depth_rule must be one of {DEPTH_RULES}, got {self.depth_rule!r}")

    @property
    def normal_stiffness(self) -> float:
        """``E / h``, Pa/m."""
        return self.modulus / self.thickness

    @property
    def tangential_stiffness(self) -> float:
        """``G / h``, Pa/m."""
        g = self.modulus / 3.0 if self.shear_modulus is None else self.shear_modulus
        return g / self.thickness

    @property
    def depth_cap(self) -> float:
        """Saturation of the element compression, m."""
        return self.thickness if self.max_depth is None else float(self.max_depth)

    def as_dict(self) -> dict:
        """JSON-ready, SI, with the derived stiffnesses."""
        return {
            "thickness_m": self.thickness,
            "modulus_pa": self.modulus,
            "shear_modulus_pa": self.tangential_stiffness * self.thickness,
            "friction": self.friction,
            "max_depth_m": self.depth_cap,
            "depth_rule": self.depth_rule,
            "normal_stiffness_pa_per_m": self.normal_stiffness,
            "tangential_stiffness_pa_per_m": self.tangential_stiffness,
        }


def _frozen(a: ArrayLike, dtype=float) -> NDArray:
    out = np.ascontiguousarray(a, dtype=dtype)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class FrictionState:
    """Stored tangential displacement of the elements in contact, and the object pose then.

    Attributes
    ----------
    index : array of int, shape (k,)
        Skin element indices in contact, ascending.
    displacement : array, shape (k, 3)
        Elastic tangential displacement ``u`` of each, m, sensor frame.
    pose : Pose or None
        Object pose at which the state was committed (None: no history).
    """

    index: NDArray[np.intp] = field(default_factory=lambda: _frozen(np.zeros(0), np.intp))
    displacement: NDArray[np.float64] = field(default_factory=lambda: _frozen(np.zeros((0, 3))))
    pose: Pose | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "index", _frozen(self.index, np.intp))
        object.__setattr__(self, "displacement", _frozen(np.reshape(self.displacement, (-1, 3))))


@dataclass(frozen=True, eq=False)
class ContactResult:
    """Contact of one object pose; per-point arrays cover the quadrature points in contact.

    Attributes
    ----------
    wrench : array, shape (6,)
        ``fx, fy, fz, mx, my, mz`` the object exerts on the fingertip (N, N·m about the
        sensor origin).
    index : array of int, shape (k,)
        Quadrature points in contact (``element * quadrature² + k``, ascending).
    centre : array, shape (k, 3)
        Their undeformed positions on the skin, m.
    point : array, shape (k, 3)
        Contact interface points (on the object surface) where the forces act, m.
    normal : array, shape (k, 3)
        Direction of the pressure: minus the skin normal (into the fingertip).
    area : array, shape (k,)
        Element area times coverage, m².
    depth : array, shape (k,)
        Compression δ, m.
    pressure : array, shape (k,)
        Normal pressure ``E δ / h``, Pa.
    traction : array, shape (k, 3)
        Traction in the skin's tangent plane, Pa (``|traction| <= μ pressure``).
    slip : array of bool, shape (k,)
        Elements at the Coulomb limit.
    state : FrictionState
        The friction state to carry to the next step.
    """

    wrench: NDArray[np.float64]
    index: NDArray[np.intp]
    centre: NDArray[np.float64]
    point: NDArray[np.float64]
    normal: NDArray[np.float64]
    area: NDArray[np.float64]
    depth: NDArray[np.float64]
    pressure: NDArray[np.float64]
    traction: NDArray[np.float64]
    slip: NDArray[np.bool_]
    state: FrictionState

    @property
    def force(self) -> NDArray[np.float64]:
        """Total force on the fingertip, N, shape (3,)."""
        return self.wrench[:3]

    @property
    def moment(self) -> NDArray[np.float64]:
        """Moment about the sensor origin, N·m, shape (3,)."""
        return self.wrench[3:]

    @property
    def in_contact(self) -> bool:
        """Whether any element is compressed."""
        return len(self.index) > 0

    @property
    def contact_area(self) -> float:
        """Compressed skin area, m²."""
        return float(self.area.sum())

    @property
    def max_depth(self) -> float:
        """Largest compression, m (0 without contact)."""
        return float(self.depth.max()) if len(self.depth) else 0.0

    @property
    def slip_fraction(self) -> float:
        """Fraction of the contact area at the Coulomb limit (0 without contact)."""
        a = self.area.sum()
        return float(self.area[self.slip].sum() / a) if a > 0.0 else 0.0

    @property
    def pressure_centre(self) -> NDArray[np.float64]:
        """Pressure-weighted mean of the compressed element centres, m, (3,); NaN without contact."""
        w = self.pressure * self.area
        s = w.sum()
        if s <= 0.0:
            return np.full(3, np.nan)
        return (w @ self.centre) / s

    @property
    def friction_depth(self) -> float:
        """Depth at which the tangential tractions act, m: ``F_t · Σ δ_i F_t,i / |F_t|²``
        with ``F_t,i`` the elements' tangential forces and ``F_t`` their sum; NaN without
        contact or when ``|F_t|`` is below 1 % of the normal force."""
        ft = self.area[:, None] * self.traction
        total = ft.sum(axis=0)
        tt = float(total @ total)
        f_normal = float(np.sum(self.area * self.pressure))
        if not len(self.depth) or tt <= (0.01 * f_normal) ** 2:
            return math.nan
        return float(total @ (self.depth @ ft)) / tt

    def moment_about(self, point: ArrayLike) -> NDArray[np.float64]:
        """Moment about ``point`` (m, (3,)): ``m - point × f``, N·m."""
        return self.moment - np.cross(np.asarray(point, dtype=float), self.force)


@dataclass(frozen=True, eq=False)
class ContactModel:
    """The skin mesh with its material: evaluates the wrench of an object pose.

    Each skin element is integrated with ``quadrature × quadrature`` points laid out in its
    tangent plane and projected onto the skin (default 2 × 2). The extra points are only
    evaluated for elements near the object, so they cost little, and they remove most of
    the lattice noise of the single-point rule on tent-shaped pressure fields (sharp
    wedges) at a given element count.

    Parameters
    ----------
    skin : SkinMesh
        Discretised skin.
    params : ContactParams
        Material.
    quadrature : int
        Quadrature points per element side (1: the element centre only).
    """

    skin: SkinMesh
    params: ContactParams = field(default_factory=ContactParams)
    quadrature: int = 2

    def __post_init__(self) -> None:
        if int(self.quadrature) < 1:
            raise ValueError(f"quadrature must be a positive integer, got {self.quadrature!r}")
        object.__setattr__(self, "quadrature", int(self.quadrature))

    @cached_property
    def _points(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        # quadrature points (N*Q², 3) on the skin, their normals, areas and sizes
        skin, nq = self.skin, self.quadrature
        c, n, a, h = skin.centres, skin.normals, skin.areas, skin.spacing
        if nq == 1:
            return c, n, a, h
        ref = np.where(np.abs(n[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        t1 = np.cross(ref, n)
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        t2 = np.cross(n, t1)
        g = (np.arange(nq) + 0.5) / nq - 0.5
        ga, gb = (x.ravel() for x in np.meshgrid(g, g, indexing="ij"))
        p = c[:, None, :] + h[:, None, None] * (ga[None, :, None] * t1[:, None, :] + gb[None, :, None] * t2[:, None, :])
        p = skin.tip.project(p.reshape(-1, 3))
        normals = skin.tip.normal(p)
        areas = np.repeat(a / nq**2, nq**2)
        sizes = np.repeat(h / nq, nq**2)
        for arr in (p, normals, areas, sizes):
            arr.setflags(write=False)
        return p, normals, areas, sizes

    def prepare(self) -> ContactModel:
        """Build the quadrature points now (otherwise on first use); returns ``self``."""
        self._points  # noqa: B018 - cached_property: evaluating it builds and caches
        return self

    def candidates_near(self, point: ArrayLike, radius: float) -> NDArray[np.intp]:
        """Indices (ascending) of the skin elements within ``radius`` (m) of ``point`` (m, (3,))."""
        d = self.skin.centres - np.asarray(point, dtype=float)
        return np.flatnonzero(np.einsum("ij,ij->i", d, d) <= radius * radius)

    def candidates_touching(
        self, obj: RigidObject, pose: Pose, margin: float, candidates: NDArray[np.intp] | None = None
    ) -> NDArray[np.intp]:
        """Elements (ascending) that may touch ``obj`` at any pose within ``margin`` (m) of ``pose``.

        The signed distance is 1-Lipschitz, so an element whose centre is farther than
        ``margin`` plus its own reach from the object cannot touch it after the object
        moves by at most ``margin``. With ``depth_rule="column"`` an element whose column
        may pass within that distance of the object is kept as well.
        """
        idx = np.arange(len(self.skin)) if candidates is None else np.asarray(candidates, dtype=np.intp)
        q = (self.skin.centres[idx] - pose.translation) @ pose.rotation
        sd = obj.sdf_local(q)
        reach = _REACH * self.skin.spacing[idx] + margin
        keep = sd < reach
        if self.params.depth_rule == "column":
            keep |= self._overhang(obj, q, -self.skin.normals[idx] @ pose.rotation, sd, reach)
        return idx[keep]

    def evaluate(
        self,
        obj: RigidObject,
        pose: Pose | None = None,
        state: FrictionState | None = None,
        candidates: NDArray[np.intp] | None = None,
    ) -> ContactResult:
        """Wrench and per-point contact of ``obj`` at ``pose``.

        Parameters
        ----------
        obj : RigidObject
            The object's geometry (its own ``pose`` is used when ``pose`` is None).
        pose : Pose, optional
            Object pose in the sensor frame.
        state : FrictionState, optional
            Friction state committed at the previous step (None: no tangential history,
            i.e. tractions start from zero).
        candidates : array of int, optional
            Skin element indices to consider; default all. Elements left out cannot touch:
            the caller is responsible for the cull being large enough.

        Returns
        -------
        ContactResult
            Per-point arrays index the quadrature points (``element * quadrature² + k``).
        """
        pose = obj.pose if pose is None else pose
        skin, prm = self.skin, self.params
        rot, trans = pose.rotation, pose.translation
        idx = np.arange(len(skin)) if candidates is None else np.asarray(candidates, dtype=np.intp)
        column = prm.depth_rule == "column"
        nq2 = self.quadrature**2
        if nq2 > 1:
            # element-level cull, then the element's quadrature points
            qe = (skin.centres[idx] - trans) @ rot
            reach = _REACH * skin.spacing[idx]
            sde = obj.sdf_local(qe)
            keep = sde < reach
            if column:
                keep |= self._overhang(obj, qe, -skin.normals[idx] @ rot, sde, reach)
            idx = np.sort(idx[keep])
            idx = (idx[:, None] * nq2 + np.arange(nq2)).ravel()
        else:
            idx = np.sort(idx)
        pts, nrm, areas, sizes = self._points
        q = (pts[idx] - trans) @ rot
        sd = obj.sdf_local(q)
        half = 0.5 * sizes[idx]
        if column:
            geo = self._column_points(obj, idx, q, -nrm[idx] @ rot, sd, half)
        else:
            geo = self._surface_points(obj, idx, q, -nrm[idx] @ rot, sd, half)
        if geo is None:
            return self._empty(pose)
        gidx, start, base, u, offset, cover = geo
        s, _ = obj.exit_local(start, u)
        depth = np.minimum(offset + s, prm.depth_cap)
        touch = (depth > 0.0) & (cover > 0.0)
        if not touch.any():
            return self._empty(pose)
        q = base
        area = areas[gidx[touch]] * cover[touch]
        gidx, q, u, depth = gidx[touch], q[touch], u[touch], depth[touch]
        e_loc = q + depth[:, None] * u
        point = e_loc @ rot.T + trans
        normal = -nrm[gidx]  # the springs push along the shell normal, into the fingertip
        pressure = prm.normal_stiffness * depth

        # tangential layer: stored displacement plus the object's motion at the contact
        disp = np.zeros_like(point)
        if state is not None and state.pose is not None and len(state.index):
            pos = np.minimum(np.searchsorted(state.index, gidx), len(state.index) - 1)
            kept = state.index[pos] == gidx
            if kept.any():
                prev = state.pose
                moved = point[kept] - (e_loc[kept] @ prev.rotation.T + prev.translation)
                disp[kept] = state.displacement[pos[kept]] + moved
        disp -= np.einsum("ij,ij->i", disp, normal)[:, None] * normal
        kt = prm.tangential_stiffness
        mag = kt * np.sqrt(np.einsum("ij,ij->i", disp, disp))
        limit = prm.friction * pressure
        slip = mag > limit
        if slip.any():
            disp[slip] *= (limit[slip] / mag[slip])[:, None]
        traction = kt * disp

        forces = area[:, None] * (pressure[:, None] * normal + traction)
        wrench = np.concatenate((forces.sum(axis=0), _cross(point, forces).sum(axis=0)))
        return ContactResult(
            wrench=wrench,
            index=gidx,
            centre=pts[gidx],
            point=point,
            normal=normal,
            area=area,
            depth=depth,
            pressure=pressure,
            traction=traction,
            slip=slip,
            state=FrictionState(gidx, disp, pose),
        )

    def _overhang(self, obj: RigidObject, q: NDArray[np.float64], u: NDArray[np.float64],
                  sd: NDArray[np.float64], reach: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Columns ``q + s u``, ``0 <= s <= depth cap``, that may come within ``reach`` of the object.

        The signed distance is convex along a line (the object is convex), so it stays
        above its tangent at ``s = 0``: ``sd + min(0, ∂sd/∂s) · cap`` bounds it from below.
        """
        cap = self.params.depth_cap
        out = np.zeros(len(q), dtype=bool)
        pool = np.flatnonzero((sd >= reach) & (sd < reach + cap))
        if len(pool):
            slope = np.einsum("ij,ij->i", obj.normal_local(q[pool]), u[pool])
            out[pool] = sd[pool] + np.minimum(slope, 0.0) * cap < reach[pool]
        return out

    def _surface_points(self, obj, idx, q, u, sd, half):
        # "surface" rule: the skin point itself must lie inside (or at the silhouette of) the object
        act = np.flatnonzero(sd < half)
        if len(act) == 0:
            return None
        gidx, q, sd, half, u = idx[act], q[act], sd[act], half[act], u[act]
        cover = np.ones(len(act))
        near = np.flatnonzero(sd > -half)
        if len(near):
            # box filter across the silhouette: distance in the skin's tangent plane to where
            # the object surface cuts the skin is sdf / |tangential part of the object normal|
            g = obj.normal_local(q[near])
            un = u[near]
            gt = g - np.einsum("ij,ij->i", g, un)[:, None] * un
            tang = np.sqrt(np.einsum("ij,ij->i", gt, gt))
            with np.errstate(divide="ignore", invalid="ignore"):
                lateral = np.where(tang > 1e-12, sd[near] / tang, np.where(sd[near] > 0.0, np.inf, -np.inf))
            cover[near] = np.clip(0.5 - lateral / (2.0 * half[near]), 0.0, 1.0)
            out = sd[near] > 0.0
            if out.any():
                # centre just outside: take the compression of the nearest object surface point
                o = near[out]
                q[o] -= (sd[o] + _INSIDE_EPS)[:, None] * g[out]
        return gidx, q, q, u, np.zeros(len(act)), cover

    def _column_points(self, obj, idx, q, u, sd, half):
        # "column" rule: the spring's column q + s u (0 <= s <= cap) against the whole object.
        # Its deepest point, or its closest approach, in closed form per object kind: s = 0
        # wherever the object does not overhang the skin point (the surface rule's point).
        s_min, m = obj.segment_min_local(q, u, self.params.depth_cap, sd)
        hit = m < half  # otherwise the coverage below is 0
        if not hit.all():
            if not hit.any():
                return None
            idx, q, u, sd, half, s_min, m = idx[hit], q[hit], u[hit], sd[hit], half[hit], s_min[hit], m[hit]
        start = q + s_min[:, None] * u
        cover = np.ones(len(idx))
        band = np.flatnonzero(m > -half)
        if len(band):
            # coverage: a box filter of the lateral distance from the column to the object's
            # shadow on it. At the skin point (s = 0) that is the surface rule's sdf /
            # |tangential part of the object normal|; deeper, a column inside the object
            # reaches its minimum against a face along it (tangential normal ≈ 1)
            mb, ub = m[band], u[band]
            g = obj.normal_local(start[band])
            gu = np.einsum("ij,ij->i", g, ub)
            tang = np.sqrt(np.maximum(1.0 - gu * gu, 0.0))  # g is a unit vector
            with np.errstate(divide="ignore", invalid="ignore"):
                lateral = np.where(tang > 1e-12, mb / tang, np.where(mb > 0.0, np.inf, -np.inf))
            lateral = np.where((mb < 0.0) & (s_min[band] > 0.0), mb, lateral)
            cover[band] = np.clip(0.5 - lateral / (2.0 * half[band]), 0.0, 1.0)
            # column just beside the object: start the exit search from the nearest object
            # point, as the surface rule does
            out = mb > -_INSIDE_EPS
            if out.any():
                start[band[out]] -= (mb[out] + _INSIDE_EPS)[:, None] * g[out]
        # (elements with no coverage are dropped by the caller)
        return idx, start, start - s_min[:, None] * u, u, s_min, cover

    def _empty(self, pose: Pose) -> ContactResult:
        z3 = np.zeros((0, 3))
        z = np.zeros(0)
        return ContactResult(
            wrench=np.zeros(6),
            index=np.zeros(0, dtype=np.intp),
            centre=z3,
            point=z3,
            normal=z3,
            area=z,
            depth=z,
            pressure=z,
            traction=z3,
            slip=np.zeros(0, dtype=bool),
            state=FrictionState(pose=pose),
        )
