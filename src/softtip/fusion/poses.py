"""Poses of the fingertips' sensor frames in a common frame (the hand, or the robot's base),
over time.

A :class:`PoseSeries` holds the pose of one sensor frame in the common frame at a sequence of
times and interpolates it at any time inside them (spherical linear interpolation of the
rotation, linear of the translation: scipy's :class:`~scipy.spatial.transform.Slerp`). A pose
maps a sensor-frame point ``p`` to ``R p + t`` in the common frame. Sources: a fixed pose
(:meth:`PoseSeries.fixed`, e.g. from a hand file, :func:`read_hand_file`), pose columns of a
log (:func:`poses_from_columns`: ``px, py, pz, qw, qx, qy, qz``) or a ROS bag's ``/tf`` and
``/tf_static`` (:mod:`softtip.fusion.tf`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation, Slerp

from softtip.core.mounting import pose_from_table
from softtip.errors import InputError
from softtip.tomlfile import read_toml

__all__ = ["POSE_COLUMNS", "PoseSeries", "poses_from_columns", "read_hand_file", "HandFile"]

#: Pose columns of a log: position (m) and unit quaternion (scalar first).
POSE_COLUMNS = ("px", "py", "pz", "qw", "qx", "qy", "qz")


@dataclass(frozen=True, eq=False)
class PoseSeries:
    """The pose of a sensor frame in the common frame at times ``t``.

    Parameters
    ----------
    t : array-like, shape (K,)
        s, increasing; K ≥ 1 (one pose: fixed for all time).
    rotation : Rotation of length K (or a single one when K = 1)
        Sensor frame to common frame.
    translation : array-like, shape (K, 3)
        m; the sensor frame's origin in the common frame.
    max_gap : float
        s; :meth:`at` refuses times farther than this from the series' ends (a stale pose).
    name : str
        What the poses are of, for messages.
    """

    t: NDArray[np.float64]
    rotation: Rotation
    translation: NDArray[np.float64]
    max_gap: float = 0.1
    name: str = "sensor"

    def __post_init__(self) -> None:
        t = np.atleast_1d(np.asarray(self.t, dtype=float))
        tr = np.asarray(self.translation, dtype=float).reshape(-1, 3)
        rot = self.rotation if not self.rotation.single else Rotation.concatenate([self.rotation])
        if t.ndim != 1 or len(t) < 1 or len(rot) != len(t) or len(tr) != len(t):
            raise ValueError(f"{self.name}: need as many times, rotations and translations, got {len(t)}, {len(rot)}, {len(tr)}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(tr))):
            raise ValueError(f"{self.name}: pose times and translations must be finite")
        if np.any(np.diff(t) <= 0):
            raise ValueError(f"{self.name}: pose times must increase")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "rotation", rot)
        object.__setattr__(self, "translation", tr)

    @classmethod
    def fixed(cls, rotation: Rotation | ArrayLike, translation: ArrayLike = (0.0, 0.0, 0.0), name: str = "sensor") -> PoseSeries:
        """A pose that does not change (``rotation``: a Rotation or a 3×3 matrix)."""
        rot = rotation if isinstance(rotation, Rotation) else Rotation.from_matrix(np.asarray(rotation, dtype=float))
        return cls(np.zeros(1), rot, np.asarray(translation, dtype=float).reshape(1, 3), math.inf, name)

    @property
    def is_fixed(self) -> bool:
        return len(self.t) == 1

    def at(self, t: ArrayLike) -> tuple[Rotation, NDArray[np.float64]]:
        """Rotation and translation at times ``t`` (shape (N,)), interpolated.

        Raises
        ------
        InputError
            A time outside the series by more than ``max_gap`` (the pose is stale or missing).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.is_fixed:
            return Rotation.concatenate([self.rotation] * len(t)) if len(t) else self.rotation[:0], np.repeat(self.translation, len(t), axis=0)
        lo, hi = self.t[0], self.t[-1]
        bad = (t < lo - self.max_gap) | (t > hi + self.max_gap)
        if bad.any():
            k = int(np.argmax(bad))
            raise InputError(
                f"no pose of {self.name} at t = {t[k]:.6f} s: poses cover {lo:.6f}–{hi:.6f} s "
                f"(more than {self.max_gap:g} s away: missing or stale)"
            )
        tc = np.clip(t, lo, hi)
        rot = Slerp(self.t, self.rotation)(tc)
        tr = np.stack([np.interp(tc, self.t, self.translation[:, i]) for i in range(3)], axis=-1)
        return rot, tr

    def apply(self, t: ArrayLike, points: ArrayLike) -> NDArray[np.float64]:
        """Sensor-frame points ``(N, 3)`` at times ``t`` ``(N,)`` in the common frame."""
        rot, tr = self.at(t)
        return rot.apply(np.asarray(points, dtype=float)) + tr

    def rotate(self, t: ArrayLike, vectors: ArrayLike) -> NDArray[np.float64]:
        """Sensor-frame vectors ``(N, 3)`` at times ``t`` in the common frame."""
        rot, _ = self.at(t)
        return rot.apply(np.asarray(vectors, dtype=float))


def poses_from_columns(t: ArrayLike, columns: Mapping[str, ArrayLike], name: str = "sensor", source: str = "log") -> PoseSeries:
    """The pose columns ``px, py, pz, qw, qx, qy, qz`` of a log (m; unit quaternion)."""
    missing = [c for c in POSE_COLUMNS if c not in columns]
    if missing:
        raise InputError(f"{source}: missing pose column(s) {', '.join(missing)}; expected {', '.join(POSE_COLUMNS)} "
                         "(the sensor's pose over time), or fixed poses in a hand file (softtip fuse --hand HAND.toml)")  # fmt: skip
    try:
        a = {c: np.asarray(columns[c], dtype=float) for c in POSE_COLUMNS}
    except ValueError:
        raise InputError(f"{source}: pose columns must be numbers") from None
    q = np.stack([a["qx"], a["qy"], a["qz"], a["qw"]], axis=-1)
    norm = np.linalg.norm(q, axis=-1)
    bad = ~np.isfinite(norm) | (np.abs(norm - 1.0) > 0.01)
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(f"{source}: row {k + 1}: pose quaternion (qw, qx, qy, qz) has norm {norm[k]:g}; expected a unit quaternion")
    tr = np.stack([a["px"], a["py"], a["pz"]], axis=-1)
    t = np.asarray(t, dtype=float)
    keep = np.concatenate(([True], np.diff(t) > 0))  # repeated stamps: the first pose
    return PoseSeries(t[keep], Rotation.from_quat(q[keep]), tr[keep], max_gap=0.0, name=name)


@dataclass(frozen=True)
class HandFile:
    """A hand file: the common frame's name and each finger's fixed sensor pose in it."""

    frame: str
    fingers: dict[str, PoseSeries]


def read_hand_file(path: str | Path) -> HandFile:
    """Read a TOML hand file.

    ::

        [hand]
        frame = "hand"                      # the common frame's name

        [finger.right]                      # one table per finger
        translation = [0.038, 0.0, 0.0]     # m: its sensor frame's origin in the hand frame
        rpy_deg = [0.0, -90.0, 0.0]         # roll, pitch, yaw about the hand's fixed x, y, z
        # or quaternion = [w, x, y, z]
    """
    path = Path(path)
    data = read_toml(path, "hand")
    hand = data.get("hand", {})
    frame = hand.get("frame", "hand") if isinstance(hand, dict) else None
    if not isinstance(frame, str) or not frame:
        raise InputError(f"{path}: [hand] frame must be a frame name")
    fingers = data.get("finger")
    if not isinstance(fingers, dict) or not fingers:
        raise InputError(f"{path}: expected one [finger.NAME] table per fingertip")
    out = {}
    for name, table in fingers.items():
        rotation, translation = pose_from_table(table, f"{path}: [finger.{name}]")
        out[name] = PoseSeries.fixed(rotation, translation, name=name)
    return HandFile(frame, out)
