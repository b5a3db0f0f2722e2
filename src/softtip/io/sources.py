"""Sources of force/torque samples: what a log replay or a live sensor yields, one sample at a time.

A **source** is anything iterable that yields samples ``(t, wrench)``: ``t`` in s (strictly
increasing), ``wrench`` six numbers ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m), raw (softtip
tares it), sensor frame. softtip's own sources yield :class:`Reading`, a named tuple whose
first two fields are exactly that, plus the bookkeeping a live sensor needs (sequence
number, packets lost before this one, arrival time). A plain generator works as well::

    import softtip

    def my_sensor():
        while True:
            t, w = read_my_driver()      # s, (fx, fy, fz, mx, my, mz) in N, N·m
            yield t, w

    for est in softtip.run(my_sensor(), "murakami2006"):   # softtip.apps.live.run
        if est.state == "line":
            print(est.angle)              # rad

Sources here: :class:`LogSource` (a recorded log, replayed at its recorded rate, faster,
or as fast as possible) and :class:`softtip.io.netft.NetFTSource`
(an ATI Net F/T or Axia over RDT/UDP).
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from softtip.io.tables import Log

__all__ = ["Interrupted", "LogSource", "Reading", "SourceError", "readings"]


class SourceError(RuntimeError):
    """A live source failed at run time: no data (time-out), device unreachable, ...

    Not bad input (that is :class:`~softtip.errors.InputError`): the command line exits
    with code 1 and the message.
    """


class Interrupted(Exception):
    """A source was asked to stop (Ctrl-C, SIGTERM) before its first sample."""


class Reading(NamedTuple):
    """One raw sample from a source.

    Attributes
    ----------
    t : float
        s, strictly increasing within a source.
    wrench : tuple of 6 float
        Raw ``fx, fy, fz`` (N) and ``mx, my, mz`` (N·m), sensor frame, not tared.
    seq : int
        The source's sequence number (RDT sequence for a Net F/T, row index for a log).
    lost : int
        Records missing just before this one (a gap in ``seq``) that softtip did not drop
        itself: lost on the network, or to arrive late (then counted in ``late`` of a later
        reading); 0 for a log.
    arrival_ns : int
        When the sample reached this host, ``time.monotonic_ns()`` clock; 0 if unknown.
    status : int
        The device's status word (0 healthy; a Net F/T's RDT status); 0 for a log.
    host_time : float
        When the sample reached this host, s since the Unix epoch (for syncing with other
        logs); NaN if unknown.
    dropped : int
        Records just before this one that softtip's own receive queue dropped (the consumer
        did not keep up).
    late, duplicates, malformed : int
        Late packets, duplicates and malformed datagrams discarded since the previous reading.
    stamp_ns : int
        The sample's own stamp, ns since the Unix epoch, where the source has one (a replayed
        log with absolute stamps: a ROS export's ``header.stamp``); 0 otherwise.
    """

    t: float
    wrench: tuple[float, ...]
    seq: int = 0
    lost: int = 0
    arrival_ns: int = 0
    status: int = 0
    host_time: float = math.nan
    dropped: int = 0
    late: int = 0
    duplicates: int = 0
    malformed: int = 0
    stamp_ns: int = 0


def readings(source: Iterable) -> Iterator[Reading]:
    """Normalise a source's items to :class:`Reading` (plain ``(t, wrench)`` pairs included)."""
    for seq, item in enumerate(source):
        if isinstance(item, Reading):
            yield item
        else:
            t, w = item[0], item[1]
            w = w.tolist() if isinstance(w, np.ndarray) else w
            yield Reading(float(t), tuple(float(v) for v in w), seq, 0, 0, 0, math.nan, 0, 0, 0, 0)


class LogSource:
    """A recorded log as a live source, replayed in (scaled) real time.

    Parameters
    ----------
    t : array-like, shape (N,)
        s, strictly increasing.
    wrench : array-like, shape (N, 6)
        Raw wrench, N and N·m.
    speed : float
        Replay speed: 1 is the recorded rate, 2 twice as fast, 0 as fast as possible.
    name : str
        Shown in the live view.
    stop : threading.Event, optional
        Set it to end the replay at once, also while it waits for the next sample.
    stamps_ns : array-like of int, shape (N,), optional
        The log's absolute stamps, ns since the Unix epoch (:attr:`~softtip.io.tables.Log.stamps_ns`),
        passed on as each reading's ``stamp_ns``.

    Notes
    -----
    Sample ``k`` is released at ``start + (t[k] - t[0]) / speed`` (wall clock): a slow
    consumer catches up without drift instead of stretching the log.
    """

    def __init__(
        self,
        t: ArrayLike,
        wrench: ArrayLike,
        speed: float = 1.0,
        name: str = "log",
        stop: threading.Event | None = None,
        stamps_ns: ArrayLike | None = None,
    ) -> None:
        self.t = np.asarray(t, dtype=float)
        self.wrench = np.asarray(wrench, dtype=float)
        if self.t.ndim != 1 or self.wrench.shape != (len(self.t), 6):
            raise ValueError(
                f"expected t (N,) and wrench (N, 6), got {self.t.shape} and {self.wrench.shape}"
            )
        if not (np.isfinite(speed) and speed >= 0):
            raise ValueError(
                f"speed must be a non-negative number (0: as fast as possible), got {speed!r}"
            )
        self.speed = float(speed)
        self.name = name
        self.stamps_ns = None if stamps_ns is None else np.asarray(stamps_ns, dtype=np.int64)
        if self.stamps_ns is not None and self.stamps_ns.shape != self.t.shape:
            raise ValueError(f"expected stamps_ns {self.t.shape}, got {self.stamps_ns.shape}")
        self.stop_event = stop
        dt = np.diff(self.t)
        #: Recorded sample rate, Hz (median step); None for fewer than two samples.
        self.rate_hz: float | None = float(1.0 / np.median(dt)) if len(dt) else None

    @classmethod
    def from_csv(
        cls,
        path: str | os.PathLike[str],
        units: str = "si",
        speed: float = 1.0,
        stop: threading.Event | None = None,
    ) -> LogSource:
        """Read a CSV log (manual §4) (columns ``t, fx, fy, fz, mx, my, mz``); see :func:`softtip.io.tables.read_log`."""
        from softtip.io.tables import read_log

        return cls.from_log(read_log(path, units=units), speed=speed, stop=stop)

    @classmethod
    def from_log(cls, log: Log, speed: float = 1.0, stop: threading.Event | None = None) -> LogSource:
        """A :class:`~softtip.io.tables.Log` replayed: its samples, named by its file, its absolute stamps
        (:attr:`~softtip.io.tables.Log.stamps_ns`) passed on as each reading's ``stamp_ns``."""
        return cls(log.t, log.wrench, speed=speed, name=os.path.basename(log.source), stop=stop, stamps_ns=log.stamps_ns)

    def __len__(self) -> int:
        return len(self.t)

    def __iter__(self) -> Iterator[Reading]:
        ts = self.t.tolist()
        ws = [tuple(row) for row in self.wrench.tolist()]
        stamps = [0] * len(ts) if self.stamps_ns is None else self.stamps_ns.tolist()
        clock, wall = time.monotonic_ns, time.time_ns
        stop = self.stop_event
        if self.speed == 0 or not ts:
            for k, (t, w, st) in enumerate(zip(ts, ws, stamps)):
                yield Reading(t, w, k, 0, clock(), 0, wall() * 1e-9, 0, 0, 0, 0, st)
            return
        start = time.monotonic()
        t0, speed = ts[0], self.speed
        for k, (t, w, st) in enumerate(zip(ts, ws, stamps)):
            wait = start + (t - t0) / speed - time.monotonic()
            if wait > 0:
                if stop is None:
                    time.sleep(wait)
                elif stop.wait(wait):
                    return
            yield Reading(t, w, k, 0, clock(), 0, wall() * 1e-9, 0, 0, 0, 0, st)
