"""A fingertip mounted on the sensor at an angle or an offset.

Real hands rarely put the fingertip's axis on the sensor's ``z`` axis. :class:`Mounted`
wraps any fingertip shape, given in its own frame, with its pose in the sensor frame: a point
``p_tip`` of the fingertip's frame is ``R p_tip + t`` in the sensor frame. Every estimator
output stays in the sensor frame.

The contact solution of a mounted tip is the shape's own solution for the wrench expressed
in the fingertip's frame — ``f' = Rᵀ f``, ``m' = Rᵀ (m − t × f)`` — mapped back, so closed
forms stay closed forms.

In a fingertip file::

    [fingertip]
    shape = "capsule"
    radius = 0.016
    length = 0.020

    [fingertip.mount]
    translation = [0.0, 0.003, 0.0]   # m: the fingertip frame's origin in the sensor frame
    rpy_deg = [0.0, 10.0, 0.0]        # roll, pitch, yaw about the sensor's fixed x, y, z axes
    # or: quaternion = [w, x, y, z]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:  # scipy.spatial costs ~0.3 s to import: only where a rotation is made
    from scipy.spatial.transform import Rotation

from softtip.core._xp import NP
from softtip.core.shape import Fingertip
from softtip.errors import InputError

__all__ = ["Mounted", "mount_from_mapping", "pose_from_table", "rpy_of"]


@dataclass(frozen=True)
class Mounted(Fingertip):
    """``tip`` (in its own frame) mounted at ``rotation`` and ``translation`` on the sensor.

    Parameters
    ----------
    tip : Fingertip
        The shape in its own frame.
    rotation : array-like, shape (3, 3)
        Rotation matrix from the fingertip's frame to the sensor frame (or a
        :class:`scipy.spatial.transform.Rotation`).
    translation : array-like, shape (3,)
        m; the fingertip frame's origin in the sensor frame.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from softtip import Sphere, contact_from_wrench
    >>> from softtip.core.mounting import Mounted
    >>> tip = Mounted(Sphere(0.01, (0, 0, 0.02)), Rotation.from_euler("y", 90, degrees=True), (0, 0, 0.005))
    >>> (np.round(tip.normal([0.03, 0.0, 0.005]), 12) + 0.0).tolist()   # the sphere's top now faces +x
    [1.0, 0.0, 0.0]
    """

    tip: Fingertip
    rotation: tuple[tuple[float, float, float], ...]
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    kind: ClassVar[str] = "mounted"

    def __post_init__(self) -> None:
        if not isinstance(self.tip, Fingertip) or isinstance(self.tip, Mounted):
            raise ValueError(f"tip must be an unmounted Fingertip, got {self.tip!r}")
        rot = self.rotation
        m = rot.as_matrix() if hasattr(rot, "as_matrix") else np.asarray(rot, dtype=float)  # a scipy Rotation
        if m.shape != (3, 3) or not np.all(np.isfinite(m)):
            raise ValueError(f"rotation must be a 3×3 rotation matrix, got {self.rotation!r}")
        if not (np.allclose(m @ m.T, np.eye(3), atol=1e-9) and np.linalg.det(m) > 0):
            raise ValueError("rotation must be a proper rotation matrix (orthonormal, determinant +1)")
        t = np.asarray(self.translation, dtype=float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise ValueError(f"translation must be 3 finite numbers (m), got {self.translation!r}")
        object.__setattr__(self, "rotation", tuple(tuple(float(v) for v in row) for row in m))
        object.__setattr__(self, "translation", tuple(float(v) for v in t))

    @property
    def skin_thickness(self) -> float | None:
        """The mounted shape's skin thickness (m; ``None`` when it gives none)."""
        return getattr(self.tip, "skin_thickness", None)

    # sensor → fingertip frame and back, component-wise (floats or arrays)
    def _to_tip(self, x, y, z):
        (a, b, c), (d, e, f), (g, h, i) = self.rotation
        tx, ty, tz = self.translation
        x, y, z = x - tx, y - ty, z - tz
        return a * x + d * y + g * z, b * x + e * y + h * z, c * x + f * y + i * z

    def _rotate(self, x, y, z):
        (a, b, c), (d, e, f), (g, h, i) = self.rotation
        return a * x + b * y + c * z, d * x + e * y + f * z, g * x + h * y + i * z

    def _from_tip(self, x, y, z):
        tx, ty, tz = self.translation
        x, y, z = self._rotate(x, y, z)
        return x + tx, y + ty, z + tz

    def wrench_in_tip_frame(self, fx, fy, fz, mx, my, mz):
        """The wrench about the fingertip frame's origin, in that frame (component-wise)."""
        tx, ty, tz = self.translation
        mx, my, mz = mx - (ty * fz - tz * fy), my - (tz * fx - tx * fz), mz - (tx * fy - ty * fx)
        (a, b, c), (d, e, f), (g, h, i) = self.rotation
        return (
            a * fx + d * fy + g * fz, b * fx + e * fy + h * fz, c * fx + f * fy + i * fz,
            a * mx + d * my + g * mz, b * mx + e * my + h * mz, c * mx + f * my + i * mz,
        )  # fmt: skip

    def _surface_kernel(self, x, y, z, xp):
        return self.tip._surface_kernel(*self._to_tip(x, y, z), xp)

    def _normal_kernel(self, x, y, z, xp):
        return self._rotate(*self.tip._normal_kernel(*self._to_tip(x, y, z), xp))

    def _project_kernel(self, x, y, z, xp):
        return self._from_tip(*self.tip._project_kernel(*self._to_tip(x, y, z), xp))

    @property
    def bounding_sphere(self) -> tuple[NDArray[np.float64], float]:
        c, r = self.tip.bounding_sphere
        return np.array(self._from_tip(*np.asarray(c, dtype=float))), r

    def _contact_kernel(self, fx, fy, fz, mx, my, mz, xp=NP):
        # the shape's own solution for the wrench in its frame, mapped back to the sensor frame
        rx, ry, rz, nx, ny, nz, sigma, valid = self.tip._contact_kernel(*self.wrench_in_tip_frame(fx, fy, fz, mx, my, mz), xp)
        return (*self._from_tip(rx, ry, rz), *self._rotate(nx, ny, nz), sigma, valid)

    def skin_elements(self, n_elements: int, z_min: float | None = None) -> tuple[NDArray, NDArray, NDArray]:
        """The shape's own skin (``z_min`` in its own frame: its flange), placed by the mount.
        See :meth:`Fingertip.skin_elements`."""
        centres, normals, areas = self.tip.skin_elements(n_elements, z_min)
        rot, shift = np.array(self.rotation), np.array(self.translation)
        return centres @ rot.T + shift, normals @ rot.T, areas

    def support_point(self, normal: ArrayLike) -> NDArray[np.float64]:
        rot = np.array(self.rotation)
        return self.tip.support_point(np.asarray(normal, dtype=float) @ rot) @ rot.T + np.array(self.translation)

    def apex_hint(self) -> NDArray[np.float64]:
        """The shape's own apex hint (on its own +z axis), placed by the mount."""
        return np.array(self.rotation) @ self.tip.apex_hint() + np.array(self.translation)

    def surface_mesh(self, n_around: int = 48, n_along: int = 32) -> tuple[NDArray, NDArray, NDArray]:
        """The shape's own mesh placed by the mount. See :meth:`Fingertip.surface_mesh`."""
        v, tri, n = self.tip.surface_mesh(n_around, n_along)
        rot = np.array(self.rotation)
        return v @ rot.T + np.array(self.translation), tri, n @ rot.T

    def to_toml(self) -> str:
        from scipy.spatial.transform import Rotation

        q = Rotation.from_matrix(np.array(self.rotation)).as_quat()  # x, y, z, w
        t = ", ".join(repr(v) for v in self.translation)
        quat = ", ".join(repr(float(v)) for v in (q[3], q[0], q[1], q[2]))
        return f"{self.tip.to_toml()}\n[fingertip.mount]\ntranslation = [{t}]\nquaternion = [{quat}]\n"


def _numbers(value, n: int, key: str, where: str) -> list[float]:
    ok = isinstance(value, list) and len(value) == n
    ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    if not ok:
        raise InputError(f"{where} {key} = {value!r}; expected a list of {n} finite numbers")
    return [float(v) for v in value]


def rpy_of(rotation: Rotation) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad, URDF's fixed-axis ``xyz``) of ``rotation``. At a pitch of ±90°
    (a CAD part whose axis is along x, mounted upright) only roll ± yaw is defined: scipy then
    sets yaw to 0 and warns on every load; the angles returned compose to the same rotation."""
    import warnings

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock detected", category=UserWarning)
        return tuple(float(a) for a in rotation.as_euler("xyz"))


def pose_from_table(table: dict, where: str) -> tuple[Rotation, tuple[float, float, float]]:
    """A rigid pose from a TOML table with ``translation`` (m) and ``rpy_deg`` (roll, pitch,
    yaw about the fixed x, y, z axes) or ``quaternion`` (``[w, x, y, z]``); both optional.

    ``where`` names the table in messages (file and section).
    """
    if not isinstance(table, dict):
        raise InputError(f"{where} must be a table")
    unknown = sorted(set(table) - {"translation", "rpy_deg", "quaternion"})
    if unknown:
        raise InputError(f"{where} unknown key(s) {', '.join(unknown)}; expected translation and rpy_deg or quaternion")
    if "rpy_deg" in table and "quaternion" in table:
        raise InputError(f"{where} give rpy_deg or quaternion, not both")
    from scipy.spatial.transform import Rotation

    translation = _numbers(table.get("translation", [0.0, 0.0, 0.0]), 3, "translation", where)
    if max(abs(v) for v in translation) > 1.0:
        raise InputError(f"{where} translation = {translation!r} m is over 1 m; expected metres")
    if "quaternion" in table:
        w, x, y, z = _numbers(table["quaternion"], 4, "quaternion", where)
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if not 0.99 < norm < 1.01:
            raise InputError(f"{where} quaternion has norm {norm:g}; expected a unit [w, x, y, z]")
        rotation = Rotation.from_quat([x, y, z, w])
    else:
        rpy = _numbers(table.get("rpy_deg", [0.0, 0.0, 0.0]), 3, "rpy_deg", where)
        rotation = Rotation.from_euler("xyz", rpy, degrees=True)
    return rotation, (translation[0], translation[1], translation[2])


def mount_from_mapping(tip: Fingertip, table: dict, source: str) -> Mounted:
    """A :class:`Mounted` fingertip from a ``[fingertip.mount]`` table of file ``source``
    (see :func:`pose_from_table`)."""
    rotation, translation = pose_from_table(table, f"{source}: [fingertip.mount]")
    return Mounted(tip, rotation, translation)
