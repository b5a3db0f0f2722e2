"""The fingertip shape protocol: what every skin shape implements, in one place per shape.

A shape is a subclass of :class:`Fingertip` (docs/shapes.md). It gives, in its own module:

* **surface** — the component-wise kernels ``_surface_kernel`` (``S``, negative inside),
  ``_normal_kernel`` (outward unit normal ``∇S/|∇S|``), ``_project_kernel`` (the nearest skin
  point) and :attr:`~Fingertip.bounding_sphere`; the array methods :meth:`~Fingertip.surface`,
  :meth:`~Fingertip.normal` and :meth:`~Fingertip.project` wrap them;
* **contact solve** — ``_contact_kernel``: the soft-finger solution of ``m = r × f + σ n(r)``
  on the skin, closed form or general, component-wise on floats or arrays
  (:mod:`softtip.core._xp`);
* **simulator skin** — :meth:`~Fingertip.skin_elements`: the touchable skin as small surface
  elements (:mod:`softtip.sim.skin`), and :meth:`~Fingertip.support_point` and
  :meth:`~Fingertip.apex_hint` for where the simulator's scenarios touch;
* **calibration** — :attr:`~Fingertip.calibrates` and :meth:`~Fingertip.press_model`: the
  parameters ``softtip calibrate`` fits from plane presses (:class:`PressModel`);
* **mesh export and view** — :meth:`~Fingertip.surface_mesh`, a triangle mesh of the skin;
* **file form** — :meth:`~Fingertip.from_table` and :meth:`~Fingertip.to_toml`, the
  ``[fingertip]`` TOML table (manual §2).

The shapes a fingertip file can name are listed in :data:`softtip.core.fingertip.SHAPES`.
This module also holds what the shapes share: the batch contact result :class:`Contact`, its
component-wise form :class:`SoftFinger`, and :func:`sphere_kernel`, the closed-form solution
on a sphere that the other closed forms and the general solvers' restarts build on.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._jit import jitable
from softtip.core._xp import NP
from softtip.errors import InputError

__all__ = ["Contact", "Fingertip", "PressModel", "SoftFinger", "sphere_kernel"]


# -- the contact solution ----------------------------------------------------------------------


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


@jitable
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


# -- calibration from plane presses -------------------------------------------------------------


class PressModel(abc.ABC):
    """The geometry ``softtip calibrate`` fits from plane presses, for one shape.

    During a press against a flat surface the contact normal ``n`` is fixed, so the contact
    point is the skin point whose outward normal is ``n`` (:meth:`points`), moved in by the
    skin's indentation. :mod:`softtip.calibration.probing` fits the parameters :attr:`names`
    (lengths in mm inside the fit, centre first) with the indentation and one normal per press.
    """

    #: Names of the fitted parameters, in order (messages and reports); the first three are
    #: the centre's x, y, z.
    names: ClassVar[tuple[str, ...]] = ()
    #: Where presses must be to enter the fit (messages), "" when anywhere on the skin.
    region: ClassVar[str] = ""
    #: How far around the tip presses must spread to determine the parameters (messages).
    coverage: ClassVar[str] = "±60° around the tip"

    @abc.abstractmethod
    def start(self, center: NDArray, radius: float) -> NDArray:
        """Start parameters (mm) from the sphere (m) through the presses' contact points."""

    def accepts(self, normals: NDArray) -> NDArray[np.bool_]:
        """Which presses (their contact normals, shape (K, 3)) enter the fit; all by default."""
        return np.ones(len(normals), dtype=bool)

    @abc.abstractmethod
    def points(self, x: NDArray, normals: NDArray, depth: NDArray) -> NDArray:
        """Contact points (mm, shape (N, 3)) for parameters ``x`` (mm), normals (N, 3) and
        indentations ``depth`` (mm, shape (N,)) along ``−n``."""

    @abc.abstractmethod
    def tip(self, x: NDArray, source: str) -> Fingertip:
        """The fingertip of the fitted parameters ``x`` (m); InputError when it cannot be one."""

    @abc.abstractmethod
    def stds(self, std: NDArray) -> dict[str, float]:
        """The parameters' standard deviations (m) by name, the one reported first when
        several are equally large first (:meth:`~softtip.calibration.probing.Calibration.precision_warning`)."""

    @abc.abstractmethod
    def report(self, x: NDArray, std: NDArray) -> tuple[list[str], list[str]]:
        """Lines of the calibration report (mm) about the shape's parameters ``x`` and their
        standard deviations ``std`` (m): those before the indentation and residual, and those after."""

    @abc.abstractmethod
    def std_line(self, std: NDArray) -> str:
        """The standard deviations ``std`` (m) in one line (mm) for the calibrated file's header."""


# -- the protocol -------------------------------------------------------------------------------


def _split(points: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must have shape (..., 3), got {p.shape}")
    return p[..., 0], p[..., 1], p[..., 2]


class Fingertip(abc.ABC):
    """Base class of the fingertip shapes: the shape protocol (module docs).

    Subclasses define the component-wise kernels and :meth:`_contact_kernel`; the array
    methods below wrap them. The optional parts (simulator skin, calibration, file form)
    raise or are ``None`` by default.
    """

    #: The shape's name: a fingertip file's ``shape`` (:data:`softtip.core.fingertip.SHAPES`).
    kind: ClassVar[str] = ""
    #: A ``[fingertip]`` key that names the shape when ``shape`` is left out (``mesh``), or None.
    implied_by: ClassVar[str | None] = None
    #: The shape reads ``[fingertip.mount]`` itself (a mesh places its vertices); otherwise a
    #: mount wraps the shape in a :class:`~softtip.core.mounting.Mounted`.
    reads_mount: ClassVar[bool] = False
    #: What ``softtip calibrate --shape`` fits for this shape: ``"presses"`` (the geometry,
    #: :meth:`press_model`), ``"placement"`` (the pose of a given shape on the sensor,
    #: :mod:`softtip.calibration.mesh`) or None.
    calibrates: ClassVar[str | None] = None

    # -- surface (components in, components out; xp is softtip.core._xp.NP or PY) ---------------
    @abc.abstractmethod
    def _surface_kernel(self, x, y, z, xp):
        """``S`` at the point ``(x, y, z)``."""

    @abc.abstractmethod
    def _normal_kernel(self, x, y, z, xp):
        """Outward unit normal ``(nx, ny, nz)`` at ``(x, y, z)``."""

    @abc.abstractmethod
    def _project_kernel(self, x, y, z, xp):
        """The point of the skin nearest ``(x, y, z)`` (see :meth:`project`)."""

    @property
    def twist_radius(self) -> float | None:
        """The skin's radius of curvature (m) where one number describes it at every contact (a
        sphere's radius, a capsule's), else None: the lever of a line's tilt in the line
        evidence's twist term (:func:`softtip.estimator.evidence.twist_curvature`)."""
        return None

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

    # -- contact solve -------------------------------------------------------------------------
    @abc.abstractmethod
    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp=NP):
        """The soft-finger contact for the wrench ``(f, m)`` (N, N·m, sensor frame), component-wise.

        Returns ``(rx, ry, rz, nx, ny, nz, sigma, valid)`` (see
        :func:`softtip.core.location.contact_kernel`): floats with ``PY``, arrays with ``NP``.
        """

    # -- simulator skin ------------------------------------------------------------------------
    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """The touchable skin as about ``n_elements`` small surface elements (the simulator's skin).

        Parameters
        ----------
        n_elements : int
            Target element count.
        z_min : float, optional
            Lowest covered height, m (each shape documents its default).

        Returns
        -------
        centres : ndarray, shape (N, 3)
            Element centres on the skin, m.
        normals : ndarray, shape (N, 3)
            Outward unit normals there.
        areas : ndarray, shape (N,)
            Element areas, m².
        """
        raise TypeError(f"the simulator has no skin for a {type(self).__name__} (it implements no skin_elements)")

    def support_point(self, normal: ArrayLike) -> NDArray[np.float64]:
        """The skin point whose outward normal is ``normal`` (unit, shape (..., 3)), m, shape (..., 3)."""
        raise TypeError(f"a {type(self).__name__} gives no skin point for a normal (it implements no support_point)")

    def apex_hint(self) -> NDArray[np.float64]:
        """A point well outside the skin on the shape's own +z axis, m, shape (3,): projected
        onto the skin it is the apex, where a scenario touches by default."""
        centre, radius = self.bounding_sphere
        return centre + np.array([0.0, 0.0, 4.0 * radius])

    # -- calibration ---------------------------------------------------------------------------
    @classmethod
    def press_model(cls) -> PressModel:
        """The parameters ``softtip calibrate`` fits from plane presses (``calibrates == "presses"``)."""
        raise InputError(f"a {cls.kind or cls.__name__} fingertip cannot be calibrated from plane presses")

    # -- mesh export and view ----------------------------------------------------------------------
    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        """A triangle mesh of the skin in the sensor frame (views, export).

        By default a sphere grid over :attr:`bounding_sphere` projected onto the skin.

        Parameters
        ----------
        n_around, n_along : int
            Vertices around the shape's z axis and along the profile (tessellated shapes).

        Returns
        -------
        vertices : ndarray, shape (V, 3)
            m.
        triangles : ndarray of int32, shape (T, 3)
            Vertex indices, counter-clockwise seen from outside.
        normals : ndarray, shape (V, 3)
            Outward unit normals at the vertices.
        """
        center, radius = self.bounding_sphere
        return grid_mesh(self, self.project(center + radius * uv_sphere(n_around, n_along)))

    # -- file form -----------------------------------------------------------------------------
    @classmethod
    def from_table(cls, table: dict, source: str) -> Fingertip:
        """The shape from a parsed ``[fingertip]`` table of file ``source`` (manual §2).

        Raises
        ------
        InputError
            Missing, unknown or invalid keys (the message names the file and the key).
        """
        raise InputError(f"{source}: a {cls.kind or cls.__name__} fingertip has no file form")

    @abc.abstractmethod
    def to_toml(self) -> str:
        """The fingertip as a fingertip TOML file (manual §2)."""


# -- helpers the shapes share ------------------------------------------------------------------


def vec3(value: ArrayLike, name: str) -> tuple[float, float, float]:
    """``value`` as 3 finite floats (m); ValueError naming ``name`` otherwise."""
    a = np.asarray(value, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be 3 finite numbers (m), got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def positive(value: float, name: str) -> float:
    """``value`` as a positive finite float (m); ValueError naming ``name`` otherwise."""
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a positive length in metres, got {value!r}")
    return v


def fmt(v: float) -> str:
    """A float as TOML (round-trips exactly)."""
    return repr(float(v))


#: Plausible fingertip sizes (m, the diameter of its bounding sphere; a mesh's largest extent):
#: outside, a units mistake (a file in mm read as m is 1000× too large; a log's moments in N·mm
#: read as N·m calibrate a tip 1000× too small).
SIZE_RANGE = (0.002, 0.2)
#: Plausible skin thickness (m): from this to the fingertip's bounding radius.
MIN_SKIN_THICKNESS = 1e-4


def check_size(tip, source: str, fix: str = "lengths in a fingertip file are in metres: 16 mm is 0.016") -> None:
    """Stop a fingertip whose size, or whose skin, no fingertip has (:data:`SIZE_RANGE`,
    :data:`MIN_SKIN_THICKNESS`): a units mistake.

    Parameters
    ----------
    tip : Fingertip
    source : str
        Where it comes from, for the message (a file; a calibration's log).
    fix : str
        What the message says to check.

    Raises
    ------
    InputError
    """
    _, radius = tip.bounding_sphere
    size = 2.0 * float(radius)
    lo, hi = SIZE_RANGE
    if not lo <= size <= hi:
        times = f"{size / 0.03:.3g}× a fingertip's size" if size > hi else f"{0.03 / size:.3g}× smaller than a fingertip"
        raise InputError(
            f"{source}: the fingertip is {size * 1e3:.4g} mm across ({times}); expected {lo * 1e3:g} to {hi * 1e3:g} mm: "
            f"{fix}"
        )
    h = getattr(tip, "skin_thickness", None)
    if h is not None and not MIN_SKIN_THICKNESS <= h < radius:
        raise InputError(
            f"{source}: skin_thickness = {h:.4g} m ({h * 1e3:.4g} mm) on a fingertip {size * 1e3:.4g} mm across; expected "
            f"{MIN_SKIN_THICKNESS * 1e3:g} mm to less than its radius ({float(radius) * 1e3:.4g} mm): lengths in a "
            "fingertip file are in metres (5 mm is 0.005), and --skin-thickness takes a unit (5mm)"
        )


def check_skin(tip) -> None:
    """Validate the optional ``skin_thickness`` (m) of a fingertip dataclass."""
    h = tip.skin_thickness
    if h is not None:
        object.__setattr__(tip, "skin_thickness", positive(h, "skin_thickness"))


def skin_toml(tip) -> str:
    """The ``skin_thickness`` line of a fingertip's TOML, or ``""``."""
    h = getattr(tip, "skin_thickness", None)
    return "" if h is None else f"skin_thickness = {fmt(h)}\n"


def fields_from_table(table: dict, source: str, shape: str, fields: dict[str, bool], pairs: tuple[str, ...] = ()) -> dict:
    """The constructor's keyword arguments from a ``[fingertip]`` table of plain numbers.

    ``fields`` maps each key to whether it is required; a key is a number or a list of 3
    numbers, or, for the keys in ``pairs``, a list of 2.

    Raises
    ------
    InputError
        Unknown, missing or malformed keys (the message names the file and the key).
    """
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
        size = 2 if key in pairs else 3
        if isinstance(value, list):
            ok = len(value) == size and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        elif key in pairs:
            ok = False
        if not ok:
            what = "a list of 2 numbers [x, y]" if key in pairs else "a number (or a list of 3)"
            raise InputError(f"{source}: [fingertip] {key} = {value!r} is not {what} in metres")
    return kwargs


_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


def fibonacci_cap(n: int, cos_min: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``n`` equal-area unit vectors with ``z`` from 1 down to ``cos_min``, and their areas on the unit sphere.

    A Fibonacci spiral lattice: equal-area, quasi-uniform and without a pole, so the apex is
    not a singular point of the grid.
    """
    k = np.arange(n) + 0.5
    cz = 1.0 - k * (1.0 - cos_min) / n
    sz = np.sqrt(np.maximum(1.0 - cz * cz, 0.0))
    phi = _GOLDEN_ANGLE * np.arange(n)
    u = np.column_stack((sz * np.cos(phi), sz * np.sin(phi), cz))
    area = np.full(n, 2.0 * math.pi * (1.0 - cos_min) / n)
    return u, area


def uv_sphere(n_around: int, n_along: int) -> NDArray[np.float64]:
    """Unit vectors on a latitude-longitude grid from the south pole up, shape (n_along, n_around, 3)."""
    phi = np.linspace(0.0, 2.0 * np.pi, n_around, endpoint=False)
    a = np.linspace(np.pi, 0.0, n_along)
    return np.stack(
        [
            np.sin(a)[:, None] * np.cos(phi),
            np.sin(a)[:, None] * np.sin(phi),
            np.broadcast_to(np.cos(a)[:, None], (n_along, n_around)),
        ],
        axis=-1,
    )


def grid_mesh(tip: Fingertip, pts: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Triangles over a grid of skin points ``pts`` (rows along the profile, columns around,
    closed around), with ``tip``'s normals at the vertices: see :meth:`Fingertip.surface_mesh`."""
    rows, cols = pts.shape[:2]
    vertices = pts.reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(cols), indexing="ij")
    a0 = i * cols + j
    a1 = i * cols + (j + 1) % cols
    b0, b1 = a0 + cols, a1 + cols
    triangles = np.concatenate(
        [
            np.stack([a0, a1, b1], -1).reshape(-1, 3),
            np.stack([a0, b1, b0], -1).reshape(-1, 3),
        ]
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        normals = tip.normal(vertices)
    normals = np.where(np.isfinite(normals), normals, np.array([0.0, 0.0, 1.0]))
    return vertices, triangles.astype(np.int32), normals


def fingertip_table(data: dict, source: str) -> dict:
    """The ``[fingertip]`` table of a parsed fingertip file, which must hold nothing else (a
    ``[mount]`` meant as ``[fingertip.mount]`` would leave the tip unmounted without a word).

    Raises
    ------
    InputError
        No ``[fingertip]`` table, or a key or table outside it; naming ``source``.
    """
    table = data.get("fingertip")
    if not isinstance(table, dict):
        raise InputError(f"{source}: expected a [fingertip] table")
    extra = [k for k in data if k != "fingertip"]
    if extra:
        hint = "; a mount is [fingertip.mount]" if "mount" in extra else ""
        raise InputError(
            f"{source}: unknown {'table' if isinstance(data[extra[0]], dict) else 'key'} {extra[0]!r} outside "
            f"[fingertip]; expected only the [fingertip] table and its [fingertip.mount]{hint}"
        )
    return table
