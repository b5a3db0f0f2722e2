"""Gravity compensation of logs and live sources: orientation columns, compensated sources.

A log's orientation is in columns ``qw, qx, qy, qz`` (unit quaternion of the sensor frame in
a z-up world frame, scalar first); the maths is :mod:`softtip.core.gravity`.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from softtip.core.gravity import Payload, PayloadCompensator, compensate_payload, load_payload
from softtip.errors import InputError

if TYPE_CHECKING:
    from softtip.io.tables import Log

__all__ = ["QUATERNION_COLUMNS", "UNIT_TOLERANCE", "read_orientation", "compensate_log", "CompensatedSource", "replay_source"]

#: Orientation columns of a log: the sensor frame in the world frame, scalar first.
QUATERNION_COLUMNS = ("qw", "qx", "qy", "qz")
#: Largest accepted deviation of a quaternion's norm from 1.
UNIT_TOLERANCE = 1e-3



def _to_float(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return math.nan


def read_orientation(log, tolerance: float = UNIT_TOLERANCE) -> NDArray[np.float64]:
    """The ``qw, qx, qy, qz`` columns of a log as unit quaternions, shape (N, 4).

    Parameters
    ----------
    log : softtip.io.tables.Log
        Read by :func:`softtip.io.tables.read_log`; the quaternion columns are among its extra
        columns.
    tolerance : float
        Largest accepted ``| |q| − 1 |``; accepted quaternions are normalised.

    Raises
    ------
    InputError
        A column missing, a cell empty, non-numeric or not finite, or a quaternion that is
        not a unit quaternion; names the file, the line and the column.
    """
    missing = [c for c in QUATERNION_COLUMNS if c not in log.extra]
    if missing:
        have = ", ".join(log.extra) or "none"
        raise InputError(
            f"{log.source}: missing orientation column(s) {', '.join(missing)}; gravity compensation needs "
            f"qw, qx, qy, qz (unit quaternion of the sensor frame in a z-up world frame); extra columns present: {have}"
        )
    def where(i: int, col: str) -> str:
        first = getattr(log, "first_line", None)  # the reader's: no second look at the file
        line = f"{log.source}:{first + i}" if first is not None else f"{log.source}: data row {i + 1}"
        return f"{line}: column {col!r}"

    n = len(log.t)
    q = np.empty((n, 4))
    for j, col in enumerate(QUATERNION_COLUMNS):
        cells = log.extra[col]
        try:
            q[:, j] = np.array(cells, dtype=float)
        except ValueError:  # cell by cell, to find the first bad one
            q[:, j] = [_to_float(c) for c in cells]
        bad = ~np.isfinite(q[:, j])
        if bad.any():
            i = int(np.argmax(bad))
            cell = cells[i]
            try:
                float(cell)
                what = f"expected a finite number, got {cell!r}"
            except ValueError:
                what = "empty cell; expected a number" if not cell.strip() else f"expected a number, got {cell!r}"
            raise InputError(f"{where(i, col)}: {what}")
    norm = np.linalg.norm(q, axis=1)
    bad = np.abs(norm - 1.0) > tolerance
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(
            f"{where(i, 'qw')}: qw, qx, qy, qz = {', '.join(str(log.extra[c][i]).strip() for c in QUATERNION_COLUMNS)} "
            f"has norm {norm[i]:.6g}; expected a unit quaternion (norm within {tolerance:g} of 1)"
        )
    return q / norm[:, None]


def compensate_log(log, payload: Payload | str | os.PathLike[str]):
    """A copy of ``log`` with the payload's gravity wrench removed (orientation from its columns).

    Parameters
    ----------
    log : softtip.io.tables.Log
    payload : Payload or path of a payload TOML file

    Returns
    -------
    softtip.io.tables.Log
    """
    payload = load_payload(payload)
    q = read_orientation(log)
    return replace(log, wrench=compensate_payload(log.wrench, q, payload))


class CompensatedSource:
    """A live source with the payload's gravity removed from every sample (plain floats).

    Parameters
    ----------
    source : iterable of Reading or (t, wrench)
        The raw source (its ``rate_hz``, ``name`` and ``close`` are passed through).
    orientations : iterable of 4 floats, or a callable
        ``qw, qx, qy, qz`` of each sample, in step with ``source``; or a function of the
        sample's time ``t`` (s) returning them — the robot's current sensor orientation from
        its joint states, an IMU, or a transform listener.
    payload : Payload
    """

    def __init__(self, source, orientations: Iterable | Callable[[float], Sequence[float]], payload: Payload) -> None:
        self.source = source
        self.orientations = orientations
        self.compensate = PayloadCompensator(payload)
        self.rate_hz = getattr(source, "rate_hz", None)
        self.name = getattr(source, "name", "source")

    def __iter__(self) -> Iterator:
        from softtip.io.sources import readings

        comp = self.compensate
        if callable(self.orientations):
            orientation = self.orientations
            for reading in readings(self.source):
                yield reading._replace(wrench=comp(reading.wrench, orientation(reading.t)))
            return
        for reading, q in zip(readings(self.source), self.orientations):
            yield reading._replace(wrench=comp(reading.wrench, q))

    def close(self) -> None:
        """Close the wrapped source, if it can be."""
        if hasattr(self.source, "close"):
            self.source.close()


def replay_source(
    log: Log, speed: float, payload: Payload | str | os.PathLike[str], stop: threading.Event | None = None
) -> CompensatedSource:
    """``softtip stream --replay LOG --payload FILE``: the log (:func:`~softtip.io.tables.read_log`'s)
    replayed with per-sample compensation, its orientation from its ``qw, qx, qy, qz`` columns;
    ``speed`` and ``stop`` as :class:`~softtip.io.sources.LogSource`'s."""
    from softtip.io.sources import LogSource

    payload = load_payload(payload)
    q = read_orientation(log)
    src = LogSource.from_log(log, speed=speed, stop=stop)
    return CompensatedSource(src, [tuple(row) for row in q.tolist()], payload)
