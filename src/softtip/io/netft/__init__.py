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
     datagram of the right size) is counted as malformed; two such records in a row whose RDT
     sequences continue each other (1 to 64 apart) cannot be told from a restarted stream, as
     RDT carries no stream identity, and are taken as one;
   * a silent device is asked again to stream (every ``resend_s``), so a device that
     rebooted streams again;
   * the rate in the XML is checked against the host clock (from 2 s on, by the lower
     envelope of arrival times, so late packets do not count): a difference of more than
     2 % is warned about, since ``t`` would be rescaled by it.

   Only the faults named in ``strict`` end the stream (:class:`StreamFault`).

The wrench is **not** biased on the device unless ``device_bias`` is set: softtip's
estimator tares from the first samples, which needs the fingertip untouched at start.
"""

from softtip.io.netft.device import (
    COUNTS_PER_UNIT_RANGE,
    FORCE_UNITS_SI,
    RDT_RATE_RANGE,
    TORQUE_UNITS_SI,
    DeviceInfo,
    parse_device_xml,
)
from softtip.io.netft.rdt import FAULTS, RDT_RECORD, RDT_REQUEST, RDTTracker, StreamFault
from softtip.io.netft.source import NetFTSource

__all__ = [
    "COUNTS_PER_UNIT_RANGE",
    "FAULTS",
    "FORCE_UNITS_SI",
    "RDT_RATE_RANGE",
    "RDT_RECORD",
    "RDT_REQUEST",
    "TORQUE_UNITS_SI",
    "DeviceInfo",
    "NetFTSource",
    "RDTTracker",
    "StreamFault",
    "parse_device_xml",
]
