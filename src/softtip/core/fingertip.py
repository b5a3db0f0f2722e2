"""Fingertip shapes with closed forms, the registry of shapes and the fingertip file.

The skin is the surface ``S(r) = 0`` in the sensor frame (manual §2), ``S < 0`` inside and
``S > 0`` outside, with outward normal ``∇S / |∇S|`` (paper Eq. 2); lengths in metres.
Each shape implements the shape protocol (:class:`~softtip.core.shape.Fingertip`) in one
place: its surface, its contact solution, its simulator skin, its calibration, its view
and its file form. Here: :class:`Sphere`, :class:`Capsule` (the papers' fingertip: a
cylinder along +z from ``z = 0`` capped by a hemisphere centred at ``(0, 0, length)``) and
:class:`Ellipsoid` (axis-aligned, Bicchi's quadric case), each with its closed-form contact
solution. :class:`~softtip.core.implicit.ImplicitSurface` (any callable ``S``) and
:class:`~softtip.core.mesh.MeshFingertip` (a triangle mesh) have their own modules;
:class:`~softtip.core.mounting.Mounted` places any of them on the sensor.

:data:`SHAPES` names the shapes a fingertip file can give; :func:`load_fingertip` reads
a preset or a file.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._jit import jitable
from softtip.core.implicit import ImplicitSurface
from softtip.core.mesh import MESH_SUFFIXES, MeshFingertip
from softtip.core.mounting import mount_from_mapping
from softtip.core.shape import (
    Fingertip,
    PressModel,
    check_size,
    check_skin,
    fibonacci_cap,
    fields_from_table,
    fingertip_table,
    fmt,
    grid_mesh,
    positive,
    skin_toml,
    sphere_kernel,
    uv_sphere,
    vec3,
)
from softtip.errors import InputError

__all__ = [
    "Fingertip",
    "Sphere",
    "Capsule",
    "Ellipsoid",
    "ImplicitSurface",
    "PRESETS",
    "SHAPES",
    "murakami2006",
    "load_fingertip",
    "fingertip_from_mapping",
]


# -- sphere -------------------------------------------------------------------------------------


class _SphericalPress(PressModel):
    """A sphere's (or a capsule's cap's) centre and radius: the contact point is ``c + (R − δ) n``."""

    names = ("centre x", "centre y", "centre z", "radius")
    centre_name = "centre"

    def start(self, center: NDArray, radius: float) -> NDArray:
        return np.concatenate((center * 1e3, [radius * 1e3]))

    def points(self, x: NDArray, normals: NDArray, depth: NDArray) -> NDArray:
        rho = x[3] - depth
        return x[:3] + rho[:, None] * normals

    def tip(self, x: NDArray, source: str) -> Fingertip:
        return Sphere(radius=x[3], center=tuple(x[:3]))

    def stds(self, std: NDArray) -> dict[str, float]:
        return {"radius": std[3], "centre x": std[0], "centre y": std[1], "centre z": std[2]}

    def report(self, x: NDArray, std: NDArray) -> tuple[list[str], list[str]]:
        mm = 1e3
        c, cs = x[:3] * mm, std[:3] * mm
        return [
            f"  {self.centre_name:10s} x = {c[0]:+.3f} ± {cs[0]:.3f} mm, y = {c[1]:+.3f} ± {cs[1]:.3f} mm, "
            f"z = {c[2]:+.3f} ± {cs[2]:.3f} mm",
            f"  radius     {x[3] * mm:.3f} ± {std[3] * mm:.3f} mm",
        ], []

    def std_line(self, std: NDArray) -> str:
        mm = 1e3
        return f"radius std {std[3] * mm:.4f} mm; centre std " + ", ".join(f"{v * mm:.4f}" for v in std[:3]) + " mm"


@jitable
def sphere_normal_kernel(x, y, z, cx, cy, cz, xp):
    """The outward unit normal of a sphere centred at ``c`` (m) through ``(x, y, z)``, component-wise."""
    px, py, pz = x - cx, y - cy, z - cz
    norm = xp.sqrt(px * px + py * py + pz * pz)
    return xp.div(px, norm), xp.div(py, norm), xp.div(pz, norm)


@jitable
def sphere_project_kernel(x, y, z, radius, cx, cy, cz, xp):
    """The point of a sphere of ``radius`` centred at ``c`` (m) nearest to ``(x, y, z)``, component-wise."""
    nx, ny, nz = sphere_normal_kernel(x, y, z, cx, cy, cz, xp)
    return cx + radius * nx, cy + radius * ny, cz + radius * nz


@dataclass(frozen=True)
class Sphere(Fingertip):
    """Spherical skin of ``radius`` (m) centred at ``center`` (m, sensor frame)."""

    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    skin_thickness: float | None = field(default=None, compare=False)
    kind: ClassVar[str] = "sphere"
    calibrates: ClassVar[str | None] = "presses"

    def __post_init__(self) -> None:
        check_skin(self)
        object.__setattr__(self, "radius", positive(self.radius, "radius"))
        object.__setattr__(self, "center", vec3(self.center, "center"))

    def _surface_kernel(self, x, y, z, xp):
        cx, cy, cz = self.center
        px, py, pz = x - cx, y - cy, z - cz
        return xp.sqrt(px * px + py * py + pz * pz) - self.radius

    def _normal_kernel(self, x, y, z, xp):
        return sphere_normal_kernel(x, y, z, *self.center, xp)

    def _project_kernel(self, x, y, z, xp):
        return sphere_project_kernel(x, y, z, self.radius, *self.center, xp)

    @property
    def twist_radius(self) -> float:
        return float(self.radius)

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return np.array(self.center), self.radius

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp):
        return sphere_kernel(fx, fy, fz, mx, my, mz, self.radius, *self.center, xp)

    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """Fibonacci-lattice elements from the top down to ``z_min`` (m; default
        ``center_z − radius/2``, 120° from the top). See :meth:`Fingertip.skin_elements`."""
        r = self.radius
        cen = np.array(self.center)
        zc = cen[2] - 0.5 * r if z_min is None else float(z_min)
        cos_min = min(max((zc - cen[2]) / r, -1.0), 1.0)
        if cos_min >= 1.0:
            raise ValueError(f"z_min {zc} m leaves no skin on the sphere")
        u, w = fibonacci_cap(n_elements, cos_min)
        return cen + r * u, u, w * r * r

    def support_point(self, normal: ArrayLike) -> NDArray[np.float64]:
        return np.array(self.center) + self.radius * np.asarray(normal, dtype=float)

    @classmethod
    def press_model(cls) -> PressModel:
        return _SphericalPress()

    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        return grid_mesh(self, np.asarray(self.center) + self.radius * uv_sphere(n_around, n_along))

    @classmethod
    def from_table(cls, table: dict, source: str) -> Fingertip:
        kwargs = fields_from_table(table, source, "sphere", {"radius": True, "center": False, "skin_thickness": False})
        return _construct(cls, kwargs, source)

    def to_toml(self) -> str:
        c = ", ".join(fmt(v) for v in self.center)
        return f'[fingertip]\nshape = "sphere"\nradius = {fmt(self.radius)}\ncenter = [{c}]\n' + skin_toml(self)


def _construct(cls, kwargs: dict, source: str) -> Fingertip:
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: [fingertip] {exc}") from None


# -- capsule ------------------------------------------------------------------------------------

#: Capsule presses whose contact normal is less than this far above the equator may touch
#: the cylinder side (the contact patch reaches ~15° around its centre at a few N).
_CAP_MIN_NZ = math.sin(math.radians(20.0))


class _CapPress(_SphericalPress):
    """The capsule's cap: its centre ``(x, y, length)`` and radius, from presses on the cap."""

    centre_name = "cap centre"
    region = "on the capsule's cap (contact normal ≥ 20° above the equator)"

    def accepts(self, normals: NDArray) -> NDArray[np.bool_]:
        return normals[:, 2] >= _CAP_MIN_NZ

    def tip(self, x: NDArray, source: str) -> Fingertip:
        if not x[2] >= 0.0:
            raise InputError(f"{source}: the fitted cap centre is at z = {x[2] * 1e3:.3f} mm, below the sensor; expected ≥ 0")
        return Capsule(radius=x[3], length=x[2], axis_offset=tuple(x[:2]))

    def report(self, x: NDArray, std: NDArray) -> tuple[list[str], list[str]]:
        head, _ = super().report(x, std)
        mm = 1e3
        return head, [f"  length     {x[2] * mm:.3f} ± {std[2] * mm:.3f} mm (cap centre height); axis offset x, y = cap centre x, y"]


@jitable
def _capsule_kernel(fx, fy, fz, mx, my, mz, radius, length, ox, oy, xp):
    # an axis through (ox, oy): solve about that point (m' = m − o × f), then shift back
    mx = mx - oy * fz  # o × f = (oy fz, −ox fz, ox fy − oy fx)
    my = my + ox * fz
    mz = mz - (ox * fy - oy * fx)
    rx, ry, rz, nx, ny, nz, sig, valid = _centred_capsule_kernel(fx, fy, fz, mx, my, mz, radius, length, xp)
    return rx + ox, ry + oy, rz, nx, ny, nz, sig, valid


@jitable
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


@jitable
def _height_above_cap(z, length, xp):
    # distance along the axis above the cap centre, 0 on the cylinder part
    dz = z - length
    return xp.where(dz > 0.0, dz, 0.0 * dz)


@jitable
def capsule_normal_kernel(x, y, z, length, ox, oy, xp):
    """The outward unit normal of a capsule (cap centre at height ``length``, axis through
    ``(ox, oy)``, m) at ``(x, y, z)``, component-wise."""
    x, y = x - ox, y - oy
    dz = _height_above_cap(z, length, xp)
    norm = xp.sqrt(x * x + y * y + dz * dz)
    return xp.div(x, norm), xp.div(y, norm), xp.div(dz, norm)


@jitable
def capsule_project_kernel(x, y, z, radius, length, ox, oy, xp):
    """The point of a capsule's skin nearest to ``(x, y, z)`` (m), component-wise."""
    nx, ny, nz = capsule_normal_kernel(x, y, z, length, ox, oy, xp)
    zc = xp.where(z > length, length + 0.0 * z, z)
    return ox + radius * nx, oy + radius * ny, zc + radius * nz


@dataclass(frozen=True)
class Capsule(Fingertip):
    """The papers' fingertip: cylinder of ``radius`` along +z from ``z = 0`` to ``length``,
    capped by a hemisphere centred at ``(x₀, y₀, length)``. Both in metres.

    ``axis_offset = (x₀, y₀)`` (m, default ``(0, 0)``) shifts the axis in the sensor's
    x–y plane: a fingertip mounted off-centre (``softtip calibrate --shape capsule``
    measures it). The skin below ``z = 0`` (where the fingertip meets the sensor) does not
    exist; ``S`` there is that of the infinite cylinder.
    """

    radius: float
    length: float
    axis_offset: tuple[float, float] = (0.0, 0.0)
    skin_thickness: float | None = field(default=None, compare=False)
    kind: ClassVar[str] = "capsule"
    calibrates: ClassVar[str | None] = "presses"

    def __post_init__(self) -> None:
        check_skin(self)
        object.__setattr__(self, "radius", positive(self.radius, "radius"))
        length = float(self.length)
        if not (math.isfinite(length) and length >= 0.0):
            raise ValueError(f"length must be a non-negative length in metres, got {self.length!r}")
        object.__setattr__(self, "length", length)
        off = np.asarray(self.axis_offset, dtype=float)
        if off.shape != (2,) or not np.all(np.isfinite(off)):
            raise ValueError(f"axis_offset must be 2 finite numbers (x, y) in metres, got {self.axis_offset!r}")
        object.__setattr__(self, "axis_offset", (float(off[0]), float(off[1])))

    def _surface_kernel(self, x, y, z, xp):
        x, y = x - self.axis_offset[0], y - self.axis_offset[1]
        dz = _height_above_cap(z, self.length, xp)
        return xp.sqrt(x * x + y * y + dz * dz) - self.radius

    def _normal_kernel(self, x, y, z, xp):
        return capsule_normal_kernel(x, y, z, self.length, *self.axis_offset, xp)

    def _project_kernel(self, x, y, z, xp):
        return capsule_project_kernel(x, y, z, self.radius, self.length, *self.axis_offset, xp)

    @property
    def twist_radius(self) -> float:
        return float(self.radius)

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        half = 0.5 * (self.length + self.radius)
        return np.array([*self.axis_offset, half]), math.hypot(self.radius, half)

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp):
        return _capsule_kernel(fx, fy, fz, mx, my, mz, self.radius, self.length, *self.axis_offset, xp)

    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """The cap as a Fibonacci lattice, the side from ``z_min`` (m, default 0: the sensor
        flange) up as a staggered (brick) grid. See :meth:`Fingertip.skin_elements`."""
        r, length = self.radius, self.length
        z0 = 0.0 if z_min is None else float(z_min)
        if z0 > length:
            raise ValueError(f"z_min must not exceed the capsule length {length} m, got {z0}")
        a_cap = 2.0 * math.pi * r * r
        a_side = 2.0 * math.pi * r * (length - z0)
        h = math.sqrt((a_cap + a_side) / n_elements)
        n_cap = max(1, round(a_cap / (h * h)))
        u, w = fibonacci_cap(n_cap, 0.0)
        ox, oy = self.axis_offset
        centres = [u * r + np.array([ox, oy, length])]
        normals = [u]
        areas = [w * r * r]
        if a_side > 0.0:
            n_phi = max(3, round(2.0 * math.pi * r / h))
            n_z = max(1, round((length - z0) / h))
            dphi, dz = 2.0 * math.pi / n_phi, (length - z0) / n_z
            j, i = np.meshgrid(np.arange(n_z), np.arange(n_phi), indexing="ij")
            phi = (i + 0.5 * (j % 2)).ravel() * dphi  # staggered rows: a brick pattern
            z = z0 + (j.ravel() + 0.5) * dz
            nrm = np.column_stack((np.cos(phi), np.sin(phi), np.zeros_like(phi)))
            centres.append(np.column_stack((ox + r * nrm[:, 0], oy + r * nrm[:, 1], z)))
            normals.append(nrm)
            areas.append(np.full(len(phi), r * dphi * dz))
        return np.concatenate(centres), np.concatenate(normals), np.concatenate(areas)

    def support_point(self, normal: ArrayLike) -> NDArray[np.float64]:
        """The point of the cap whose outward normal is ``normal`` (unit, ``n_z ≥ 0``), m."""
        n = np.asarray(normal, dtype=float)
        if np.any(n[..., 2] < 0.0):
            raise ValueError("a capsule's skin point for a normal is on its cap: normals need n_z >= 0")
        return np.array([*self.axis_offset, self.length]) + self.radius * n

    @classmethod
    def press_model(cls) -> PressModel:
        return _CapPress()

    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        # profile: the cylinder from the sensor (z = 0) up, then the hemisphere to the tip
        phi = np.linspace(0.0, 2.0 * np.pi, n_around, endpoint=False)
        n_cyl = max(2, n_along // 3) if self.length > 0 else 0
        z_cyl = np.linspace(0.0, self.length, n_cyl, endpoint=False)
        a = np.linspace(0.5 * np.pi, 0.0, n_along - n_cyl)
        rho = np.concatenate((np.full(n_cyl, self.radius), self.radius * np.sin(a)))
        z = np.concatenate((z_cyl, self.length + self.radius * np.cos(a)))
        pts = np.stack(
            [
                self.axis_offset[0] + rho[:, None] * np.cos(phi),
                self.axis_offset[1] + rho[:, None] * np.sin(phi),
                np.broadcast_to(z[:, None], (len(z), n_around)),
            ],
            axis=-1,
        )
        return grid_mesh(self, pts)

    @classmethod
    def from_table(cls, table: dict, source: str) -> Fingertip:
        fields = {"radius": True, "length": True, "axis_offset": False, "skin_thickness": False}
        return _construct(cls, fields_from_table(table, source, "capsule", fields, pairs=("axis_offset",)), source)

    def to_toml(self) -> str:
        text = f'[fingertip]\nshape = "capsule"\nradius = {fmt(self.radius)}\nlength = {fmt(self.length)}\n'
        if self.axis_offset != (0.0, 0.0):
            text += f"axis_offset = [{', '.join(fmt(v) for v in self.axis_offset)}]\n"
        return text + skin_toml(self)


# -- ellipsoid ----------------------------------------------------------------------------------


class _EllipsoidPress(PressModel):
    """An axis-aligned ellipsoid's centre and semi-axes: the contact point for the normal ``n``
    is ``c + D² n / |D n| − δ n`` (``D = diag(a, b, c)``)."""

    names = ("centre x", "centre y", "centre z", "semi-axis a", "semi-axis b", "semi-axis c")
    coverage = "±85° around the tip, down to its widest part: within ±60° its centre's height and semi-axis c are nearly one unknown"

    def start(self, center: NDArray, radius: float) -> NDArray:
        return np.concatenate((center * 1e3, [radius * 1e3] * 3))

    def points(self, x: NDArray, normals: NDArray, depth: NDArray) -> NDArray:
        d = x[3:6]
        dn = d * normals
        return x[:3] + (d * dn) / np.sqrt(np.sum(dn * dn, axis=1))[:, None] - depth[:, None] * normals

    def tip(self, x: NDArray, source: str) -> Fingertip:
        return Ellipsoid(semi_axes=tuple(x[3:6]), center=tuple(x[:3]))

    def stds(self, std: NDArray) -> dict[str, float]:
        return dict(zip(self.names[3:] + self.names[:3], np.concatenate((std[3:6], std[:3]))))

    def report(self, x: NDArray, std: NDArray) -> tuple[list[str], list[str]]:
        mm = 1e3
        c, cs, a, s = x[:3] * mm, std[:3] * mm, x[3:6] * mm, std[3:6] * mm
        return [
            f"  centre     x = {c[0]:+.3f} ± {cs[0]:.3f} mm, y = {c[1]:+.3f} ± {cs[1]:.3f} mm, z = {c[2]:+.3f} ± {cs[2]:.3f} mm",
            f"  semi-axes  a = {a[0]:.3f} ± {s[0]:.3f} mm, b = {a[1]:.3f} ± {s[1]:.3f} mm, c = {a[2]:.3f} ± {s[2]:.3f} mm",
        ], []

    def std_line(self, std: NDArray) -> str:
        mm = 1e3
        return (
            "semi-axes std " + ", ".join(f"{v * mm:.4f}" for v in std[3:6])
            + " mm; centre std " + ", ".join(f"{v * mm:.4f}" for v in std[:3]) + " mm"
        )


@jitable
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


@jitable
def ellipsoid_normal_kernel(x, y, z, a, b, c, cx, cy, cz, xp):
    """The outward unit normal of an axis-aligned ellipsoid (semi-axes ``a, b, c``, centre ``c``, m)
    at ``(x, y, z)``, component-wise."""
    sx, sy, sz = (x - cx) / a, (y - cy) / b, (z - cz) / c
    gx, gy, gz = sx / a, sy / b, sz / c
    norm = xp.sqrt(gx * gx + gy * gy + gz * gz)
    return xp.div(gx, norm), xp.div(gy, norm), xp.div(gz, norm)


@jitable
def ellipsoid_project_kernel(x, y, z, a, b, c, cx, cy, cz, xp):
    """The point of an axis-aligned ellipsoid's skin on the ray from its centre through ``(x, y, z)``
    (m), component-wise."""
    sx, sy, sz = (x - cx) / a, (y - cy) / b, (z - cz) / c
    s = xp.sqrt(sx * sx + sy * sy + sz * sz)
    return cx + a * xp.div(sx, s), cy + b * xp.div(sy, s), cz + c * xp.div(sz, s)


@dataclass(frozen=True)
class Ellipsoid(Fingertip):
    """Axis-aligned ellipsoid with ``semi_axes`` (m) centred at ``center`` (m)."""

    semi_axes: tuple[float, float, float]
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    skin_thickness: float | None = field(default=None, compare=False)
    kind: ClassVar[str] = "ellipsoid"
    calibrates: ClassVar[str | None] = "presses"

    def __post_init__(self) -> None:
        check_skin(self)
        axes = vec3(self.semi_axes, "semi_axes")
        for a in axes:
            positive(a, "each of semi_axes")
        object.__setattr__(self, "semi_axes", axes)
        object.__setattr__(self, "center", vec3(self.center, "center"))

    def _scaled(self, x, y, z):
        a, b, c = self.semi_axes
        cx, cy, cz = self.center
        return (x - cx) / a, (y - cy) / b, (z - cz) / c

    def _surface_kernel(self, x, y, z, xp):
        # S = |D⁻¹ p| - 1: dimensionless, zero on the skin
        sx, sy, sz = self._scaled(x, y, z)
        return xp.sqrt(sx * sx + sy * sy + sz * sz) - 1.0

    def _normal_kernel(self, x, y, z, xp):
        return ellipsoid_normal_kernel(x, y, z, *self.semi_axes, *self.center, xp)

    def _project_kernel(self, x, y, z, xp):
        return ellipsoid_project_kernel(x, y, z, *self.semi_axes, *self.center, xp)

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return np.array(self.center), max(self.semi_axes)

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp):
        return _ellipsoid_kernel(fx, fy, fz, mx, my, mz, *self.semi_axes, *self.center, xp)

    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """The sphere's Fibonacci lattice mapped onto the ellipsoid (``p = c + D u``), from the
        top down to ``z_min`` (m; default ``center_z − c/2``, as the sphere's 120°).

        An element's area is its area on the unit sphere times ``abc |D⁻¹ u|`` (the area
        scale of ``D`` on the tangent plane with normal ``u``), so the areas sum to the
        covered skin's area; elements are smaller where the skin is more curved.
        See :meth:`Fingertip.skin_elements`.
        """
        d = np.array(self.semi_axes)
        cen = np.array(self.center)
        zc = cen[2] - 0.5 * d[2] if z_min is None else float(z_min)
        cos_min = min(max((zc - cen[2]) / d[2], -1.0), 1.0)
        if cos_min >= 1.0:
            raise ValueError(f"z_min {zc} m leaves no skin on the ellipsoid")
        u, w = fibonacci_cap(n_elements, cos_min)
        g = u / d  # ∝ the outward normal at c + D u
        gn = np.linalg.norm(g, axis=1)
        return cen + d * u, g / gn[:, None], w * np.prod(d) * gn

    def support_point(self, normal: ArrayLike) -> NDArray[np.float64]:
        n = np.asarray(normal, dtype=float)
        d = np.array(self.semi_axes)
        dn = d * n
        return np.array(self.center) + d * dn / np.linalg.norm(dn, axis=-1, keepdims=True)

    @classmethod
    def press_model(cls) -> PressModel:
        return _EllipsoidPress()

    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        return grid_mesh(self, np.asarray(self.center) + np.asarray(self.semi_axes) * uv_sphere(n_around, n_along))

    @classmethod
    def from_table(cls, table: dict, source: str) -> Fingertip:
        fields = {"semi_axes": True, "center": False, "skin_thickness": False}
        return _construct(cls, fields_from_table(table, source, "ellipsoid", fields), source)

    def to_toml(self) -> str:
        a = ", ".join(fmt(v) for v in self.semi_axes)
        c = ", ".join(fmt(v) for v in self.center)
        return f'[fingertip]\nshape = "ellipsoid"\nsemi_axes = [{a}]\ncenter = [{c}]\n' + skin_toml(self)


# -- presets, the registry and the fingertip file -----------------------------------------------


def murakami2006() -> Capsule:
    """The papers' fingertip: capsule of radius 16 mm (11 mm aluminium shell + 5 mm skin).

    The papers do not give the cylinder length; 20 mm is softtip's choice (manual §2). The
    5 mm skin switches on the online depth compensation (:mod:`softtip.estimator.depth`).
    """
    return Capsule(radius=0.016, length=0.020, skin_thickness=0.005)


#: Named fingertips accepted wherever a fingertip file is.
PRESETS: dict[str, Callable[[], Fingertip]] = {"murakami2006": murakami2006}

#: The shapes a fingertip file's ``shape`` names (manual §2), and ``softtip calibrate
#: --shape``'s choices (those that calibrate). Adding a shape is its module and a line here
#: (docs/shapes.md). :class:`ImplicitSurface` is made in Python (its ``S`` is code), so no
#: file names it.
SHAPES: dict[str, type[Fingertip]] = {
    "sphere": Sphere,
    "capsule": Capsule,
    "ellipsoid": Ellipsoid,
    "mesh": MeshFingertip,
}


def load_fingertip(spec: str | Path | Fingertip) -> Fingertip:
    """A fingertip from a preset name or a fingertip TOML file (manual §2).

    Parameters
    ----------
    spec : str, Path or Fingertip
        A preset name (see :data:`PRESETS`), a path to a ``.toml`` file, or a fingertip
        (returned unchanged).

    Raises
    ------
    InputError
        Unknown preset, unreadable file, malformed TOML, unknown shape, missing, unknown or
        invalid keys. The message names the file and the key.
    """
    if isinstance(spec, Fingertip):
        return spec
    name = str(spec)
    if name in PRESETS:
        return PRESETS[name]()
    path = Path(name)
    if not path.exists():
        if path.suffix.lower() != ".toml" and _looks_like_name(name):
            raise InputError(
                f"unknown fingertip preset {name!r}; expected one of "
                f"{', '.join(sorted(PRESETS))} or a path to a .toml fingertip file"
            )
        raise InputError(f"{name}: fingertip file not found")
    if path.suffix.lower() in MESH_SUFFIXES:  # read as TOML, it would be "malformed TOML"
        raise InputError(
            f"{name}: a mesh file, not a fingertip file; expected a fingertip TOML naming it: [fingertip] mesh = "
            f'"{path.name}", mesh_units = "mm" (or m, cm...) (manual §2)'
        )
    from softtip.tomlfile import read_toml

    return fingertip_from_mapping(read_toml(path, "fingertip"), source=str(path))


def _looks_like_name(name: str) -> bool:
    """True when ``name`` looks like a bare word (a preset name), not a path."""
    return "/" not in name and "\\" not in name


def _shape_name(table: dict) -> str | None:
    """The shape a ``[fingertip]`` table names: its ``shape``, else the shape a key implies
    (``mesh = "…"``: a mesh), else None."""
    shape = table.get("shape")
    if shape is None:
        shape = next((name for name, cls in SHAPES.items() if cls.implied_by is not None and cls.implied_by in table), None)
    return shape


def fingertip_from_mapping(data: dict, source: str = "<fingertip>") -> Fingertip:
    """Build a fingertip from the parsed TOML mapping (``{"fingertip": {...}}``).

    The ``[fingertip]`` table's ``shape`` picks the class in :data:`SHAPES`, which reads the
    rest (:meth:`~softtip.core.shape.Fingertip.from_table`); a ``[fingertip.mount]`` places
    it on the sensor (:class:`~softtip.core.mounting.Mounted`) unless the shape reads it itself.
    """
    table = fingertip_table(data, source)
    shape = _shape_name(table)
    cls = SHAPES.get(shape) if isinstance(shape, str) else None
    mount = table.get("mount")
    if mount is not None and not (cls is not None and cls.reads_mount):
        # [fingertip.mount]: the tip's pose in the sensor frame
        inner = {k: v for k, v in table.items() if k != "mount"}
        return mount_from_mapping(fingertip_from_mapping({"fingertip": inner}, source), mount, source)
    if cls is None:
        given = "has no shape key" if shape is None else f"shape = {shape!r}"
        raise InputError(f"{source}: [fingertip] {given}; expected shape = one of {', '.join(SHAPES)}")
    tip = cls.from_table(table, source)
    check_size(tip, source)  # a file in mm: 1000× too large
    return tip
