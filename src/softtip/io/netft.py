"""Live samples from an ATI Net F/T or Axia: RDT over UDP, received by softtip itself.

Uses the standard library only (sockets, ``urllib``); no extra package is needed.

What happens on :meth:`NetFTSource.open`:

1. softtip reads ``/netftapi2.xml`` from the device over HTTP: counts per force and per
   torque unit (``cfgcpf``, ``cfgcpt``), the unit names (``scfgfu``, ``scfgtu``), the RDT
   output rate (``comrdtrate``) and the product name.
2. It asks for an endless RDT stream (request ``0x1234, 0x0002, 0``) and receives the
   36-byte big-endian records (``>III6i``: RDT sequence, F/T sequence, status word,
   ``Fx, Fy, Fz, Tx, Ty, Tz`` in counts) in its own thread, into a queue that holds
   ``buffer_s`` seconds at ``max_rate_hz``, each datagram stamped with the host's clock
   (the kernel's receive time where the OS gives it).
3. The consumer (:meth:`NetFTSource.__iter__`) hands every datagram to an
   :class:`RDTTracker`, the packet handling: it times samples on the device's clock,
   ``t = (seq - seq0) / comrdtrate`` (free of network jitter; a lost packet leaves a gap),
   converts counts to SI, and keeps going through whatever the network and the sensor do:

   * a **duplicate** (a sequence number already taken) and a **late** packet (one that
     arrives after a later one: its place is already a gap) are dropped and counted;
   * a datagram that is not one 36-byte record is **malformed**: counted, skipped;
   * packets missing from the sequence are **lost** (network), unless this host dropped
     them (**dropped**, counted apart): softtip's queue was full because the consumer did
     not keep up, or (Linux, ``SO_RXQ_OVFL``) the socket's buffer overflowed;
   * the 32-bit sequence wraps at 2^32 and is unwrapped relative to the newest packet, so a
     packet from before the wrap arriving after it is simply late;
   * the **status word** of every record is kept (``Reading.status``); a nonzero word is
     warned about once per distinct value and counted;
   * an F/T sequence that stops advancing while records keep coming is a **stall** (the
     device is repeating stale data): counted and warned;
   * a **restart** of the device or of its RDT stream (the F/T sequence going back, or the
     RDT sequence starting again, after a silence or with the F/T sequence still advancing,
     or jumping further than the host clock allows) re-synchronises once the next record
     confirms it: time goes on from the last sample plus the host-clock gap. The first
     record, too, waits for the next to confirm it. A record that no other follows (a stray
     datagram of the right size) is counted as malformed;
   * a silent device is asked again to stream (every ``resend_s``), so a device that
     rebooted streams again;
   * the rate in the XML is checked against the host clock (from 2 s on, by the lower
     envelope of arrival times, so late packets do not count): a difference of more than
     2 % is warned about, since ``t`` would be rescaled by it.

   Only the faults named in ``strict`` end the stream (:class:`StreamFault`).

The wrench is **not** biased on the device unless ``device_bias`` is set: softtip's
estimator tares from the first samples, which needs the fingertip untouched at start.
"""

from __future__ import annotations

import collections
import math
import re
import socket
import struct
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import NoReturn

from softtip.io.sources import Interrupted, Reading, SourceError

__all__ = [
    "FAULTS",
    "FORCE_UNITS_SI",
    "RDT_RECORD",
    "RDT_REQUEST",
    "TORQUE_UNITS_SI",
    "DeviceInfo",
    "NetFTSource",
    "RDTTracker",
    "StreamFault",
    "parse_device_xml",
]

#: SI value (N) of one force unit, by the name the device (or pynetft) gives it.
FORCE_UNITS_SI = {
    "N": 1.0,
    "lbf": 4.4482216152605,
    "klbf": 4448.2216152605,
    "kN": 1e3,
    "kgf": 9.80665,
}
#: SI value (N·m) of one torque unit, by the name the device (or pynetft) gives it.
TORQUE_UNITS_SI = {
    "N-m": 1.0,
    "Nm": 1.0,
    "N-mm": 1e-3,
    "Nmm": 1e-3,
    "lbf-in": 0.1129848290276167,
    "lbf-ft": 1.3558179483314004,
    "kgf-cm": 0.0980665,
    "kN-m": 1e3,
    "kNm": 1e3,
}
#: RDT request: header 0x1234, command, sample count (big-endian).
RDT_REQUEST = struct.Struct(">HHI")
#: RDT record: rdt_sequence, ft_sequence, status, Fx, Fy, Fz, Tx, Ty, Tz (counts).
RDT_RECORD = struct.Struct(">III6i")
_HEADER, _CMD_STOP, _CMD_START, _CMD_BIAS = 0x1234, 0x0000, 0x0002, 0x0042
_MASK, _HALF = 2**32 - 1, 2**31
#: Faults ``strict`` can make fatal.
FAULTS = ("status", "restart", "stall", "lost", "duplicate", "late", "malformed", "dropped")
_MAX_WARNINGS = 20
_CONFIRM = 64  # a restart is confirmed by a record at most this far after its first
_SO_TIMESTAMPNS = 35  # Linux: kernel receive time stamps (SOL_SOCKET level, CLOCK_REALTIME)
_SO_RXQ_OVFL = 40  # Linux: datagrams the socket's buffer dropped so far, with each datagram


class StreamFault(SourceError):
    """A fault the user asked to be fatal (``strict``) happened in the stream."""


@dataclass(frozen=True)
class DeviceInfo:
    """What the device said about itself.

    Attributes
    ----------
    product : str
    force_unit, torque_unit : str
        Units of the calibrated data, as the device names them (``N``, ``Nmm``, ...).
    counts_per_force, counts_per_torque : float
        Counts per force / torque unit.
    rate_hz : float or None
        RDT output rate (``comrdtrate``), None when the device did not say.
    """

    product: str
    force_unit: str
    torque_unit: str
    counts_per_force: float
    counts_per_torque: float
    rate_hz: float | None


#: What a real Net F/T or Axia reports: counts per force or torque unit (ATI's calibrations use
#: 1e3–1e7 counts per unit) and RDT output rates (at most 7 kHz on a Net F/T, 7.8 kHz on an Axia);
#: values outside these ranges (a corrupted or hostile configuration page) are refused.
COUNTS_PER_UNIT_RANGE = (1.0, 1e9)
RDT_RATE_RANGE = (1.0, 1e5)


def _field(text: str, name: str) -> str | None:
    m = re.search(rf"<{name}>\s*([^<]*?)\s*</{name}>", text)
    return m.group(1) if m else None


def _number(text: str, name: str) -> float | None:
    value = _field(text, name)
    if value is None:
        return None
    m = re.match(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", value)  # first of a list, if a list
    try:
        x = float(m.group(0)) if m else math.nan
    except ValueError:  # pragma: no cover - the pattern only matches numbers
        return None
    return x if math.isfinite(x) and x > 0 else None


def parse_device_xml(text: str, where: str = "device") -> DeviceInfo:
    """The calibration and rate in a ``netftapi2.xml`` document.

    Raises
    ------
    SourceError
        A counts-per-unit field missing or not positive, or a unit softtip does not know.
    """
    cpf, cpt = _number(text, "cfgcpf"), _number(text, "cfgcpt")
    fu, tu = _field(text, "scfgfu"), _field(text, "scfgtu")
    if cpf is None or cpt is None or fu is None or tu is None:
        raise SourceError(
            f"{where}: /netftapi2.xml lacks the calibration (cfgcpf, cfgcpt, scfgfu, scfgtu as positive "
            "numbers and unit names); expected a Net F/T or Axia"
        )
    if fu not in FORCE_UNITS_SI or tu not in TORQUE_UNITS_SI:
        raise SourceError(
            f"{where}: calibration in units {fu!r} / {tu!r}; expected force in "
            f"{', '.join(FORCE_UNITS_SI)} and torque in {', '.join(TORQUE_UNITS_SI)}"
        )
    rate = _number(text, "comrdtrate")
    checks = [("cfgcpf (counts per force unit)", cpf, COUNTS_PER_UNIT_RANGE), ("cfgcpt (counts per torque unit)", cpt, COUNTS_PER_UNIT_RANGE)]
    if rate is not None:
        checks.append(("comrdtrate (RDT output rate, Hz)", rate, RDT_RATE_RANGE))
    for setting, value, (low, high) in checks:
        if not low <= value <= high:
            raise SourceError(
                f"{where}: /netftapi2.xml reports {setting} = {value:g}, outside any Net F/T's or Axia's "
                f"range [{low:g}, {high:g}]; refusing to believe it (check the sensor's configuration page)"
            )
    return DeviceInfo(
        product=_field(text, "prodname") or "Net F/T",
        force_unit=fu,
        torque_unit=tu,
        counts_per_force=cpf,
        counts_per_torque=cpt,
        rate_hz=rate,
    )


def _signed(d: int) -> int:
    """A 32-bit sequence difference as a signed number in [-2^31, 2^31)."""
    return ((d + _HALF) & _MASK) - _HALF


class RDTTracker:
    """The packet handling of one RDT stream: datagrams in, :class:`Reading` out.

    Pure bookkeeping, no I/O: :class:`NetFTSource` feeds it every datagram it receives, and
    tests feed it scripted ones.

    Parameters
    ----------
    rate_hz : float or None
        RDT output rate; None times samples by the host clock instead.
    force_scale, torque_scale : float
        N per force count and N·m per torque count.
    strict : iterable of str
        Faults (of :data:`FAULTS`) that raise :class:`StreamFault` instead of being counted.
    window : int
        How far back (records) a packet may arrive and still be told late from duplicate.
    restart_silence_s : float
        A packet from the past after at least this much silence (host clock) is a restart.
    rate_check_s : float
        Host-clock seconds after which the device rate is checked against the host clock
        (from then on, every quarter of it, over the whole span).
    rate_tolerance : float
        Relative difference between ``rate_hz`` and the arrival rate that is warned about.
    where : str
        Names the device in messages.

    Attributes
    ----------
    received, lost, duplicates, late, malformed, dropped, restarts, stalls, status_records : int
        Counters: samples passed on; records missing on the network (gaps, minus the late
        ones that later filled a gap, minus softtip's own drops); duplicates and late
        packets dropped; datagrams that were not a record; records softtip's queue dropped;
        restarts re-synchronised; records with a stalled F/T sequence; records with a
        nonzero status word.
    last_status : int
        Status word of the newest record.
    measured_rate_hz : float or None
        Records per second by the host clock (device sequence over host time), once known.
    warnings : list of str
        What was warned about, in order (at most 20, then a last one saying so); the
        device is not named in them (``where`` names it in errors).
    """

    def __init__(
        self,
        rate_hz: float | None,
        force_scale: float,
        torque_scale: float,
        *,
        strict: Iterable[str] = (),
        window: int = 1 << 16,
        restart_silence_s: float = 0.25,
        rate_check_s: float = 2.0,
        rate_tolerance: float = 0.02,
        where: str = "device",
        on_warning: Callable[[str], None] | None = None,
    ) -> None:
        strict = frozenset(strict)
        unknown = strict - set(FAULTS)
        if unknown:
            raise ValueError(f"unknown faults {sorted(unknown)}; expected some of {', '.join(FAULTS)}")
        if rate_hz is not None and not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be positive and finite, got {rate_hz!r}")
        self.rate_hz = rate_hz
        self.force_scale, self.torque_scale = float(force_scale), float(torque_scale)
        self.strict = strict
        self.window = int(window)
        self.restart_silence_ns = int(restart_silence_s * 1e9)
        self.rate_check_ns = int(rate_check_s * 1e9)
        self.rate_tolerance = rate_tolerance
        self.where = where
        self.on_warning = on_warning
        self.received = self.lost = self.duplicates = self.late = self.malformed = 0
        self.dropped = self.restarts = self.stalls = self.status_records = 0
        self.last_status = 0
        self.measured_rate_hz: float | None = None
        self.warnings: list[str] = []
        #: Raw RDT sequence numbers of records softtip's receive queue dropped (the
        #: receiver adds to it under ``drop_lock``; gaps are checked against it).
        self.local_drops: set[int] = set()
        self.drop_lock = threading.Lock()
        self._statuses_seen: set[int] = set()
        self._mark = (0, 0, 0)  # late, duplicates, malformed at the previous sample
        self._pending: tuple | None = None  # a record that may start a new stream
        self._host_drops = 0  # socket-buffer drops not yet matched with a gap
        self._stalled = False
        self._rate_warned = False
        self._h: int | None = None  # newest accepted sequence, unwrapped, this epoch
        self._first = 0  # first accepted sequence of this epoch
        self._last_raw = 0
        self._last_ft = 0
        self._missing: set[int] = set()  # gaps (unwrapped) a late packet may still fill
        self._before_first: set[int] = set()  # late packets older than the first one seen
        self._t_base = 0.0
        self._seq_base = 0
        self._last_t = -math.inf
        self._last_arrival = 0
        self._period_ns = 1e9 / rate_hz if rate_hz else 0.0
        self._rate_anchor: tuple[float, int, int] | None = None  # (min phase, its sequence, block start)
        self._rate_block: list | None = None  # [block start, min phase, its sequence]
        self._t0_arrival: int | None = None

    # -- warnings and faults ---------------------------------------------------------
    def _warn(self, message: str) -> None:
        if len(self.warnings) < _MAX_WARNINGS:
            self.warnings.append(message)
        elif len(self.warnings) == _MAX_WARNINGS:
            self.warnings.append("more warnings not shown")
        if self.on_warning is not None:
            self.on_warning(message)

    def _fault(self, kind: str, message: str) -> None:
        if kind in self.strict:
            raise StreamFault(f"{self.where}: {message} (fatal: --strict {kind})")

    @property
    def held(self) -> bool:
        """A record is held back until the next one confirms a restart."""
        return self._pending is not None

    def counters(self) -> dict[str, int]:
        """All counters by name (``received``, ``lost``, ``dropped``, ``duplicates``, ...)."""
        return {
            "received": self.received,
            "lost": self.lost,
            "dropped": self.dropped,
            "duplicates": self.duplicates,
            "late": self.late,
            "malformed": self.malformed,
            "restarts": self.restarts,
            "stalls": self.stalls,
            "status_records": self.status_records,
        }

    # -- the packet handling -----------------------------------------------------------
    def feed(self, data: bytes, host_ns: int = 0, arrival_ns: int = 0, host_drops: int = 0) -> tuple[Reading, ...]:
        """Handle one datagram.

        Parameters
        ----------
        data : bytes
            The datagram as received.
        host_ns : int
            Host receive time, ns since the Unix epoch (0: unknown).
        arrival_ns : int
            Host receive time, ``time.monotonic_ns()`` clock (0: unknown).
        host_drops : int
            Datagrams this host dropped just before this one (its socket buffer overflowed:
            softtip did not read in time); the next gap counts them as dropped, not lost.

        Returns
        -------
        tuple of Reading
            The sample this datagram carries; nothing when it is dropped (malformed,
            duplicate, late) or held (it may start a restarted stream: the next record
            confirms it); two when it confirms a held one.

        Raises
        ------
        StreamFault
            A fault named in ``strict``.
        """
        if host_drops:
            self._host_drops += host_drops
        if len(data) != 36:
            self.malformed += 1
            self._fault("malformed", f"a datagram of {len(data)} bytes (expected one 36-byte RDT record)")
            return ()
        raw, ft, status, a, b, c, d, e, f = RDT_RECORD.unpack(data)
        pending = self._pending
        if pending is not None:  # the first record, or a restart, waits for the next to confirm it
            step = _signed(raw - pending[0])
            if step == 0:
                self.duplicates += 1
                self._fault("duplicate", f"a duplicate packet (sequence {raw})")
                return ()
            self._pending = None
            if 1 <= step <= _CONFIRM or (self._h is None and -self.window <= step <= self.window):
                return self._record(*pending, confirmed=True) + self._record(raw, ft, status, (a, b, c, d, e, f), host_ns, arrival_ns)
            self.malformed += 1  # a stray record that fits neither the old nor a new stream
            self._fault("malformed", f"a stray record (RDT sequence {pending[0]}) that no other record follows")
        return self._record(raw, ft, status, (a, b, c, d, e, f), host_ns, arrival_ns)

    def _record(
        self, raw: int, ft: int, status: int, w: tuple, host_ns: int, arrival_ns: int, confirmed: bool = False
    ) -> tuple[Reading, ...]:
        """Handle one record (``feed`` after parsing); ``confirmed``: a restart starts here."""
        h = self._h
        restart = confirmed and h is not None
        gap = 0
        if h is None:  # the first record, once the next one confirms it
            if not confirmed:
                self._pending = (raw, ft, status, w, host_ns, arrival_ns)
                return ()
            u = raw
            self._first = u
            self._seq_base = u
            self._t_base = 0.0
            self._t0_arrival = arrival_ns
        elif not confirmed:
            step = _signed(raw - self._last_raw)
            u = h + step
            if step == 0:
                return self._behind(u)
            if step < 0:
                silent = arrival_ns - self._last_arrival >= self.restart_silence_ns if arrival_ns else False
                dft = _signed(ft - self._last_ft)
                if dft > 0 or -step > self.window or (silent and u not in self._missing):
                    restart = True  # the RDT stream started again
                else:
                    return self._behind(u)
            elif step > self.window and self.rate_hz and arrival_ns and self._last_arrival:
                # a jump far ahead that the host clock does not back: a restart, not loss
                host_s = (arrival_ns - self._last_arrival) * 1e-9
                restart = step / self.rate_hz > 2.0 * host_s + 1.0
            if not restart:
                gap = step - 1
                if _signed(ft - self._last_ft) < 0:  # F/T counter reset: the device restarted
                    restart = True
        dropped = 0
        if restart and not confirmed:
            self._pending = (raw, ft, status, w, host_ns, arrival_ns)
            return ()
        if restart:
            self._restart(raw, arrival_ns)
            u = raw
            gap = 0
        elif gap:
            dropped = self._account_gap(h, gap)
        # accepted
        self._h = u
        self._last_raw = raw
        if h is not None and not restart and ft == self._last_ft:
            self.stalls += 1
            if not self._stalled:
                self._stalled = True
                self._warn(f"the F/T sequence stalled at {ft} (the device repeats stale data)")
            self._fault("stall", f"the F/T sequence stalled at {ft}")
        else:
            self._stalled = False
        self._last_ft = ft
        if status:
            self.status_records += 1
            if status not in self._statuses_seen and len(self._statuses_seen) < 64:
                self._statuses_seen.add(status)
                self._warn(f"device status word 0x{status:08x} (0 is healthy)")
            self._fault("status", f"device status word 0x{status:08x}")
        self.last_status = status
        rate = self.rate_hz
        if rate:
            t = self._t_base + (u - self._seq_base) / rate
            if arrival_ns:
                self._check_rate(u, arrival_ns)
        else:  # host arrival time, kept strictly increasing
            t = (arrival_ns - self._t0_arrival) * 1e-9 if arrival_ns else float(u - self._first)
            if t <= self._last_t:
                t = self._last_t + 1e-9
        self._last_t = t
        if arrival_ns:
            self._last_arrival = arrival_ns
        self.received += 1
        sf, st = self.force_scale, self.torque_scale
        a, b, c, d, e, f = w
        # what was discarded since the previous sample, for this sample's row
        late, dups, bad = self.late, self.duplicates, self.malformed
        mark = self._mark
        self._mark = (late, dups, bad)
        return (
            Reading(t, (a * sf, b * sf, c * sf, d * st, e * st, f * st), u, gap - dropped, arrival_ns, status,
                    host_ns * 1e-9 if host_ns else math.nan, dropped, late - mark[0], dups - mark[1], bad - mark[2]),
        )  # fmt: skip

    def _behind(self, u: int) -> tuple[()]:
        """A packet at or behind the newest one: late if it fills a gap, else a duplicate."""
        missing = self._missing
        if u in missing:
            missing.discard(u)
            self.late += 1
            self.lost -= 1
            self._fault("late", f"a late packet (sequence {u})")
        elif u < self._first and u not in self._before_first and len(self._before_first) < self.window:
            self._before_first.add(u)
            self.late += 1
            self._fault("late", f"a late packet (sequence {u})")
        else:
            self.duplicates += 1
            self._fault("duplicate", f"a duplicate packet (sequence {u})")
        return ()

    def _account_gap(self, h: int, gap: int) -> int:
        """``gap`` records missing after sequence ``h``: softtip's own drops, or lost.

        Returns how many softtip dropped.
        """
        hits = self._take_local_drops(self._last_raw, gap) if self.local_drops else []
        dropped = len(hits)
        if self._host_drops:  # the socket buffer's drops: some of this gap, softtip's own
            host = min(self._host_drops, gap - dropped)
            self._host_drops -= host
            dropped += host
        lost = gap - dropped
        self.dropped += dropped
        self.lost += lost
        if lost:
            missing = self._missing
            lo = max(h + 1, h + gap + 1 - self.window)
            missing.update(range(lo, h + gap + 1))
            if hits:  # a copy of a record softtip dropped is a duplicate, not late
                missing.difference_update(h + ((s - self._last_raw) & _MASK) for s in hits)
            if len(missing) > 2 * self.window:  # forget gaps too old to be filled
                floor = h + gap - self.window
                self._missing = {s for s in missing if s > floor}
        if dropped:
            self._fault("dropped", f"{dropped} record(s) dropped by softtip's receive queue (the consumer did not keep up)")
        if lost:
            self._fault("lost", f"{lost} record(s) lost before sequence {h + gap + 1}")
        return dropped

    def _take_local_drops(self, last_raw: int, gap: int) -> list[int]:
        """Which of the raw sequences after ``last_raw`` (``gap`` of them) softtip dropped."""
        drops = self.local_drops
        with self.drop_lock:
            if gap <= len(drops):
                hits = [s for s in ((last_raw + i) & _MASK for i in range(1, gap + 1)) if s in drops]
            else:
                hits = [s for s in drops if 0 < ((s - last_raw) & _MASK) <= gap]
            drops.difference_update(hits)
        return hits

    def _restart(self, raw: int, arrival_ns: int) -> None:
        """Re-synchronise on a new RDT epoch starting at ``raw``."""
        self.restarts += 1
        gap_s = (arrival_ns - self._last_arrival) * 1e-9 if arrival_ns and self._last_arrival else 0.0
        step = 1.0 / self.rate_hz if self.rate_hz else 1e-9
        self._t_base = self._last_t + max(gap_s, step)
        self._seq_base = raw
        self._first = raw
        self._missing = set()
        self._before_first = set()
        self._rate_anchor = self._rate_block = None
        self._stalled = False
        self._warn(
            f"the device restarted its stream (RDT sequence {raw}); "
            f"re-synchronised at t = {self._t_base:.3f} s by the host clock"
        )
        self._fault("restart", f"the device restarted its stream (RDT sequence {raw})")

    def _check_rate(self, u: int, arrival_ns: int) -> None:
        """Compare the device rate with the host clock, robust to late arrivals.

        A record arrives at ``T0 + u·P' + delay`` with ``delay >= 0``. Against the nominal
        period ``P``, the phase ``arrival - u·P`` drifts by ``P' - P`` per record; its lower
        envelope (the minimum over blocks of a quarter of ``rate_check_s``) ignores network
        and scheduling delays. The slope between the first block and the latest gives P'.
        """
        phase = arrival_ns - u * self._period_ns
        blk = self._rate_block
        if blk is None:
            self._rate_block = [arrival_ns, phase, u]
            return
        if phase < blk[1]:
            blk[1], blk[2] = phase, u
        if arrival_ns - blk[0] < self.rate_check_ns // 4:
            return
        self._rate_block = [arrival_ns, phase, u]
        ref = self._rate_anchor
        if ref is None:
            self._rate_anchor = (blk[1], blk[2], blk[0])
            return
        m0, u0, start = ref
        if arrival_ns - start < self.rate_check_ns or blk[2] <= u0:
            return
        slope = (blk[1] - m0) / (blk[2] - u0)  # ns per record
        measured = 1e9 / (self._period_ns + slope)
        self.measured_rate_hz = measured
        if not self._rate_warned and abs(measured / self.rate_hz - 1.0) > self.rate_tolerance:
            self._rate_warned = True
            self._warn(
                f"the device says it streams at {self.rate_hz:g} Hz (comrdtrate), but records "
                f"arrive at {measured:.1f} Hz by the host clock; t (device clock) is off by "
                f"{100 * (measured / self.rate_hz - 1):+.1f} %"
            )


def _interruptible(func: Callable[[], object], deadline: float, stop: threading.Event | None, what: str):
    """Run ``func`` in a thread; wait until it returns, ``deadline`` passes or ``stop`` is set."""
    box: dict[str, object] = {}

    def target() -> None:
        try:
            box["value"] = func()
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc

    th = threading.Thread(target=target, daemon=True, name=f"softtip-{what}")
    th.start()
    while th.is_alive():
        if stop is not None and stop.is_set():
            raise Interrupted(f"interrupted during {what}")
        if time.monotonic() >= deadline:
            raise TimeoutError
        th.join(0.05)
    if "error" in box:
        raise box["error"]  # type: ignore[misc]
    return box.get("value")


class NetFTSource:
    """An ATI Net F/T or Axia as a source of :class:`~softtip.io.sources.Reading`.

    Parameters
    ----------
    host : str
        The device's address.
    rdt_port, http_port : int
        UDP port of RDT (49152 on the device) and HTTP port (80).
    timeout : float
        s without a datagram before :class:`~softtip.io.sources.SourceError` (a silent sensor);
        also the limit for the HTTP request.
    buffer_s : float
        Seconds of samples the receive queue holds at ``max_rate_hz``.
    max_rate_hz : float
        Highest stream rate to size the queue for (the Net F/T streams up to 7 kHz).
    device_bias : bool
        Send the device's software-bias command at start (the sensor reads zero from then);
        softtip's own tare is independent of it.
    strict : iterable of str
        Faults of :data:`FAULTS` that end the stream (:class:`StreamFault`); none by default.
    stop : threading.Event, optional
        Set it to end discovery or the stream at once (within 0.05 s): :meth:`open` raises
        :class:`~softtip.io.sources.Interrupted`, iteration ends.
    resend_s : float
        s of silence after which the streaming request is sent again.
    on_warning : callable, optional
        Called with each warning's text (status words, restarts, stalls, the rate check).

    Attributes
    ----------
    info : DeviceInfo or None
    tracker : RDTTracker or None
        The counters (``lost``, ``dropped``, ``duplicates``, ``late``, ``malformed``, ...).

    Examples
    --------
    >>> with NetFTSource("192.168.1.1") as src:          # doctest: +SKIP
    ...     for est in softtip.run(src, "murakami2006"):
    ...         print(est.state)
    """

    def __init__(
        self,
        host: str,
        rdt_port: int = 49152,
        http_port: int = 80,
        timeout: float = 2.0,
        buffer_s: float = 5.0,
        max_rate_hz: float = 7000.0,
        device_bias: bool = False,
        *,
        strict: Iterable[str] = (),
        stop: threading.Event | None = None,
        resend_s: float = 0.5,
        on_warning: Callable[[str], None] | None = None,
    ) -> None:
        if not (isinstance(timeout, (int, float)) and math.isfinite(timeout) and timeout > 0):
            raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
        for name, port in (("rdt_port", rdt_port), ("http_port", http_port)):
            if not 0 < int(port) < 65536:
                raise ValueError(f"{name} must be in 1..65535, got {port!r}")
        self.strict = frozenset(strict)
        if self.strict - set(FAULTS):
            raise ValueError(f"unknown faults {sorted(self.strict - set(FAULTS))}; expected some of {', '.join(FAULTS)}")
        self.host, self.rdt_port, self.http_port = host, int(rdt_port), int(http_port)
        self.timeout = float(timeout)
        self.queue_size = max(1, int(buffer_s * max_rate_hz))
        self.device_bias = device_bias
        self.stop_event = stop
        self.resend_s = float(resend_s)
        self.on_warning = on_warning
        self.info: DeviceInfo | None = None
        self.tracker: RDTTracker | None = None
        self._sock: socket.socket | None = None
        self._queue: collections.deque = collections.deque()
        self._wake = threading.Event()
        self._waiting = False
        self._closing = False
        self._rx: threading.Thread | None = None
        self._rx_error: BaseException | None = None
        self._rx_dropped = 0
        self._host_overflow = 0  # socket-buffer drops not yet handed to the tracker
        self._last_request = 0.0

    @property
    def name(self) -> str:
        return f"{self.host}:{self.rdt_port}"

    @property
    def rate_hz(self) -> float | None:
        return self.info.rate_hz if self.info else None

    @property
    def lost(self) -> int:
        """Records lost on the network so far."""
        return self.tracker.lost if self.tracker else 0

    @property
    def received(self) -> int:
        """Samples passed on so far."""
        return self.tracker.received if self.tracker else 0

    @property
    def dropped(self) -> int:
        """Datagrams this host dropped: softtip's receive queue was full (the consumer did not
        keep up), or the socket's buffer overflowed (the receive thread was starved; Linux)."""
        return self._rx_dropped

    @property
    def warnings(self) -> list[str]:
        return self.tracker.warnings if self.tracker else []

    def counters(self) -> dict[str, int]:
        """The tracker's counters, with ``dropped`` counting every datagram the queue dropped."""
        c = self.tracker.counters() if self.tracker else {}
        c["dropped"] = self._rx_dropped
        return c

    def _where(self) -> str:
        return f"Net F/T at {self.host} (RDT UDP port {self.rdt_port}, HTTP port {self.http_port})"

    def _read_info(self) -> DeviceInfo:
        url = f"http://{self.host}:{self.http_port}/netftapi2.xml"

        def get() -> str:
            with urllib.request.urlopen(url, timeout=self.timeout) as resp:
                return resp.read(1 << 20).decode("latin-1")

        try:
            text = _interruptible(get, time.monotonic() + self.timeout + 0.5, self.stop_event, "discovery")
        except TimeoutError:
            raise SourceError(
                f"{self._where()}: no answer over HTTP within {self.timeout:g} s; "
                "expected a reachable Net F/T serving /netftapi2.xml"
            ) from None
        except (OSError, ValueError) as exc:
            raise SourceError(
                f"{self._where()}: cannot read the calibration over HTTP ({exc}); "
                "expected a reachable Net F/T serving /netftapi2.xml"
            ) from None
        return parse_device_xml(str(text), self._where())

    def _request(self, command: int) -> None:
        if self._sock is not None:
            try:
                self._sock.send(RDT_REQUEST.pack(_HEADER, command, 0))
            except OSError:  # unreachable for now (ICMP); the time-out says so if it lasts
                pass
            if command == _CMD_START:
                self._last_request = time.monotonic()

    def open(self) -> NetFTSource:
        """Read the calibration, start streaming and wait for the first datagram.

        Raises
        ------
        SourceError
            Device unreachable, calibration unusable, or no data within ``timeout``.
        Interrupted
            ``stop`` was set meanwhile.
        """
        if self._sock is not None:
            return self
        self.info = info = self._read_info()
        self.tracker = RDTTracker(
            info.rate_hz,
            FORCE_UNITS_SI[info.force_unit] / info.counts_per_force,
            TORQUE_UNITS_SI[info.torque_unit] / info.counts_per_torque,
            strict=self.strict,
            where=self._where(),
            on_warning=self.on_warning,
        )
        try:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            sock.connect((self.host, self.rdt_port))  # only the device's datagrams reach us
        except OSError as exc:
            raise SourceError(f"{self._where()}: cannot open the RDT socket ({exc})") from None
        self._stamps = False
        if sys.platform.startswith("linux"):
            try:
                sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
                sock.setsockopt(socket.SOL_SOCKET, _SO_RXQ_OVFL, 1)
                self._stamps = True
            except OSError:  # pragma: no cover - every Linux has them
                pass
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        except OSError:  # pragma: no cover - capped by the OS instead
            pass
        # blocking: the receive thread waits in the kernel with the GIL released, and takes
        # the GIL once per datagram (a time-out would take it twice, a wait each when busy)
        sock.settimeout(None)
        self._sock = sock
        self._closing = False
        self._rx = threading.Thread(target=self._receive, daemon=True, name="softtip-rdt-receive")
        self._rx.start()
        try:
            self._request(_CMD_START)
            deadline = time.monotonic() + self.timeout
            while not self._queue:
                if self.stop_event is not None and self.stop_event.is_set():
                    raise Interrupted("interrupted while waiting for the first RDT record")
                now = time.monotonic()
                if now >= deadline or self._rx_error is not None:
                    raise SourceError(
                        f"{self._where()}: no data for {self.timeout:g} s after the streaming request; "
                        "expected RDT records over UDP (is the sensor streaming, is UDP blocked?)"
                    )
                if now - self._last_request >= self.resend_s:
                    self._request(_CMD_START)
                self._wake.wait(0.05)
                self._wake.clear()
            if self.device_bias:
                self._request(_CMD_BIAS)
        except BaseException:
            self.close()
            raise
        return self

    def _receive(self) -> None:
        """Receive thread: datagrams (with host time stamps) into the queue, until closed."""
        sock, queue, cap = self._sock, self._queue, self.queue_size
        assert sock is not None
        tracker = self.tracker
        assert tracker is not None
        recvmsg, mono, wall = sock.recvmsg, time.monotonic_ns, time.time_ns
        ancsize = socket.CMSG_SPACE(16) + socket.CMSG_SPACE(4) if self._stamps else 0
        unpack_stamp = struct.Struct("=qq").unpack_from
        unpack_count = struct.Struct("=I").unpack_from
        overflows = 0  # the socket buffer's drop count so far
        append, wake = queue.append, self._wake
        while True:
            try:
                data, anc, _flags, _addr = recvmsg(2048, ancsize)
            except (ConnectionRefusedError, InterruptedError):  # ICMP: nobody there (yet)
                continue
            except OSError as exc:
                if not self._closing:
                    self._rx_error = exc
                    wake.set()
                return
            if self._closing:  # woken by close()
                return
            arrival, now = mono(), wall()
            host = 0
            for level, kind, payload in anc:
                if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(payload) >= 16:
                    sec, nsec = unpack_stamp(payload)
                    host = sec * 1_000_000_000 + nsec
                elif level == socket.SOL_SOCKET and kind == _SO_RXQ_OVFL and len(payload) >= 4:
                    # this host dropped datagrams before this one: this thread was starved
                    (count,) = unpack_count(payload)
                    if count != overflows:
                        self._rx_dropped += (count - overflows) & _MASK
                        self._host_overflow += (count - overflows) & _MASK
                        overflows = count
            if host and 0 <= now - host < 10**9:  # the kernel's stamp: arrival on the socket
                arrival -= now - host
            else:
                host = now
            if len(queue) >= cap:  # the consumer is not keeping up: softtip drops, counted
                self._rx_dropped += 1
                if len(data) == 36:
                    with tracker.drop_lock:
                        tracker.local_drops.add(int.from_bytes(data[:4], "big"))
                continue
            if self._host_overflow:
                data_drops, self._host_overflow = self._host_overflow, 0
                append((data, host, arrival, data_drops))
            else:
                append((data, host, arrival, 0))
            if self._waiting:
                wake.set()

    def close(self) -> None:
        """Stop streaming and the receive thread (idempotent)."""
        sock = self._sock
        if sock is None:
            return
        self._request(_CMD_STOP)
        self._closing = True
        try:
            sock.shutdown(socket.SHUT_RDWR)  # wakes the receive thread's blocking recvmsg
        except OSError:  # pragma: no cover - not connected: nothing to wake
            pass
        if self._rx is not None and self._rx is not threading.current_thread():
            self._rx.join(1.0)
        self._sock = None
        sock.close()

    def __enter__(self) -> NetFTSource:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    def _no_new_sample(self, tracker: RDTTracker) -> NoReturn:
        """Raise the :class:`SourceError` of a stream that gave no new sample for ``timeout`` s."""
        c = tracker.counters()
        faults = ", ".join(f"{c[k]} {k}" for k in ("malformed", "duplicates", "late") if c.get(k))
        raise SourceError(
            f"{self._where()}: no new sample for {self.timeout:g} s (--timeout; after {tracker.received} samples"
            + (f"; meanwhile {faults}" if faults else "")
            + "); expected a continuous RDT stream (sensor unplugged or stopped, or sending only faulty records?)"
        )

    def __iter__(self) -> Iterator[Reading]:
        """Samples until closed or ``stop`` is set.

        Raises
        ------
        SourceError
            No datagram for ``timeout`` s, or the socket failed.
        StreamFault
            A fault named in ``strict``.
        """
        if self._sock is None:
            self.open()
        tracker = self.tracker
        assert tracker is not None
        queue, wake = self._queue, self._wake
        popleft, feed = queue.popleft, tracker.feed
        stop = self.stop_event
        timeout_ns = int(self.timeout * 1e9)
        resend_ns = int(self.resend_s * 1e9)
        last_ns = time.monotonic_ns()  # the last new sample's arrival (malformed, repeated and late datagrams do not count)
        while True:
            if queue:
                if stop is not None and stop.is_set():  # a flood of datagrams must not hold off the end
                    return
                data, host, arrival, overflow = popleft()
                out = feed(data, host, arrival, overflow)
                if out:
                    last_ns = arrival
                    yield from out
                elif arrival - last_ns >= timeout_ns:
                    self._no_new_sample(tracker)
                continue
            # nothing queued: check for the end, a silence, then wait a little
            if self._sock is None or (stop is not None and stop.is_set()):
                return
            if self._rx_error is not None:
                raise SourceError(f"{self._where()}: receiving failed ({self._rx_error})")
            now = time.monotonic_ns()
            silent = now - last_ns
            if silent >= timeout_ns:
                self._no_new_sample(tracker)
            if silent >= resend_ns and time.monotonic() - self._last_request >= self.resend_s:
                self._request(_CMD_START)  # a device that restarted streams again when asked
            self._waiting = True
            if not queue:
                wake.wait(0.05)
            self._waiting = False
            wake.clear()
