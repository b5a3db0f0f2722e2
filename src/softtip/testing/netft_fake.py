"""A fake ATI Net F/T (or Axia) for tests, benchmarks and demos without hardware.

It speaks the two protocols softtip uses, on the loopback interface by default:

* **RDT over UDP.** A client sends an 8-byte request ``>HHI`` (header ``0x1234``,
  command, sample count); command ``0x0002`` starts streaming (count 0: forever),
  ``0x0000`` stops, ``0x0042`` sets the software bias (the current sample becomes zero).
  Each record is 36 bytes, big-endian ``>III6i``: RDT sequence, F/T sequence, status, then
  ``Fx, Fy, Fz, Tx, Ty, Tz`` in counts, sent to the address the request came from.
* **HTTP**: ``GET /netftapi2.xml`` returns the calibration the real device publishes:
  ``cfgcpf`` / ``cfgcpt`` (counts per force / torque unit), ``scfgfu`` / ``scfgtu`` (the
  unit names), ``comrdtrate`` (RDT output rate, Hz), ``prodname``.

The wrench it streams is a given SI array, cycled; by default softtip's example grasp
resampled to the stream rate (fingertip untouched for the first 2 s, so taring works).
Faults can be injected to test that a session survives them: records dropped (``drop``,
``drop_every``), duplicated (``duplicate_every``), swapped with the next one
(``reorder_every``), malformed datagrams sent between records (``malformed_every``:
zero-length and 7-byte ones in turn), a nonzero status word (``status_every``), a device
restart (``reboot_after_s``: silent for ``reboot_silence_s``, then the RDT and F/T sequences
start again from 1 once streaming is requested again), or any datagram sequence at all
(``mangle``). The device can be ``silent`` (HTTP answers, UDP never does) to test
time-outs.

Run ``python -m softtip.testing.netft_fake --rate 1000`` for a device to point ``softtip stream
--netft 127.0.0.1 --rdt-port ... --http-port ...`` at; it prints its ports.
"""

from __future__ import annotations

import argparse
import select
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["RDT_RECORD", "RDT_REQUEST", "FakeNetFT", "example_wrench"]

#: RDT request: header 0x1234, command, sample count (big-endian).
RDT_REQUEST = struct.Struct(">HHI")
#: RDT record: rdt_sequence, ft_sequence, status, Fx, Fy, Fz, Tx, Ty, Tz (counts).
RDT_RECORD = struct.Struct(">III6i")
_HEADER = 0x1234
CMD_STOP, CMD_START, CMD_BIAS = 0x0000, 0x0002, 0x0042

# SI value of one device unit, for the unit names the device reports
_FORCE_UNIT_SI = {
    "N": 1.0,
    "lbf": 4.4482216152605,
    "kN": 1e3,
    "klbf": 4448.2216152605,
    "kgf": 9.80665,
}
_TORQUE_UNIT_SI = {"Nm": 1.0, "N-m": 1.0, "Nmm": 1e-3, "N-mm": 1e-3, "lbf-in": 0.1129848290276167,
                   "lbf-ft": 1.3558179483314004, "kgf-cm": 0.0980665, "kNm": 1e3}  # fmt: skip


def example_wrench(rate_hz: float) -> NDArray[np.float64]:
    """softtip's example grasp (10 s) resampled to ``rate_hz``: shape (N, 6), N and N·m."""
    from softtip.io.examples import load_example

    log = load_example()
    t = np.arange(0.0, log.t[-1], 1.0 / rate_hz)
    return np.stack([np.interp(t, log.t, log.wrench[:, i]) for i in range(6)], axis=-1)


class FakeNetFT:
    """A fake Net F/T on ``host`` (loopback by default): UDP RDT and HTTP calibration.

    Parameters
    ----------
    wrench : array-like, shape (N, 6), optional
        The wrench to stream, N and N·m, cycled one row per record; default
        :func:`example_wrench` at ``rate_hz``.
    rate_hz : float
        Records per second while streaming.
    host : str
        Address to bind, loopback by default.
    rdt_port, http_port : int
        Ports; 0 picks free ones (read them back from the attributes after :meth:`start`).
    counts_per_force, counts_per_torque : float
        Calibration: counts per ``force_unit`` / ``torque_unit``.
    force_unit, torque_unit : str
        Unit names as the device reports them (``N``, ``lbf``, ... / ``Nm``, ``Nmm``, ...).
    drop : iterable of int
        RDT sequence numbers never sent (lost packets); the sequence still advances.
    silent : bool
        Never answer on UDP.
    product_name : str
    duplicate_every, reorder_every, malformed_every, status_every, drop_every : int
        Every n-th record (0: never) is sent twice / sent after the next one / preceded by
        a malformed datagram / sent with status word ``status_word`` / not sent.
    status_word : int
        The status word of the records ``status_every`` picks.
    reboot_after_s : float, optional
        Restart once, this many seconds after streaming started.
    reboot_silence_s : float
        How long the restart keeps the device silent.
    mangle : callable, optional
        ``mangle(seq, record) -> datagrams``: what to send in place of each record (after
        the faults above); may keep state (hold a record back, send it later).
    """

    def __init__(
        self,
        wrench: ArrayLike | None = None,
        rate_hz: float = 1000.0,
        host: str = "127.0.0.1",
        rdt_port: int = 0,
        http_port: int = 0,
        counts_per_force: float = 1_000_000.0,
        counts_per_torque: float = 1_000.0,
        force_unit: str = "N",
        torque_unit: str = "Nmm",
        drop: Iterable[int] = (),
        silent: bool = False,
        product_name: str = "softtip fake Net F/T",
        *,
        duplicate_every: int = 0,
        reorder_every: int = 0,
        malformed_every: int = 0,
        status_every: int = 0,
        status_word: int = 0x80010000,
        drop_every: int = 0,
        reboot_after_s: float | None = None,
        reboot_silence_s: float = 1.0,
        mangle: Callable[[int, bytes], Sequence[bytes]] | None = None,
    ) -> None:
        if force_unit not in _FORCE_UNIT_SI or torque_unit not in _TORQUE_UNIT_SI:
            raise ValueError(f"unknown units {force_unit!r} / {torque_unit!r}")
        w = (
            example_wrench(rate_hz)
            if wrench is None
            else np.asarray(wrench, dtype=float).reshape(-1, 6)
        )
        scale = np.array([counts_per_force / _FORCE_UNIT_SI[force_unit]] * 3
                         + [counts_per_torque / _TORQUE_UNIT_SI[torque_unit]] * 3)  # fmt: skip
        self.counts = np.rint(w * scale).astype(np.int64)
        if np.any(np.abs(self.counts) >= 2**31):
            raise ValueError("wrench too large for 32-bit counts at this calibration")
        self.rate_hz = float(rate_hz)
        self.host = host
        self.counts_per_force, self.counts_per_torque = (
            counts_per_force,
            counts_per_torque,
        )
        self.force_unit, self.torque_unit = force_unit, torque_unit
        self.drop = frozenset(int(d) for d in drop)
        self.silent = silent
        self.product_name = product_name
        self.duplicate_every, self.reorder_every = duplicate_every, reorder_every
        self.malformed_every, self.status_every = malformed_every, status_every
        self.status_word, self.drop_every = status_word, drop_every
        self.reboot_after_s, self.reboot_silence_s = reboot_after_s, reboot_silence_s
        self.mangle = mangle
        self.reboots = 0
        self.sent = 0  # records sent
        self.requests: list[tuple[int, int]] = []  # (command, count) received
        self._bias = np.zeros(6, dtype=np.int64)
        self._stop = threading.Event()
        self._udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._udp.bind((host, rdt_port))
        self.rdt_port = self._udp.getsockname()[1]
        self._http = ThreadingHTTPServer((host, http_port), self._handler())
        self._http.daemon_threads = True
        self.http_port = self._http.server_address[1]
        self._threads: list[threading.Thread] = []

    def xml(self) -> bytes:
        """The ``netftapi2.xml`` document this device serves."""
        return (
            '<?xml version="1.0" encoding="ISO-8859-1"?>\n<netft>'
            f"<prodname>{self.product_name}</prodname><cfgcalsn>FT00000</cfgcalsn>"
            f"<comrdtrate>{self.rate_hz:g}</comrdtrate>"
            f"<scfgfu>{self.force_unit}</scfgfu><scfgtu>{self.torque_unit}</scfgtu>"
            f"<cfgcpf>{self.counts_per_force:g}</cfgcpf><cfgcpt>{self.counts_per_torque:g}</cfgcpt>"
            "</netft>\n"
        ).encode("ascii")

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        device = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                if self.path.split("?")[0] != "/netftapi2.xml":
                    self.send_error(404)
                    return
                body = device.xml()
                self.send_response(200)
                self.send_header("Content-Type", "text/xml")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args) -> None:  # quiet
                pass

        return Handler

    def start(self) -> FakeNetFT:
        """Start serving (threads); returns ``self``."""
        for target in (self._http.serve_forever, self._serve_udp):
            th = threading.Thread(target=target, daemon=True, name="fake-netft")
            th.start()
            self._threads.append(th)
        return self

    def stop(self) -> None:
        """Stop serving and close the sockets."""
        self._stop.set()
        self._http.shutdown()
        self._http.server_close()
        for th in self._threads:
            th.join(timeout=2.0)
        self._udp.close()

    def __enter__(self) -> FakeNetFT:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _serve_udp(self) -> None:
        sock = self._udp
        peer = None
        remaining = 0  # records still to send; -1 forever
        seq = 0
        n = len(self.counts)
        period = 1.0 / self.rate_hz
        t0 = k0 = 0
        held: bytes | None = None  # a record held back to be sent after the next one
        ft = 0
        started = None
        deaf_until = 0.0  # restarting: no answer until then
        while not self._stop.is_set():
            if self.reboot_after_s is not None and started is not None and not self.reboots:
                if time.perf_counter() - started >= self.reboot_after_s:
                    self.reboots += 1
                    remaining, seq, ft, held = 0, 0, 0, None
                    deaf_until = time.perf_counter() + self.reboot_silence_s
            # while streaming, poll for commands without blocking the schedule
            ready, _, _ = select.select([sock], [], [], 0.0 if remaining else 0.05)
            if ready and time.perf_counter() < deaf_until:
                sock.recvfrom(64)  # rebooting: requests go unanswered
                continue
            if ready:
                data, addr = sock.recvfrom(64)
                if len(data) >= RDT_REQUEST.size:
                    header, command, count = RDT_REQUEST.unpack_from(data)
                    if header == _HEADER:
                        self.requests.append((command, count))
                        if command == CMD_START and not self.silent:
                            peer, remaining = addr, (count if count else -1)
                            t0, k0 = time.perf_counter(), seq
                            started = started if started is not None else t0
                        elif command == CMD_STOP:
                            remaining = 0
                        elif command == CMD_BIAS:
                            self._bias = self.counts[seq % n].copy()
                continue
            if not remaining or peer is None:
                continue
            # send every record that is due by now (bursts after a late wake-up)
            due = k0 + int((time.perf_counter() - t0) * self.rate_hz) + 1
            while seq < due and remaining:
                seq += 1
                ft += 1
                c = self.counts[(seq - 1) % n] - self._bias
                status = self.status_word if _every(self.status_every, seq) else 0
                record = RDT_RECORD.pack(seq & 0xFFFFFFFF, ft & 0xFFFFFFFF, status, *c.tolist())
                out: list[bytes] = []
                if _every(self.malformed_every, seq):
                    out.append(b"" if (seq // self.malformed_every) % 2 else b"garbage")
                if seq not in self.drop and not _every(self.drop_every, seq):
                    if _every(self.reorder_every, seq) and held is None:
                        held = record
                    else:
                        out.append(record)
                        if _every(self.duplicate_every, seq):
                            out.append(record)
                        if held is not None:
                            out.append(held)
                            held = None
                if self.mangle is not None:
                    out = [d for r in out for d in (self.mangle(seq, r) if len(r) == RDT_RECORD.size else [r])]
                try:
                    for datagram in out:
                        sock.sendto(datagram, peer)
                        self.sent += 1
                except OSError:  # the client went away
                    remaining = 0
                    break
                if remaining > 0:
                    remaining -= 1
            wait = (seq - k0) * period - (
                time.perf_counter() - t0
            )  # until the next record is due
            time.sleep(min(max(wait, 0.0), period, 0.001))


def _every(n: int, seq: int) -> bool:
    return n > 0 and seq % n == 0


def main(argv: list[str] | None = None) -> None:
    """Run a fake device until interrupted; prints its ports."""
    p = argparse.ArgumentParser(
        description="A fake ATI Net F/T on the loopback interface (RDT over UDP + HTTP)."
    )
    p.add_argument(
        "--rate", type=float, default=1000.0, help="records per second (default 1000)"
    )
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument(
        "--rdt-port", type=int, default=0, help="UDP port (default: a free one)"
    )
    p.add_argument(
        "--http-port", type=int, default=0, help="HTTP port (default: a free one)"
    )
    p.add_argument(
        "--drop",
        type=int,
        nargs="*",
        default=(),
        help="RDT sequence numbers not to send",
    )
    p.add_argument(
        "--duration", type=float, default=None, help="stop after this many seconds"
    )
    for name, what in (
        ("duplicate", "send every N-th record twice"),
        ("reorder", "send every N-th record after the next one"),
        ("malformed", "send a malformed datagram before every N-th record"),
        ("status", "set the status word of every N-th record"),
        ("drop", "do not send every N-th record"),
    ):
        p.add_argument(f"--{name}-every", type=int, default=0, metavar="N", help=what + " (0: never)")
    p.add_argument("--reboot-after", type=float, default=None, metavar="S", help="restart once after S s of streaming")
    args = p.parse_args(argv)
    dev = FakeNetFT(
        rate_hz=args.rate,
        host=args.host,
        rdt_port=args.rdt_port,
        http_port=args.http_port,
        drop=args.drop,
        duplicate_every=args.duplicate_every,
        reorder_every=args.reorder_every,
        malformed_every=args.malformed_every,
        status_every=args.status_every,
        drop_every=args.drop_every,
        reboot_after_s=args.reboot_after,
    )
    with dev:
        print(
            f"fake Net F/T on {args.host}: --rdt-port {dev.rdt_port} --http-port {dev.http_port}",
            flush=True,
        )
        try:
            if args.duration is None:
                while True:
                    time.sleep(1.0)
            else:
                time.sleep(args.duration)
        except KeyboardInterrupt:
            pass


if __name__ == "__main__":  # pragma: no cover
    main()
