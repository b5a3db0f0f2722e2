"""RDT packet handling (softtip.io.netft.RDTTracker) under what networks and sensors do.

Hypothesis builds a device stream (any start sequence, so the 32-bit wrap is crossed),
then a network that loses, duplicates, delays and reorders records, inserts zero-length and
garbage datagrams and sets status words; a simple reference model (sets, no windows)
says what should come out. Every loop is bounded by the drawn sizes.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip.io.netft import FAULTS, RDT_RECORD, RDTTracker, StreamFault
from softtip.io.netft.rdt import _CONFIRM

RATE = 1000.0
MS = 1_000_000  # ns


def record(seq, ft, status=0, k=0):
    # the wrench encodes the device index k, so every output can be traced to its record
    return RDT_RECORD.pack(seq & 0xFFFFFFFF, ft & 0xFFFFFFFF, status, k, -k, 2 * k, 3, 4, 5)


@st.composite
def network(draw):
    n = draw(st.integers(2, 120))
    start = draw(st.one_of(st.integers(0, 2**32 - 1), st.integers(2**32 - 60, 2**32 - 1)))
    ft0 = draw(st.integers(0, 2**32 - 1))
    statuses = draw(st.lists(st.sampled_from([0, 0, 0, 0x80010000, 0x80000001]), min_size=n, max_size=n))
    items = []  # (arrival order key, datagram, device index or None)
    for k in range(n):
        fate = draw(st.sampled_from(["send", "send", "send", "lose", "dup", "delay"]))
        data = record(start + k, ft0 + 3 * k, statuses[k], k)
        if fate == "lose":
            continue
        delay = draw(st.integers(1, 6)) if fate == "delay" else 0
        items.append((k + delay + 0.5 * (delay > 0), data, k))
        if fate == "dup":
            items.append((k + draw(st.integers(0, 8)) + 0.25, data, k))
        if draw(st.integers(0, 9)) == 0:
            junk = draw(st.sampled_from([b"", b"\x12\x34", bytes(35), bytes(37), bytes(72)]))
            items.append((k + 0.1, junk, None))
        if draw(st.integers(0, 19)) == 0:  # a stray record far from the stream, either way
            off = draw(st.integers(2**17, 2**31 - 1)) * draw(st.sampled_from([1, -1]))
            stray = record(start + k + off, draw(st.integers(0, 2**32 - 1)), 0, 10**6)
            items.append((k + 0.2, stray, "stray"))
    items.sort(key=lambda x: x[0])
    # the first two records start the stream (the first waits for the second to confirm it):
    # a stray record among them costs a genuine one; not modelled here
    # (two distinct records: a duplicate of the first does not confirm it)
    distinct, second = set(), None
    for i, it in enumerate(items):
        if isinstance(it[2], int):
            distinct.add(it[2])
            if len(distinct) == 2:
                second = i
                break
    items = [it for i, it in enumerate(items) if it[2] != "stray" or (second is not None and i > second)]
    # two stray records in a row (only junk between them) whose sequences continue each other
    # (1 to _CONFIRM apart) are a restarted stream to any receiver: RDT carries no stream id,
    # and a restart is confirmed by exactly that (the documented limit). Not modelled: the
    # second is left out
    kept, previous = [], None
    for it in items:
        if it[2] == "stray":
            seq = RDT_RECORD.unpack(it[1])[0]
            if previous is not None and 1 <= (seq - previous) % 2**32 <= _CONFIRM:
                continue
            previous = seq
        elif it[2] is not None:
            previous = None
        kept.append(it)
    return start, statuses, [(d, k) for _, d, k in kept]


def reference(delivered):
    """What the tracker should do, from device indices (None: not a record)."""
    out, late, dup, malformed = [], 0, 0, 0
    seen, first, top = set(), None, None
    rows, mark = [], (0, 0, 0)  # per sample: late, duplicates, malformed since the previous
    stray = held = False  # a stray record held; the first record held (until the next one)
    for _data, k in delivered:
        if k is None:
            malformed += 1
            continue
        if held and k != first:  # the first record's sample comes out with the next record
            rows.append((late - mark[0], dup - mark[1], malformed - mark[2]))
            mark, held = (late, dup, malformed), False
        if stray:  # held, then shown up by the next record
            malformed += 1
            stray = False
        if k == "stray":
            stray = True
        elif top is None or k > top:
            held = first is None
            first = k if first is None else first
            top = k
            seen.add(k)
            out.append(k)
            if not held:
                rows.append((late - mark[0], dup - mark[1], malformed - mark[2]))
                mark = (late, dup, malformed)
        elif k in seen:
            dup += 1
        else:
            seen.add(k)
            late += 1
    malformed += stray  # still held at the end
    if top is None:
        return out, late, dup, malformed, 0, rows
    lost = (top - first + 1) - len(out) - sum(1 for k in seen if first < k < top and k not in out)
    return out, late, dup, malformed, lost, rows


@settings(max_examples=300, deadline=None)
@given(network())
def test_tracker_against_reference(net):
    start, statuses, delivered = net
    tr = RDTTracker(RATE, 1e-6, 1e-3)
    got = []
    for i, (data, _) in enumerate(delivered):
        got += tr.feed(data, host_ns=1_700_000_000 * 10**9 + i * MS, arrival_ns=10**12 + i * MS)
    out, late, dup, malformed, lost, rows = reference(delivered)
    if tr.held and tr.received == 0:  # one record in all: held until another confirms it
        assert len(set(out)) == 1 and not got
        return
    ks = [round(r.wrench[0] / 1e-6) for r in got]
    assert ks == out  # each record once, in device order, nothing invented
    assert (tr.late, tr.duplicates, tr.malformed + tr.held, tr.lost, tr.restarts) == (late, dup, malformed, lost, 0)
    assert tr.received == len(out)
    if got:
        # device clock across the 32-bit wrap: t is exactly (index - first index) / rate
        np.testing.assert_allclose([r.t for r in got], (np.array(out) - out[0]) / RATE, rtol=0, atol=1e-9)
        assert [r.status for r in got] == [statuses[k] for k in out]
        assert sum(r.lost for r in got) == out[-1] - out[0] + 1 - len(out)
        assert [(r.late, r.duplicates, r.malformed) for r in got] == rows
        assert all(r.dropped == 0 for r in got)
        assert all(1.7e9 <= r.host_time < 1.7e9 + 1 for r in got)  # host clock, s since the epoch
    nonzero = {statuses[k] for k in out} - {0}
    assert tr.status_records == sum(1 for k in out if statuses[k])
    assert len([w for w in tr.warnings if "status word" in w]) == len(nonzero)


def test_pre_wrap_packet_after_the_wrap_is_late_not_a_jump():
    tr = RDTTracker(RATE, 1.0, 1.0)
    seqs = [2**32 - 3, 2**32 - 2, 0, 1, 2**32 - 1, 2, 3]  # 2^32 - 1 arrives after the wrap
    got = [r for i, s in enumerate(seqs) for r in tr.feed(record(s, s + 7), arrival_ns=10**9 + i * MS)]
    assert [r.t for r in got] == pytest.approx([0.0, 0.001, 0.003, 0.004, 0.005, 0.006])
    assert (tr.late, tr.lost) == (1, 0)


def test_device_restart_resynchronises_on_the_host_clock():
    tr = RDTTracker(RATE, 1.0, 1.0)
    got = []
    for i in range(1, 301):  # 0.3 s of stream
        got += tr.feed(record(i, 7 * i), arrival_ns=10**9 + i * MS)
    # the device reboots: 2 s of silence, then both sequences start again from 1
    for i in range(1, 101):
        got += tr.feed(record(i, i), arrival_ns=10**9 + 2300 * MS + i * MS)
    t = np.array([r.t for r in got])
    assert len(got) == 400 and tr.restarts == 1 and tr.lost == tr.duplicates == 0
    assert np.all(np.diff(t) > 0)
    assert t[300] - t[299] == pytest.approx(2.001, abs=1e-6)  # the silence, by the host clock
    assert any("restarted" in w for w in tr.warnings)


def test_rdt_stream_restart_without_silence():
    # a new streaming request restarts the RDT sequence; the F/T sequence goes on
    tr = RDTTracker(RATE, 1.0, 1.0)
    got = [r for i in range(1, 51) for r in tr.feed(record(1000 + i, 7 * i), arrival_ns=10**9 + i * MS)]
    got += [r for i in range(1, 51) for r in tr.feed(record(i, 7 * (50 + i)), arrival_ns=10**9 + (50 + i) * MS)]
    assert len(got) == 100 and tr.restarts == 1 and tr.duplicates == 0
    assert np.all(np.diff([r.t for r in got]) > 0)


def test_stall_and_status_are_counted_and_strict_makes_them_fatal():
    tr = RDTTracker(RATE, 1.0, 1.0)
    got = [r for i in range(1, 11) for r in tr.feed(record(i, 5 if i > 3 else i, 0x80010000 if i == 7 else 0))]
    assert len(got) == 10
    assert tr.stalls == 6 and tr.status_records == 1  # F/T sequence 1, 2, 3, 5, then 5 six more times
    assert sum("stalled" in w for w in tr.warnings) == 1
    for kind, datagrams in [
        ("stall", [record(1, 1), record(2, 1)]),
        ("status", [record(1, 1), record(2, 2, 0x40000000)]),
        ("duplicate", [record(1, 1), record(1, 1)]),
        ("late", [record(1, 1), record(3, 3), record(2, 2)]),
        ("lost", [record(1, 1), record(3, 3)]),
        ("malformed", [record(1, 1), b""]),
        ("restart", [record(1, 9), record(2, 1), record(3, 2)]),  # the third confirms it
    ]:
        relaxed, strict = RDTTracker(RATE, 1.0, 1.0), RDTTracker(RATE, 1.0, 1.0, strict=[kind])
        for d in datagrams:
            relaxed.feed(d)
        with pytest.raises(StreamFault, match=f"--strict {kind}"):
            for d in datagrams:
                strict.feed(d)
    with pytest.raises(ValueError, match="unknown faults"):
        RDTTracker(RATE, 1.0, 1.0, strict=["typo"])
    assert "dropped" in FAULTS


def test_queue_drops_are_not_network_loss():
    tr = RDTTracker(RATE, 1.0, 1.0)
    tr.feed(record(1, 1))
    tr.local_drops.update({2, 3, 5})  # softtip's queue dropped these; 4 never arrived
    got = tr.feed(record(6, 6))  # the first record comes out with it
    assert (got[-1].lost, got[-1].dropped) == (1, 3) and (tr.dropped, tr.lost) == (3, 1)
    assert tr.feed(record(3, 3)) == () and tr.duplicates == 1  # a copy of a dropped one
    # the socket's buffer overflowed (the kernel says how many, not which) before record 9
    got = tr.feed(record(9, 9), host_drops=2)
    assert (got[-1].lost, got[-1].dropped) == (0, 2) and (tr.dropped, tr.lost) == (5, 1)
    assert not tr.local_drops


def test_rate_disagreeing_with_the_host_clock_is_warned():
    tr = RDTTracker(1000.0, 1.0, 1.0, rate_check_s=1.0)
    for i in range(1, 1500):  # records really arrive at 1100 Hz
        tr.feed(record(i, i), arrival_ns=10**9 + round(i * 1e9 / 1100))
    assert tr.measured_rate_hz == pytest.approx(1100, rel=1e-3)
    assert any("1100" in w and "+10.0 %" in w for w in tr.warnings)
    rng = np.random.default_rng(8380)
    delay = rng.exponential(0.3 * MS, 3000).astype(int)
    delay[rng.integers(0, 3000, 30)] += 60 * MS  # a loaded host: some arrive 60 ms late
    ok = RDTTracker(1000.0, 1.0, 1.0, rate_check_s=1.0)
    for i in range(1, 3000):
        ok.feed(record(i, i), arrival_ns=10**9 + i * MS + int(delay[i]))
    assert ok.measured_rate_hz == pytest.approx(1000, rel=1e-3)
    assert ok.warnings == []


def test_a_stray_record_is_not_taken_for_a_restart():
    tr = RDTTracker(RATE, 1.0, 1.0)
    got = [r for i in range(1, 11) for r in tr.feed(record(i, i), arrival_ns=10**9 + i * MS)]
    assert tr.feed(record(2**31 + 5, 77), arrival_ns=10**9 + 11 * MS) == () and tr.held
    got += tr.feed(record(11, 11), arrival_ns=10**9 + 12 * MS)
    assert [r.seq for r in got] == list(range(1, 12)) and (tr.malformed, tr.restarts) == (1, 0)
    assert got[-1].malformed == 1


def test_a_stray_record_before_the_stream_does_not_start_it():
    tr = RDTTracker(RATE, 1.0, 1.0)
    got = list(tr.feed(record(2**31, 5, 0, 999)))  # garbage of the right size, first
    got += [r for i in range(1, 11) for r in tr.feed(record(i, i, 0, i), arrival_ns=10**9 + i * MS)]
    assert [r.seq for r in got] == list(range(1, 11)) and [r.t for r in got][0] == 0.0
    assert (tr.malformed, tr.restarts) == (1, 0)
