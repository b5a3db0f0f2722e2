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

With ``jobs`` > 1, ``jobs - 1`` worker processes and this one estimate the pieces: this process
reads, cuts and brings the carry past each piece with the stages that carry it alone
(:func:`softtip.estimator.batch.carry_over`), a worker runs the whole estimator from that
carry (this process does, when the workers have enough to do), and the pieces are yielded in
order, the bits of ``jobs=1``. Whether an earlier
contact latched is guessed when a piece is sent and checked when it comes back; a wrong
guess is estimated again, here.

Two things are taken from the first block rather than the whole log (identical for a log
sampled at a constant rate): the sample rate a low-pass filter is designed for, when
``config.sample_rate`` is not given (the median step of the first block's stamps).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from softtip.apps.pool import end_pool
from softtip.core.filtering import lowpass_sos, sosfilt_state
from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.estimator.batch import Carry, carry_over, estimate, infer_rate, validate_log
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.contact import track_contacts
from softtip.estimator.depth import resolve_depth
from softtip.estimator.measure import effective_noise
from softtip.estimator.results import Estimates
from softtip.estimator.tare import noise_in_use, tare_log

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
) -> Iterator[tuple[Estimates, dict[str, Any]]]:
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
        Processes estimating pieces at the same time: this one and ``jobs - 1`` workers (1:
        all in this process, one after the other). The pieces, and every bit of them, are
        those of ``jobs=1`` (see the module's notes); each worker holds a piece in memory.

    Yields
    ------
    (Estimates, dict)
        A piece's estimates (``contact_id`` counts on across pieces) and its rows of the
        extra columns.
    """
    if rows < 1:
        raise ValueError(f"rows = {rows}; expected at least 1")
    if jobs < 1:
        raise ValueError(f"jobs = {jobs}; expected at least 1")
    tip = load_fingertip(tip)
    config = resolve_depth(config or EstimatorConfig(), tip)
    if jobs > 1:
        yield from _parallel_pieces(blocks, tip, config, rows, jobs)
        return
    carry = Carry()
    yield from _split(blocks, tip, config, rows, carry, lambda t, w, cfg: _piece(t, w, tip, cfg, carry))


def _split(
    blocks: Iterable[Block], tip: Fingertip, config: EstimatorConfig, rows: int, carry: Carry,
    take: Callable[[NDArray, NDArray, EstimatorConfig], Any],
) -> Iterator[tuple[Any, dict[str, Any]]]:
    """Cut the log where :func:`_cut` allows; yield ``take(t, w, config)`` of each piece and its extra
    columns. ``take`` must bring ``carry`` past the piece (the next cut is looked for from there)."""
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
            cut = _cut(tt, ww, tip, config, carry, rows)
            if cut is None:
                break  # a contact goes on past the rows held: read more
            xx = {k: _joined(v) for k, v in x_buf.items()}
            yield take(tt[:cut], ww[:cut], config), {k: v[:cut] for k, v in xx.items()}
            t_buf, w_buf = [tt[cut:]], [ww[cut:]]
            x_buf = {k: [v[cut:]] for k, v in xx.items()}
            held = len(tt) - cut
    if held:
        tt, ww = _joined(t_buf), _joined(w_buf)
        yield take(tt, ww, config), {k: _joined(v) for k, v in x_buf.items()}


def _joined(parts: list[NDArray]) -> NDArray:
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _piece(t: NDArray, w: NDArray, tip: Fingertip, config: EstimatorConfig, carry: Carry) -> Estimates:
    import warnings

    from softtip.estimator.results import EstimatorWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)  # they are in Estimates.warnings
        return estimate(t, w, tip, config, carry=carry)


def _cut(t: NDArray, w: NDArray, tip: Fingertip, config: EstimatorConfig, carry: Carry, rows: int) -> int | None:
    """Where the held samples may be cut (the first sample of the next piece): the first
    sample at or after ``rows``, and after the tare, at which the estimator, run from
    ``carry``, is out of contact with nothing pending and the drift following. ``None``: no
    such sample yet (a contact goes on past the samples held)."""
    later = carry.tare is not None
    if later:
        bias, start, report = carry.tare.bias, 0, carry.tare
    else:
        bias, taring, report = tare_log(t, w, config)
        start = int(np.count_nonzero(taring))
        if not np.all(np.isfinite(bias)):
            return None  # still taring
    x = w - bias
    sos = None
    if config.lowpass_hz is not None:
        sos = lowpass_sos(config.lowpass_hz, config.sample_rate, config.lowpass_order)
        x, _ = sosfilt_state(sos, x, carry.zi if later else None)
    noise = effective_noise(noise_in_use(config, report), sos)
    ct = track_contacts(t, x, start, config, noise, carry.track if later else None)
    free = ~ct.busy
    free[: max(start + 1, rows)] = False
    idx = np.flatnonzero(free)
    return int(idx[0]) if len(idx) else None


# --- pieces in parallel (``jobs`` > 1) -------------------------------------------------------


def _parallel_pieces(
    blocks: Iterable[Block], tip: Fingertip, config: EstimatorConfig, rows: int, jobs: int
) -> Iterator[tuple[Estimates, dict[str, Any]]]:
    """:func:`estimate_pieces` by ``jobs`` processes, this one and ``jobs - 1`` workers: the same
    pieces, the same bits.

    This process reads, finds the cuts (:func:`_cut`) and brings the carry past each piece with
    the sequential stages alone (:func:`softtip.estimator.batch.carry_over`: tare, low-pass,
    contact tracking, a small part of the work); a piece goes to a worker, which runs the whole
    estimator on it from that carry, unless the workers have ``2`` pieces each to do already:
    then this process estimates it (no transfer, and its carry comes with it). The pieces are
    yielded in order. The one flag of the carry the sequential stages cannot give, whether an
    earlier contact latched (it marks the next contact's onset as re-latched), is guessed when
    a piece is started and checked when its predecessors are done: a piece started with the
    wrong guess is estimated again, here, with the right one. At most ``2 * jobs + 1`` pieces
    are held at once (memory stays bounded).
    """
    import copy
    import itertools
    import secrets
    import tempfile
    from collections import deque

    carry = Carry()  # the sequential stages' state, ahead of the pieces being estimated
    guess = _LatchGuess(config.contact_point != "track")
    shared_dir, counter, token = _SHARED_DIR or tempfile.gettempdir(), itertools.count(), secrets.token_hex(4)
    workers = jobs - 1
    pool = None
    pending: deque = deque()

    def start(t: NDArray, w: NDArray, cfg: EstimatorConfig) -> _Sent:
        before = copy.deepcopy(carry)
        before.had_latch = guess.next()
        counted = before.track.count if before.track is not None else 0
        if sum(p.future is not None and not p.future.done() for p, _ in pending) < 2 * workers:
            path = os.path.join(shared_dir, f"softtip-piece-{os.getpid()}-{next(counter)}-{token}")
            sent = _Sent(pool.submit(_estimate_piece, t, w, cfg, before, path), t, w, cfg, before, 0, path)
            sent.contacts = carry_over(t, w, tip, cfg, carry)
        else:  # every worker has work queued: estimated here, its carry with it
            after = copy.deepcopy(before)
            sent = _Sent(None, t, w, cfg, before, 0, None, (_piece(t, w, tip, cfg, after), after.had_latch))
            carry.tare, carry.zi, carry.track = after.tare, after.zi, after.track
            sent.contacts = after.track.count - counted
        guess.sent(sent.contacts)
        return sent

    def done(sent: _Sent, extra: dict[str, Any]) -> tuple[Estimates, dict[str, Any]]:
        if sent.future is None:
            est, had_latch = sent.result
        else:
            shared, had_latch = sent.future.result()
            est = _from_shared(shared, sent.path)
        if sent.before.had_latch != guess.had_latch:  # guessed wrong: again with the flag now known
            est, had_latch = _estimate_again(sent, tip, guess.had_latch)
        guess.back(had_latch, sent.contacts)
        return est, extra

    try:
        pool = _start_pool(tip, workers)
        for sent, extra in _split(blocks, tip, config, rows, carry, start):
            pending.append((sent, extra))
            while pending and (len(pending) > 2 * jobs or pending[0][0].future is None or pending[0][0].future.done()):
                yield done(*pending.popleft())
        while pending:
            yield done(*pending.popleft())
    except BaseException:  # an error, Ctrl-C, SIGTERM, a consumer that stops: the workers end now
        if pool is not None:
            end_pool(pool)
        for sent, _ in pending:  # and what they left for this process goes
            if sent.path is not None:
                with contextlib.suppress(OSError):
                    os.unlink(sent.path)
        raise
    pool.shutdown()


@dataclasses.dataclass
class _Sent:
    """A piece started: its samples and the carry it was started with (for a second run), and
    where its estimates come from (a worker's future and file, or this process's result)."""

    future: Any
    t: NDArray
    w: NDArray
    config: EstimatorConfig
    before: Carry
    contacts: int
    path: str | None  #: the file the worker leaves the estimates in
    result: tuple[Estimates, bool] | None = None  #: estimated here: the estimates and the flag after


def _estimate_again(sent: _Sent, tip: Fingertip, had_latch: bool) -> tuple[Estimates, bool]:
    """A piece started with the wrong ``had_latch``, estimated again (here) with the right one;
    and the flag after it."""
    sent.before.had_latch = had_latch
    est = _piece(sent.t, sent.w, tip, sent.config, sent.before)
    return est, sent.before.had_latch


class _LatchGuess:
    """``Carry.had_latch`` for the next piece sent, guessed, and the exact flag as the pieces come back.

    The guess: the exact flag if it is already true; otherwise, true when a piece in flight
    holds a contact and no contact back so far failed to latch (a log's contacts usually
    latch: the first one sets the flag for all that follow).
    """

    def __init__(self, latching: bool) -> None:
        self.latching = latching  # False: contact_point "track", the flag is never used or set
        self.had_latch = False  #: exact, after the pieces back so far
        self.contacts_back = 0
        self.contacts_out = 0

    def next(self) -> bool:
        if not self.latching or self.had_latch:
            return self.had_latch
        return self.contacts_out > 0 and self.contacts_back == 0

    def sent(self, contacts: int) -> None:
        self.contacts_out += contacts

    def back(self, had_latch: bool, contacts: int) -> None:
        self.had_latch = had_latch
        self.contacts_out -= contacts
        self.contacts_back += contacts


_WORKER_TIP: list[Fingertip] = []  # a worker's fingertip, sent once (a mesh is large)


def _worker_init(tip: Fingertip) -> None:
    """A worker of :func:`_parallel_pieces`: the parent decides when it ends (Ctrl-C and SIGHUP
    reach the whole process group; the parent ends the pool, SIGTERM at its default action)."""
    import signal

    for name in ("SIGINT", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _end_with_parent()
    _WORKER_TIP[:] = [tip]


def _end_with_parent() -> None:
    """End this process (a worker, or the server that forks them) as soon as its parent has
    ended: a signal that stops the run while the server loads softtip, or while a worker is
    started before the pool knows it, must not leave them running on. A worker also closes
    the server's keep-alive pipe it inherits (the server ends when the run's end closes it)."""
    import threading
    import time

    parent = os.getppid()
    if "multiprocessing.forkserver" in sys.modules:  # a worker: it starts no process of its own
        from multiprocessing import forkserver

        fd = getattr(forkserver._forkserver, "_forkserver_alive_fd", None)
        if fd is not None and parent != 1:
            with contextlib.suppress(OSError):
                os.close(fd)
            forkserver._forkserver._forkserver_alive_fd = None

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.2)
        os._exit(1)

    threading.Thread(target=watch, name="softtip-parent-watch", daemon=True).start()


def _estimate_piece(t: NDArray, w: NDArray, config: EstimatorConfig, carry: Carry, path: str) -> tuple[Any, bool]:
    """In a worker: a piece's estimates from ``carry`` (through the file ``path``: :func:`_to_shared`),
    and whether a contact latched by its end."""
    est = _piece(t, w, _WORKER_TIP[0], config, carry)
    return _to_shared(est, path), carry.had_latch


#: Where a worker leaves a piece's arrays for the parent: shared memory where there is one.
_SHARED_DIR = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
_ALIGN = 64


def _to_shared(obj: Any, path: str) -> tuple[bytes, list[int] | None]:
    """``obj`` pickled with its arrays' bytes written once into a new file ``path`` (not into
    the pickle, which would copy them twice more and once again in the parent: a piece's
    estimates are ~330 B per sample); :func:`_from_shared` maps them back without a copy.
    Where the file cannot be written (shared memory full, say) the arrays go in the pickle
    (sizes ``None``), and no file is left."""
    import pickle

    buffers: list = []
    head = pickle.dumps(obj, protocol=5, buffer_callback=buffers.append)
    raws = [b.raw() for b in buffers]
    sizes = [r.nbytes for r in raws]
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError:
        return pickle.dumps(obj, protocol=5), None
    try:  # written, not mapped: a mapping would fault in each new page (three times slower)
        for r, n in zip(raws, sizes):
            for part in (r, bytes(-n % _ALIGN)):
                view = memoryview(part)
                while len(view):
                    view = view[os.write(fd, view) :]
        if not sizes:
            os.write(fd, b"\0")
    except OSError:
        os.close(fd)
        os.unlink(path)
        return pickle.dumps(obj, protocol=5), None
    os.close(fd)
    return head, sizes


def _from_shared(shared: tuple[bytes, list[int] | None], path: str) -> Any:
    """The object :func:`_to_shared` left in ``path``; its arrays are views of the file's memory
    (the file is removed at once; the memory goes with the last array)."""
    import mmap
    import pickle

    head, sizes = shared
    if sizes is None:  # the worker could not write the file
        return pickle.loads(head)
    total = sum(-(-n // _ALIGN) * _ALIGN for n in sizes) or 1
    fd = os.open(path, os.O_RDWR)
    try:
        mm = mmap.mmap(fd, total)
    finally:
        os.close(fd)
        os.unlink(path)
    view, at, buffers = memoryview(mm), 0, []
    for n in sizes:
        buffers.append(view[at : at + n])
        at += -(-n // _ALIGN) * _ALIGN
    return pickle.loads(head, buffers=buffers)


def _start_pool(tip: Fingertip, jobs: int) -> Any:
    """``jobs`` worker processes (:func:`softtip.apps.pool.start_pool`), started at once: the
    server's imports then overlap this process's reading of the first piece."""
    from softtip.apps.pool import start_pool

    return start_pool(jobs, _worker_init, (tip,))


def warm_kernels() -> None:
    """Load the compiled kernels the pipeline uses (numba's cache; compiled there the first time)
    by running the estimator on the example grasp, latched, line-fit and low-pass filtered, with them
    forced on."""
    import warnings

    from softtip.core._jit import jit_enabled, set_jit
    from softtip.estimator.results import EstimatorWarning
    from softtip.io.examples import EXAMPLE_PATH
    from softtip.io.tables import read_log

    if not jit_enabled(1 << 62):  # no numba, or SOFTTIP_NUMBA=0: nothing to load
        return
    log = read_log(EXAMPLE_PATH, units="si")
    old = set_jit(True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)
            configs = (EstimatorConfig(), EstimatorConfig(contact_point="line-fit"), EstimatorConfig(lowpass_hz=10.0))
            for config in configs:
                estimate(log.t, log.wrench, "murakami2006", config)
    finally:
        set_jit(old)
