"""The RDT protocol's packet handling: 36-byte records in, :class:`~softtip.io.sources.Reading` out.

Pure bookkeeping, no I/O (sequence unwrapping, loss, duplicates, late packets, restarts,
stalls, the status word, the rate check): :class:`~softtip.io.netft.NetFTSource` feeds it
every datagram it receives, and tests feed it scripted ones.
"""

from __future__ import annotations

import math
import struct
import threading
from collections.abc import Callable, Iterable

from softtip.io.sources import Reading, SourceError

__all__ = ["CMD_BIAS", "CMD_START", "CMD_STOP", "FAULTS", "RDT_HEADER", "RDT_RECORD", "RDT_REQUEST", "SEQ_MASK", "RDTTracker", "StreamFault"]

#: RDT request: header 0x1234, command, sample count (big-endian).
RDT_REQUEST = struct.Struct(">HHI")
#: RDT record: rdt_sequence, ft_sequence, status, Fx, Fy, Fz, Tx, Ty, Tz (counts).
RDT_RECORD = struct.Struct(">III6i")
#: RDT request header and commands (stop, start streaming, software bias).
RDT_HEADER, CMD_STOP, CMD_START, CMD_BIAS = 0x1234, 0x0000, 0x0002, 0x0042
#: The 32-bit sequence numbers wrap at this mask.
SEQ_MASK, _HALF = 2**32 - 1, 2**31
#: Faults ``strict`` can make fatal.
FAULTS = ("status", "restart", "stall", "lost", "duplicate", "late", "malformed", "dropped")
_MAX_WARNINGS = 20
_CONFIRM = 64  # a restart is confirmed by a record at most this far after its first


class StreamFault(SourceError):
    """A fault the user asked to be fatal (``strict``) happened in the stream."""


def _signed(d: int) -> int:
    """A 32-bit sequence difference as a signed number in [-2^31, 2^31)."""
    return ((d + _HALF) & SEQ_MASK) - _HALF


class RDTTracker:
    """The packet handling of one RDT stream: datagrams in, :class:`~softtip.io.sources.Reading` out.

    Pure bookkeeping, no I/O: :class:`~softtip.io.netft.NetFTSource` feeds it every datagram it receives, and
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
                missing.difference_update(h + ((s - self._last_raw) & SEQ_MASK) for s in hits)
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
                hits = [s for s in ((last_raw + i) & SEQ_MASK for i in range(1, gap + 1)) if s in drops]
            else:
                hits = [s for s in drops if 0 < ((s - last_raw) & SEQ_MASK) <= gap]
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
