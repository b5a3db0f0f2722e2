"""Fingertip geometry: the outer skin surface ``S(r) = 0`` in the sensor frame.

Shapes (manual §2): :class:`Sphere`, :class:`Capsule` (the papers' fingertip: a cylinder
along +z from ``z = 0`` capped by a hemisphere centred at ``(0, 0, length)``),
:class:`Ellipsoid` (axis-aligned, Bicchi's quadric case) and :class:`ImplicitSurface`
(any callable ``S`` with its gradient). ``S < 0`` inside, ``S > 0`` outside; the outward
normal is ``∇S / |∇S|`` (paper Eq. 2). Lengths are in metres.

Each shape exposes batch methods on arrays of shape ``(..., 3)`` and, for the streaming
estimator, component-wise kernels (``_normal_kernel``, ``_project_kernel``) that take
either numpy arrays or Python floats (see :mod:`softtip.core._xp`).
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import NP, PY
from softtip.errors import InputError


__all__ = [
    "Fingertip",
    "Sphere",
    "Capsule",
    "Ellipsoid",
    "ImplicitSurface",
    "PRESETS",
    "murakami2006",
    "load_fingertip",
]


def _vec3(value: ArrayLike, name: str) -> tuple[float, float, float]:
    a = np.asarray(value, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be 3 finite numbers (m), got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _positive(value: float, name: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a positive length in metres, got {value!r}")
    return v


def _split(points: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must have shape (..., 3), got {p.shape}")
    return p[..., 0], p[..., 1], p[..., 2]


class Fingertip(abc.ABC):
    """Base class of the fingertip shapes.

    Subclasses define the component-wise kernels; the array methods below wrap them.
    """

    kind: ClassVar[str] = ""

    # -- kernels (components in, components out; xp is softtip.core._xp.NP or PY) --------------
    @abc.abstractmethod
    def _surface_kernel(self, x, y, z, xp):
        """``S`` at the point ``(x, y, z)``."""

    @abc.abstractmethod
    def _normal_kernel(self, x, y, z, xp):
        """Outward unit normal ``(nx, ny, nz)`` at ``(x, y, z)``."""

    @abc.abstractmethod
    def _project_kernel(self, x, y, z, xp):
        """The point of the skin nearest ``(x, y, z)`` (see :meth:`project`)."""

    # -- array API ----------------------------------------------------------------------
    def surface(self, points: ArrayLike) -> NDArray[np.float64]:
        """Value of ``S`` at ``points``, shape ``(...,)``; negative inside, 0 on the skin."""
        return np.asarray(self._surface_kernel(*_split(points), NP), dtype=float)

    def normal(self, points: ArrayLike) -> NDArray[np.float64]:
        """Outward unit normal ``∇S/|∇S|`` at ``points``, shape ``(..., 3)``."""
        return np.stack(self._normal_kernel(*_split(points), NP), axis=-1)

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map points near the skin onto it, shape ``(..., 3)``.

        Exact closest point for the sphere and the capsule; a radial (ellipsoid) or
        gradient-Newton (implicit) projection otherwise, which is the closest point to
        first order for points within a fraction of a millimetre of the surface.
        """
        return np.stack(self._project_kernel(*_split(points), NP), axis=-1)

    @property
    @abc.abstractmethod
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        """Centre (m, shape (3,)) and radius (m) of a sphere containing the whole skin."""

    @abc.abstractmethod
    def to_toml(self) -> str:
        """The fingertip as a fingertip TOML file (manual §2)."""


def _fmt(v: float) -> str:
    return repr(float(v))


def _skin(tip) -> None:
    """Validate the optional ``skin_thickness`` (m) of a fingertip dataclass."""
    h = tip.skin_thickness
    if h is not None:
        object.__setattr__(tip, "skin_thickness", _positive(h, "skin_thickness"))


def _skin_toml(tip) -> str:
    h = getattr(tip, "skin_thickness", None)
    return "" if h is None else f"skin_thickness = {_fmt(h)}\n"


@dataclass(frozen=True)
class Sphere(Fingertip):
    """Spherical skin of ``radius`` (m) centred at ``center`` (m, sensor frame)."""

    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    skin_thickness: float | None = field(default=None, compare=False)
    kind: ClassVar[str] = "sphere"

    def __post_init__(self) -> None:
        _skin(self)
        object.__setattr__(self, "radius", _positive(self.radius, "radius"))
        object.__setattr__(self, "center", _vec3(self.center, "center"))

    def _surface_kernel(self, x, y, z, xp):
        cx, cy, cz = self.center
        px, py, pz = x - cx, y - cy, z - cz
        return xp.sqrt(px * px + py * py + pz * pz) - self.radius

    def _normal_kernel(self, x, y, z, xp):
        cx, cy, cz = self.center
        px, py, pz = x - cx, y - cy, z - cz
        norm = xp.sqrt(px * px + py * py + pz * pz)
        return xp.div(px, norm), xp.div(py, norm), xp.div(pz, norm)

    def _project_kernel(self, x, y, z, xp):
        cx, cy, cz = self.center
        nx, ny, nz = self._normal_kernel(x, y, z, xp)
        r = self.radius
        return cx + r * nx, cy + r * ny, cz + r * nz

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return np.array(self.center), self.radius

    def to_toml(self) -> str:
        c = ", ".join(_fmt(v) for v in self.center)
        return f'[fingertip]\nshape = "sphere"\nradius = {_fmt(self.radius)}\ncenter = [{c}]\n' + _skin_toml(self)


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

    def __post_init__(self) -> None:
        _skin(self)
        object.__setattr__(self, "radius", _positive(self.radius, "radius"))
        length = float(self.length)
        if not (math.isfinite(length) and length >= 0.0):
            raise ValueError(f"length must be a non-negative length in metres, got {self.length!r}")
        object.__setattr__(self, "length", length)
        off = np.asarray(self.axis_offset, dtype=float)
        if off.shape != (2,) or not np.all(np.isfinite(off)):
            raise ValueError(f"axis_offset must be 2 finite numbers (x, y) in metres, got {self.axis_offset!r}")
        object.__setattr__(self, "axis_offset", (float(off[0]), float(off[1])))

    def _height_above_cap(self, z, xp):
        # distance along the axis above the cap centre, 0 on the cylinder part
        dz = z - self.length
        return xp.where(dz > 0.0, dz, 0.0 * dz)

    def _surface_kernel(self, x, y, z, xp):
        x, y = x - self.axis_offset[0], y - self.axis_offset[1]
        dz = self._height_above_cap(z, xp)
        return xp.sqrt(x * x + y * y + dz * dz) - self.radius

    def _normal_kernel(self, x, y, z, xp):
        x, y = x - self.axis_offset[0], y - self.axis_offset[1]
        dz = self._height_above_cap(z, xp)
        norm = xp.sqrt(x * x + y * y + dz * dz)
        return xp.div(x, norm), xp.div(y, norm), xp.div(dz, norm)

    def _project_kernel(self, x, y, z, xp):
        nx, ny, nz = self._normal_kernel(x, y, z, xp)
        r = self.radius
        zc = xp.where(z > self.length, self.length + 0.0 * z, z)
        return self.axis_offset[0] + r * nx, self.axis_offset[1] + r * ny, zc + r * nz

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        half = 0.5 * (self.length + self.radius)
        return np.array([*self.axis_offset, half]), math.hypot(self.radius, half)

    def to_toml(self) -> str:
        text = f'[fingertip]\nshape = "capsule"\nradius = {_fmt(self.radius)}\nlength = {_fmt(self.length)}\n'
        if self.axis_offset != (0.0, 0.0):
            text += f"axis_offset = [{', '.join(_fmt(v) for v in self.axis_offset)}]\n"
        return text + _skin_toml(self)


@dataclass(frozen=True)
class Ellipsoid(Fingertip):
    """Axis-aligned ellipsoid with ``semi_axes`` (m) centred at ``center`` (m)."""

    semi_axes: tuple[float, float, float]
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    skin_thickness: float | None = field(default=None, compare=False)
    kind: ClassVar[str] = "ellipsoid"

    def __post_init__(self) -> None:
        _skin(self)
        axes = _vec3(self.semi_axes, "semi_axes")
        for a in axes:
            _positive(a, "each of semi_axes")
        object.__setattr__(self, "semi_axes", axes)
        object.__setattr__(self, "center", _vec3(self.center, "center"))

    def _scaled(self, x, y, z):
        a, b, c = self.semi_axes
        cx, cy, cz = self.center
        return (x - cx) / a, (y - cy) / b, (z - cz) / c

    def _surface_kernel(self, x, y, z, xp):
        # S = |D⁻¹ p| - 1: dimensionless, zero on the skin
        sx, sy, sz = self._scaled(x, y, z)
        return xp.sqrt(sx * sx + sy * sy + sz * sz) - 1.0

    def _normal_kernel(self, x, y, z, xp):
        a, b, c = self.semi_axes
        sx, sy, sz = self._scaled(x, y, z)
        gx, gy, gz = sx / a, sy / b, sz / c
        norm = xp.sqrt(gx * gx + gy * gy + gz * gz)
        return xp.div(gx, norm), xp.div(gy, norm), xp.div(gz, norm)

    def _project_kernel(self, x, y, z, xp):
        a, b, c = self.semi_axes
        cx, cy, cz = self.center
        sx, sy, sz = self._scaled(x, y, z)
        s = xp.sqrt(sx * sx + sy * sy + sz * sz)
        return cx + a * xp.div(sx, s), cy + b * xp.div(sy, s), cz + c * xp.div(sz, s)

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        return np.array(self.center), max(self.semi_axes)

    def to_toml(self) -> str:
        a = ", ".join(_fmt(v) for v in self.semi_axes)
        c = ", ".join(_fmt(v) for v in self.center)
        return f'[fingertip]\nshape = "ellipsoid"\nsemi_axes = [{a}]\ncenter = [{c}]\n' + _skin_toml(self)


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
        object.__setattr__(self, "center", _vec3(self.center, "center"))
        object.__setattr__(self, "radius", _positive(self.radius, "radius"))

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

    def to_toml(self) -> str:
        raise ValueError("an implicit surface given as Python callables has no TOML form")


def murakami2006() -> Capsule:
    """The papers' fingertip: capsule of radius 16 mm (11 mm aluminium shell + 5 mm skin).

    The papers do not give the cylinder length; 20 mm is softtip's choice (manual §2). The
    5 mm skin switches on the online depth compensation (:mod:`softtip.estimator.depth`).
    """
    return Capsule(radius=0.016, length=0.020, skin_thickness=0.005)


#: Named fingertips accepted wherever a fingertip file is.
PRESETS: dict[str, Callable[[], Fingertip]] = {"murakami2006": murakami2006}

_FIELDS = {
    "sphere": {"radius": True, "center": False, "skin_thickness": False},
    "capsule": {"radius": True, "length": True, "axis_offset": False, "skin_thickness": False},
    "ellipsoid": {"semi_axes": True, "center": False, "skin_thickness": False},
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
    from softtip.io.tomlfile import read_toml

    return fingertip_from_mapping(read_toml(path, "fingertip"), source=str(path))


def _looks_like_name(name: str) -> bool:
    """True when ``name`` looks like a bare word (a preset name), not a path."""
    return "/" not in name and "\\" not in name


def fingertip_from_mapping(data: dict, source: str = "<fingertip>") -> Fingertip:
    """Build a fingertip from the parsed TOML mapping (``{"fingertip": {...}}``)."""
    table = data.get("fingertip")
    if not isinstance(table, dict):
        raise InputError(f"{source}: expected a [fingertip] table")
    mount = table.get("mount")
    if mount is not None and table.get("shape", "mesh" if "mesh" in table else None) != "mesh":
        # [fingertip.mount]: the tip's pose in the sensor frame (a mesh applies it to its vertices)
        from softtip.core.mounting import mount_from_mapping

        inner = {k: v for k, v in table.items() if k != "mount"}
        return mount_from_mapping(fingertip_from_mapping({"fingertip": inner}, source), mount, source)
    shape = table.get("shape")
    if shape == "mesh" or (shape is None and "mesh" in table):
        # a triangle mesh file (softtip.core.mesh; trimesh is imported only then)
        from softtip.core.mesh import mesh_fingertip_from_table

        return mesh_fingertip_from_table(table, source)
    if shape not in _FIELDS:
        raise InputError(
            f"{source}: [fingertip] shape = {shape!r}; expected one of {', '.join((*_FIELDS, 'mesh'))}"
        )
    fields = _FIELDS[shape]
    unknown = sorted(set(table) - set(fields) - {"shape"})
    if unknown:
        raise InputError(
            f"{source}: [fingertip] unknown key(s) {', '.join(unknown)} for shape {shape!r}; "
            f"expected {', '.join(fields)}"
        )
    missing = [k for k, required in fields.items() if required and k not in table]
    if missing:
        raise InputError(f"{source}: [fingertip] missing key(s) {', '.join(missing)} for shape {shape!r}")
    kwargs = {k: table[k] for k in fields if k in table}
    for key, value in kwargs.items():
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        size = 2 if key == "axis_offset" else 3
        if isinstance(value, list):
            ok = len(value) == size and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        elif key == "axis_offset":
            ok = False
        if not ok:
            what = "a list of 2 numbers [x, y]" if key == "axis_offset" else "a number (or a list of 3)"
            raise InputError(f"{source}: [fingertip] {key} = {value!r} is not {what} in metres")
    cls = {"sphere": Sphere, "capsule": Capsule, "ellipsoid": Ellipsoid}[shape]
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: [fingertip] {exc}") from None
