"""The Net F/T or Axia as a source: discovery over HTTP, the RDT stream over UDP, the receive thread.

The device's page is parsed in :mod:`softtip.io.netft.device`, each datagram handled in
:mod:`softtip.io.netft.rdt`; :mod:`softtip.io.netft` tells the whole story.
"""

from __future__ import annotations

import collections
import math
import socket
import struct
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Iterable, Iterator
from typing import NoReturn

from softtip.io.netft.device import FORCE_UNITS_SI, TORQUE_UNITS_SI, DeviceInfo, parse_device_xml
from softtip.io.netft.rdt import (
    CMD_BIAS,
    CMD_START,
    CMD_STOP,
    FAULTS,
    RDT_HEADER,
    RDT_REQUEST,
    SEQ_MASK,
    RDTTracker,
)
from softtip.io.sources import Interrupted, Reading, SourceError

__all__ = ["NetFTSource"]

#: s after the device's bias command whose records are dropped: those it sent before it zeroed
#: itself and those on their way (a tare over them takes the old offset for the bias).
BIAS_SETTLE_S = 0.05
_SO_TIMESTAMPNS = 35  # Linux: kernel receive time stamps (SOL_SOCKET level, CLOCK_REALTIME)
_SO_RXQ_OVFL = 40  # Linux: datagrams the socket's buffer dropped so far, with each datagram


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
    def queued(self) -> int:
        """Datagrams received and not yet taken by the consumer (how far behind it is)."""
        return len(self._queue)

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
                self._sock.send(RDT_REQUEST.pack(RDT_HEADER, command, 0))
            except OSError:  # unreachable for now (ICMP); the time-out says so if it lasts
                pass
            if command == CMD_START:
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
            self._request(CMD_START)
            deadline = time.monotonic() + self.timeout
            self._waiting = True  # the receive thread wakes this wait at the first record
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
                    self._request(CMD_START)
                self._wake.wait(0.05)
                self._wake.clear()
            self._waiting = False
            if self.device_bias:
                self._request(CMD_BIAS)
                settled = time.monotonic() + BIAS_SETTLE_S
                while time.monotonic() < settled:
                    if self.stop_event is not None and self.stop_event.is_set():
                        raise Interrupted("interrupted while the sensor zeroed itself")
                    time.sleep(0.005)
                self._queue.clear()  # none read yet: the records of the sensor before its zero
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
                        self._rx_dropped += (count - overflows) & SEQ_MASK
                        self._host_overflow += (count - overflows) & SEQ_MASK
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
        self._request(CMD_STOP)
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
                self._request(CMD_START)  # a device that restarted streams again when asked
            self._waiting = True
            if not queue:
                wake.wait(0.05)
            self._waiting = False
            wake.clear()
