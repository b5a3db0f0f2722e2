"""Live samples from an ATI Net F/T or Axia (RDT over UDP), via the ``pynetft`` client.

Needs the ``netft`` extra (``pip install 'softtip[netft]'``).

What happens on :meth:`NetFTSource.open`:

1. ``pynetft`` reads the calibration from the device over HTTP (``/netftapi2.xml``:
   counts per force and per torque unit, and the unit names) and starts RDT streaming on
   UDP. Its native receive thread and queue take the packets off the socket; the queue is
   sized for ``buffer_s`` seconds at the stream rate, so a busy Python consumer does not
   lose samples (an overflow is counted as ``dropped``, separately from network loss).
2. softtip reads ``comrdtrate`` (the RDT output rate) from the same XML, which ``pynetft``
   does not expose, to time-stamp samples from the RDT sequence: ``t = (seq − seq₀) / rate``.
   That is the device's sampling clock, free of network jitter, and a lost packet leaves a
   gap in ``t`` as it should. Without ``comrdtrate`` the host arrival time is used.
3. Force and torque are converted from the device's units (N, lbf, kgf, ... and N·m,
   N·mm, lbf·in, ...) to SI. The wrench is **not** biased on the device unless
   ``device_bias`` is set: softtip's estimator tares from the first samples, which needs
   the fingertip untouched at start.

Packet loss is read from gaps in the RDT sequence and reported per sample
(:attr:`Reading.lost`) and in total (:attr:`NetFTSource.lost`), never hidden.
"""

from __future__ import annotations

import re
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass

from softtip.sources import Reading, SourceError

__all__ = [
    "FORCE_UNITS_SI",
    "TORQUE_UNITS_SI",
    "DeviceInfo",
    "NetFTSource",
    "import_pynetft",
]

#: SI value (N) of one force unit, by pynetft's unit value.
FORCE_UNITS_SI = {
    "N": 1.0,
    "lbf": 4.4482216152605,
    "klbf": 4448.2216152605,
    "kN": 1e3,
    "kgf": 9.80665,
}
#: SI value (N·m) of one torque unit, by pynetft's unit value.
TORQUE_UNITS_SI = {
    "N-m": 1.0,
    "N-mm": 1e-3,
    "lbf-in": 0.1129848290276167,
    "lbf-ft": 1.3558179483314004,
    "kgf-cm": 0.0980665,
    "kN-m": 1e3,
}
_SEQ_MOD = 2**32  # RDT sequence numbers are uint32


def import_pynetft():
    """Import ``pynetft`` or raise an :class:`ImportError` that names the extra to install."""
    try:
        import pynetft
    except ImportError as exc:
        raise ImportError(
            "live Net F/T input needs the 'pynetft' package: pip install 'softtip[netft]'"
        ) from exc
    return pynetft


@dataclass(frozen=True)
class DeviceInfo:
    """What the device said about itself.

    Attributes
    ----------
    product : str
    force_unit, torque_unit : str
        Units of the calibrated data, as pynetft names them (``N``, ``N-mm``, ...).
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


def _read_rdt_rate(host: str, http_port: int, timeout: float) -> float | None:
    """``comrdtrate`` from ``netftapi2.xml``, or None (absent, unreachable, malformed)."""
    try:
        with urllib.request.urlopen(
            f"http://{host}:{http_port}/netftapi2.xml", timeout=timeout
        ) as resp:
            text = resp.read(65536).decode("latin-1")
    except (OSError, ValueError):
        return None
    m = re.search(r"<comrdtrate>\s*([0-9.eE+-]+)\s*</comrdtrate>", text)
    try:
        rate = float(m.group(1)) if m else None
    except ValueError:
        return None
    return rate if rate and rate > 0 else None


class NetFTSource:
    """An ATI Net F/T or Axia as a source of :class:`~softtip.sources.Reading`.

    Parameters
    ----------
    host : str
        The device's address.
    rdt_port, http_port : int
        UDP port of RDT (49152 on the device) and HTTP port (80).
    timeout : float
        s without a sample before :class:`~softtip.sources.SourceError` (a silent sensor).
    buffer_s : float
        Seconds of samples the receive queue holds at ``max_rate_hz``.
    max_rate_hz : float
        Highest stream rate to size the queue for (the Net F/T streams up to 7 kHz).
    device_bias : bool
        Send the device's software-bias command at start (the sensor reads zero from then);
        softtip's own tare is independent of it.

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
    ) -> None:
        if not timeout > 0:
            raise ValueError(f"timeout must be positive, got {timeout!r}")
        self.host, self.rdt_port, self.http_port = host, int(rdt_port), int(http_port)
        self.timeout = float(timeout)
        self.queue_size = max(1, int(buffer_s * max_rate_hz))
        self.device_bias = device_bias
        self.info: DeviceInfo | None = None
        #: Packets missing from the RDT sequence so far.
        self.lost = 0
        #: Samples received so far.
        self.received = 0
        self._client = None
        self._scale: dict[tuple[str, str], tuple[float, float]] = {}

    @property
    def name(self) -> str:
        return f"{self.host}:{self.rdt_port}"

    @property
    def rate_hz(self) -> float | None:
        return self.info.rate_hz if self.info else None

    @property
    def dropped(self) -> int:
        """Samples the receive queue had to drop because softtip did not keep up."""
        if self._client is None:
            return 0
        return int(self._client.health().python_queue_dropped_count)

    def _where(self) -> str:
        return f"Net F/T at {self.host} (RDT UDP port {self.rdt_port}, HTTP port {self.http_port})"

    def open(self) -> NetFTSource:
        """Read the calibration, start streaming and wait for the first sample."""
        pynetft = import_pynetft()
        config = pynetft.Config(
            sensor_host=self.host,
            rdt_port=self.rdt_port,
            http_port=self.http_port,
            receive_timeout=self.timeout,
            configuration_connect_timeout=min(self.timeout, 2.0),
            configuration_timeout=self.timeout,
            recovery_policy=pynetft.RecoveryPolicy.FAIL_STOP,
        )
        client = pynetft.Client(config, queue_size=self.queue_size)
        try:
            client.start()
        except pynetft.NetFTError as exc:
            raise SourceError(
                f"{self._where()}: cannot read the calibration over HTTP ({exc}); "
                "expected a reachable Net F/T serving /netftapi2.xml"
            ) from None
        self._client = client
        try:
            # discovery (HTTP) and streaming both happen in pynetft's thread; its health says which failed
            if not client.wait_for_first_sample(self.timeout + min(self.timeout, 2.0)):
                health = client.health()
                if health.fault_code == pynetft.FaultCode.SENSOR_CONFIGURATION:
                    raise SourceError(
                        f"{self._where()}: cannot read the calibration over HTTP ({health.last_error}); "
                        "expected a reachable Net F/T serving /netftapi2.xml"
                    )
                raise SourceError(
                    f"{self._where()}: no data for {self.timeout:g} s after the streaming request; "
                    "expected RDT records over UDP (is the sensor streaming, is UDP blocked?)"
                )
            cal = client.health().sensor_configuration
            if cal is None:  # pragma: no cover - pynetft always has it once data flows
                raise SourceError(
                    f"{self._where()}: streaming, but the calibration is unknown"
                )
            c = cal.calibration
            self.info = DeviceInfo(
                product=cal.product_name,
                force_unit=c.force_unit.value,
                torque_unit=c.torque_unit.value,
                counts_per_force=c.counts_per_force_unit,
                counts_per_torque=c.counts_per_torque_unit,
                rate_hz=_read_rdt_rate(
                    self.host, self.http_port, min(self.timeout, 2.0)
                ),
            )
            self._scales(c.force_unit.value, c.torque_unit.value)
            if self.device_bias:
                client.bias()
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        """Stop streaming (idempotent)."""
        if self._client is not None:
            client, self._client = self._client, None
            client.stop()

    def __enter__(self) -> NetFTSource:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    def _scales(self, force_unit: str, torque_unit: str) -> tuple[float, float]:
        key = (force_unit, torque_unit)
        if key not in self._scale:
            if force_unit not in FORCE_UNITS_SI or torque_unit not in TORQUE_UNITS_SI:
                raise SourceError(
                    f"{self._where()}: calibration in units {force_unit!r} / {torque_unit!r}; expected force in "
                    f"{', '.join(FORCE_UNITS_SI)} and torque in {', '.join(TORQUE_UNITS_SI)}"
                )
            self._scale[key] = (
                FORCE_UNITS_SI[force_unit],
                TORQUE_UNITS_SI[torque_unit],
            )
        return self._scale[key]

    def _samples(self, pynetft) -> Iterator:
        """pynetft samples, through its native queue when possible.

        pynetft's public iterator turns each sample into a frozen dataclass, which costs
        about 50 µs per sample here: at 7 kHz that alone takes a third of a core. Reading
        the client's native queue directly and picking the few fields softtip uses costs
        about 8 µs. That queue (``Client._native``) is not public API, so when it is not
        there (another pynetft version) softtip falls back to ``Client.samples``.
        """
        client = self._client
        native = getattr(client, "_native", None)
        status = getattr(getattr(pynetft, "_native", None), "ReadStatus", None)
        if native is None or status is None or not hasattr(native, "read"):
            yield from client.samples(timeout=self.timeout)
            return
        read, timeout = native.read, self.timeout
        sample_status, timeout_status = status.SAMPLE, status.TIMEOUT
        while True:
            result = read(timeout)
            st = result.status
            if st == sample_status:
                yield result.sample
            elif st == timeout_status:
                raise TimeoutError
            else:  # closed: stopped, or faulted
                health = client.health()
                if health.fault_code != pynetft.FaultCode.NONE:
                    raise SourceError(
                        f"{self._where()}: the sensor stream failed ({health.fault_code.value}: {health.last_error}) "
                        f"after {self.received} samples"
                    )
                return

    def __iter__(self) -> Iterator[Reading]:
        if self._client is None:
            self.open()
        pynetft = import_pynetft()
        rate = self.rate_hz
        seq0 = prev = t0 = None
        unwrap = 0
        t_prev = -1.0
        revision = None
        sf = st = 1.0
        try:
            for s in self._samples(pynetft):
                if (
                    s.configuration_revision != revision
                ):  # the calibration can change while streaming
                    revision = s.configuration_revision
                    sf, st = self._scales(
                        pynetft.ForceUnit[s.force_unit.name].value,
                        pynetft.TorqueUnit[s.torque_unit.name].value,
                    )
                seq = s.rdt_sequence + unwrap
                if (
                    prev is not None and seq < prev - _SEQ_MOD // 2
                ):  # uint32 wrap-around
                    unwrap += _SEQ_MOD
                    seq += _SEQ_MOD
                if prev is None:
                    seq0, t0, lost = seq, s.received_at_ns, 0
                elif (
                    seq <= prev
                ):  # duplicate, or late (already counted as lost): drop it
                    continue
                else:
                    lost = seq - prev - 1
                    self.lost += lost
                prev = seq
                # device clock when the rate is known, else host arrival time
                t = (seq - seq0) / rate if rate else (s.received_at_ns - t0) * 1e-9
                if (
                    t <= t_prev
                ):  # equal arrival times (no rate): keep time strictly increasing
                    continue
                t_prev = t
                self.received += 1
                f, m = s.force, s.torque
                yield Reading(
                    t,
                    (f[0] * sf, f[1] * sf, f[2] * sf, m[0] * st, m[1] * st, m[2] * st),
                    seq,
                    lost,
                    s.received_at_ns,
                )
        except TimeoutError:
            raise SourceError(
                f"{self._where()}: no data for {self.timeout:g} s (after {self.received} samples); "
                "expected a continuous RDT stream (sensor unplugged or stopped?)"
            ) from None
        except pynetft.SensorFaultError as exc:
            raise SourceError(
                f"{self._where()}: the sensor stream failed ({exc}) after {self.received} samples"
            ) from None
