"""A log larger than memory, estimated piece by piece with the bits of the one-shot run.

:func:`estimate_pieces` takes a log as an iterator of row blocks (``softtip.io.tables.iter_log``
reads CSV and Parquet that way) and yields :class:`~softtip.Estimates` for consecutive
pieces of it. A piece ends only where the estimator is out of contact: no contact pending
or held, the drift following the untouched wrench. Everything a contact accumulates (latch,
evidence windows, depth, joint window) is reset there, so what crosses the cut is small and
carried exactly (:class:`softtip.estimator.batch.Carry`): the tare's bias, the low-pass
filter's state, the contact tracker's drift average and hysteresis, the contact count. Each
piece is then the one-shot run's output for its samples, to the bit.

A piece holds at least ``rows`` samples, unless the log ends first, and more when a contact
(or a pending one) lasts past them: a contact longer than ``rows`` samples makes its piece
as long as the contact. The first piece holds the whole tare.

The stages that carry state across a cut (tare, low-pass filter, contact tracking) are what
finds the cut: one pass over the samples held runs them until the first sample where the
log may be cut, and the piece's per-contact stages start from that pass (they are not run
twice). With ``jobs`` > 1 the work runs on ``jobs`` threads besides the caller's: one reads,
cuts and so brings the carry past each piece, ``jobs`` threads run the per-contact stages on
the pieces, and the caller gets the pieces in order, the bits of ``jobs=1``
(and writes them, say, while the next are estimated). The compiled loops and numpy's and
pyarrow's work run without the GIL, and threads share the loaded kernels and the arrays: no
second interpreter to start, nothing to copy between processes. Whether an earlier contact
latched is guessed when a piece is started and checked when it is handed out; a wrong guess is
estimated again then.

Two things are taken from the first block rather than the whole log (identical for a log
sampled at a constant rate): the sample rate a low-pass filter is designed for, when
``config.sample_rate`` is not given (the median step of the first block's stamps).
"""

from __future__ import annotations

import copy
import dataclasses
import queue
import threading
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.estimator.batch import Carry, _estimate, _Sequential, _sequential_stages, infer_rate, validate_log
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.depth import resolve_depth
from softtip.estimator.results import Estimates

__all__ = ["DEFAULT_PIECE_ROWS", "estimate_pieces"]

#: Samples per piece unless a contact makes it longer (a peak of ~0.4 GB with the default pipeline).
DEFAULT_PIECE_ROWS = 1 << 17

Block = tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any]]


def estimate_pieces(
    blocks: Iterable[Block],
    tip: Fingertip | str = "murakami2006",
    config: EstimatorConfig | None = None,
    rows: int = DEFAULT_PIECE_ROWS,
    *,
    jobs: int = 1,
    after: Callable[[Estimates, dict[str, Any]], Any] | None = None,
) -> Iterator[tuple[Any, ...]]:
    """Estimate a log given block by block; yield each piece's estimates and extra columns.

    Parameters
    ----------
    blocks : iterable of (t, wrench, extra)
        Consecutive rows of one log: ``t`` (k,) s, ``wrench`` (k, 6) N and N·m (SI,
        sensor frame), ``extra`` a mapping of column name to (k,) values (numpy arrays).
        Time must not go back, within or across blocks.
    tip : Fingertip or str
    config : EstimatorConfig, optional
    rows : int
        Samples per piece (at least; see the module's notes), ≥ 1.
    jobs : int
        Threads estimating pieces at the same time (1: all in the caller's thread, one after
        the other; more: besides them a thread reads and cuts the log). The pieces, and every
        bit of them, are those of ``jobs=1`` (see the module's notes); up to ``jobs + 3``
        pieces are held in memory at once (started, being read, and the caller's), each with
        what ``after`` made of it.
    after : callable, optional
        Work on each piece's estimates and extra columns to do on the thread that estimated it
        (a command's summaries, checks and output blocks), so that it too runs in parallel; its
        result is yielded third.

    Yields
    ------
    (Estimates, dict) or (Estimates, dict, result)
        A piece's estimates (``contact_id`` counts on across pieces), its rows of the extra
        columns, and ``after(estimates, extra)`` when ``after`` is given.
    """
    if rows < 1:
        raise ValueError(f"rows = {rows}; expected at least 1")
    if jobs < 1:
        raise ValueError(f"jobs = {jobs}; expected at least 1")
    tip = load_fingertip(tip)
    config = resolve_depth(config or EstimatorConfig(), tip)
    if jobs > 1:
        for est, done, extra in _parallel_pieces(blocks, tip, config, rows, jobs, after):
            yield (est, extra) if after is None else (est, extra, done)
        return
    carry = Carry()
    for est, extra in _split(blocks, config, rows, carry, lambda t, w, x, cfg, stages: _estimate(t, w, tip, cfg, carry, stages)):
        yield (est, extra) if after is None else (est, extra, after(est, extra))


def _split(
    blocks: Iterable[Block], config: EstimatorConfig, rows: int, carry: Carry,
    take: Callable[[NDArray, NDArray, dict[str, NDArray], EstimatorConfig, _Sequential], Any],
) -> Iterator[tuple[Any, dict[str, Any]]]:
    """Cut the log where the estimator, run from ``carry``, is first out of contact at or after
    ``rows`` samples (and after the tare); yield ``take(t, w, extra, config, stages)`` of each
    piece (``stages``: its sequential stages, from ``carry`` as it was before the piece) and its
    extra columns. ``carry`` is brought past the piece after ``take`` (but for ``had_latch``, which
    ``take`` must bring past it)."""
    t_buf: list[NDArray] = []
    w_buf: list[NDArray] = []
    x_buf: dict[str, list[NDArray]] = {}
    held = 0
    last_t = -np.inf
    for t, w, extra in blocks:
        t, w = validate_log(t, w)
        if len(t) and t[0] < last_t:
            raise ValueError(f"time must not go back: {t[0]!r} s follows {last_t!r} s across blocks")
        if not len(t):
            continue
        last_t = float(t[-1])
        if config.lowpass_hz is not None and config.sample_rate is None:
            config = dataclasses.replace(config, sample_rate=infer_rate(t))
        t_buf.append(t)
        w_buf.append(w)
        for name, values in extra.items():
            x_buf.setdefault(name, []).append(np.asarray(values))
        held += len(t)
        while held >= rows:
            tt, ww = _joined(t_buf), _joined(w_buf)
            stages = _sequential_stages(tt, ww, config, carry, cut_from=rows)
            if stages is None:
                break  # a contact (or the tare) goes on past the rows held: read more
            cut = len(stages.taring)
            xx = {k: _joined(v) for k, v in x_buf.items()}
            extra = {k: v[:cut] for k, v in xx.items()}
            yield take(tt[:cut], ww[:cut], extra, config, stages), extra
            stages.advance(carry)
            t_buf, w_buf = [tt[cut:]], [ww[cut:]]
            x_buf = {k: [v[cut:]] for k, v in xx.items()}
            held = len(tt) - cut
    if held:
        tt, ww = _joined(t_buf), _joined(w_buf)
        stages = _sequential_stages(tt, ww, config, carry)
        extra = {k: _joined(v) for k, v in x_buf.items()}
        yield take(tt, ww, extra, config, stages), extra
        stages.advance(carry)


def _joined(parts: list[NDArray]) -> NDArray:
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


# --- pieces in parallel (``jobs`` > 1) -------------------------------------------------------


def _parallel_pieces(
    blocks: Iterable[Block], tip: Fingertip, config: EstimatorConfig, rows: int, jobs: int,
    after: Callable[[Estimates, dict[str, Any]], Any] | None = None,
) -> Iterator[tuple[Estimates, Any, dict[str, Any]]]:
    """:func:`estimate_pieces` on threads: the same pieces, the same bits; each piece's
    estimates, ``after(estimates, extra)`` (None without ``after``) and its extra columns.

    A thread of its own reads ``blocks`` and finds the cuts with the sequential stages (tare,
    low-pass, contact tracking, a small part of the work: :func:`_split`), which brings the
    carry past each piece; it hands each piece, its sequential stages and a copy of the carry
    before it to a pool of ``jobs`` threads (the per-contact stages). The caller's thread
    takes the pieces in order. The one flag of the carry the
    sequential stages cannot give, whether an earlier contact latched (it marks the next
    contact's onset as re-latched), is guessed when a piece is started and checked when its
    predecessors are done: a piece started with the wrong guess is estimated again, in the
    caller's thread, with the right one. At most ``jobs + 1`` pieces are started and not yet
    taken (memory stays bounded). An error in the reading thread (a bad row, a check of
    ``blocks``) is raised in the caller's thread after the pieces before it; when the caller
    stops (an error, a signal, a consumer that stops early), no further piece is read or
    started, and the reading thread has ended when this generator is closed (a piece being
    estimated finishes on its own).
    """
    from concurrent.futures import ThreadPoolExecutor

    carry = Carry()  # the sequential stages' state, ahead of the pieces being estimated
    guess = _LatchGuess(config.contact_point != "track")
    pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="softtip-piece")
    ready: queue.Queue = queue.Queue(maxsize=jobs)  # and one more started while the reader waits to put it
    stop = threading.Event()

    def start(t: NDArray, w: NDArray, extra: dict[str, NDArray], cfg: EstimatorConfig, stages: _Sequential) -> _Sent:
        before = copy.deepcopy(carry)  # (not yet brought past the piece: _split does that after)
        before.had_latch = guess.next()
        future = pool.submit(_estimate_piece, t, w, extra, tip, cfg, copy.deepcopy(before), stages, after)
        counted = carry.track.count if carry.track is not None else 0
        sent = _Sent(future, t, w, cfg, before, stages.ct.state.count - counted)
        guess.sent(sent.contacts)
        return sent

    def put(item: Any) -> bool:
        while not stop.is_set():
            try:
                ready.put(item, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def read() -> None:
        try:
            for item in _split(blocks, config, rows, carry, start):
                if not put(item):
                    return
            put(_END)
        except BaseException as exc:  # noqa: BLE001 - raised again in the caller's thread, in order
            put(_Failed(exc))

    reader = threading.Thread(target=read, name="softtip-read", daemon=True)
    reader.start()
    try:
        while True:
            item = ready.get()
            if item is _END:
                break
            if isinstance(item, _Failed):
                raise item.error
            sent, extra = item
            est, had_latch, done = sent.future.result()
            if sent.before.had_latch != guess.had_latch:  # guessed wrong: again with the flag now known
                est, had_latch = _estimate_again(sent, tip, guess.had_latch)
                done = after(est, extra) if after is not None else None
            guess.back(had_latch, sent.contacts)
            yield est, done, extra
    finally:  # the end, an error, a signal, a consumer that stops: nothing more is read or started
        stop.set()
        pool.shutdown(wait=False, cancel_futures=True)
        reader.join()  # it starts nothing more: the pool takes no new piece after its shutdown


_END = object()  #: the reading thread's last item


@dataclasses.dataclass
class _Failed:
    """What stopped the reading thread, for the caller's thread to raise."""

    error: BaseException


@dataclasses.dataclass
class _Sent:
    """A piece started: the estimates' future, its samples and the carry it was started with (for a second run)."""

    future: Any
    t: NDArray
    w: NDArray
    config: EstimatorConfig
    before: Carry
    contacts: int  #: the contacts that began in it


def _estimate_piece(t: NDArray, w: NDArray, extra: dict[str, NDArray], tip: Fingertip, config: EstimatorConfig,
                    carry: Carry, stages: _Sequential,
                    after: Callable[[Estimates, dict[str, NDArray]], Any] | None) -> tuple[Estimates, bool, Any]:  # fmt: skip
    """On a thread of the pool: a piece's estimates from its sequential stages and ``carry``'s
    ``had_latch``, whether a contact latched by its end, and ``after`` of the estimates and ``extra`` (None
    without it; of estimates started with the wrong ``had_latch`` too, then done again)."""
    est = _estimate(t, w, tip, config, carry, stages)
    return est, carry.had_latch, after(est, extra) if after is not None else None


def _estimate_again(sent: _Sent, tip: Fingertip, had_latch: bool) -> tuple[Estimates, bool]:
    """A piece started with the wrong ``had_latch``, estimated again (in the caller's thread) with
    the right one; and the flag after it. (The sequential stages are run again: the first run's
    arrays were the per-contact stages' to change.)"""
    sent.before.had_latch = had_latch
    est = _estimate(sent.t, sent.w, tip, sent.config, sent.before)
    return est, sent.before.had_latch


class _LatchGuess:
    """``Carry.had_latch`` for the next piece started, guessed (the reading thread), and the exact
    flag as the pieces are handed out (the caller's thread).

    The guess: the exact flag if it is already true; otherwise, true when a piece started holds a
    contact and no contact handed out so far failed to latch (a log's contacts usually latch:
    the first one sets the flag for all that follow). A guess read while the counts change is
    only a worse guess: the exact flag decides.
    """

    def __init__(self, latching: bool) -> None:
        self.latching = latching  # False: contact_point "track", the flag is never used or set
        self.had_latch = False  #: exact, after the pieces handed out so far
        self.contacts_back = 0
        self.contacts_out = 0
        self._lock = threading.Lock()

    def next(self) -> bool:
        with self._lock:
            if not self.latching or self.had_latch:
                return self.had_latch
            return self.contacts_out > 0 and self.contacts_back == 0

    def sent(self, contacts: int) -> None:
        with self._lock:
            self.contacts_out += contacts

    def back(self, had_latch: bool, contacts: int) -> None:
        with self._lock:
            self.had_latch = had_latch
            self.contacts_out -= contacts
            self.contacts_back += contacts


