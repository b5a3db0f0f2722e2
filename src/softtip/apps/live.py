"""The live path: a source through the streaming estimator to a terminal view and a recording.

:func:`run` drives the streaming estimator over any source, one estimate per sample;
:func:`run_live` is what ``softtip stream`` runs, for a live sensor and for a replayed log
alike. Its consumer loop takes each :class:`~softtip.io.sources.Reading` from the source, runs
:meth:`Estimator.update <softtip.estimator.Estimator.update>` on it and hands the result
on without waiting for anything slow:

* the :class:`Recorder` formats each row as it is handed one (in the loop, after the
  estimate) and queues the text; its own thread writes what is queued and flushes the file
  every ``flush_interval`` (0.05 s), always on a whole line, and the loop never waits on the
  disk; a stop (Ctrl-C, SIGTERM, SIGHUP, ``duration``) writes every row taken so far before the
  file is closed;
* the :class:`TerminalView` thread redraws one screen a few times a second from the latest
  estimate and the counters in :class:`LiveStats`;
* an optional ``on_estimate`` callback is called in the loop and must be cheap: the Rerun
  view's (:class:`softtip.viz.rerun.LiveRerun`) keeps 50 samples a second and queues them for
  a process of its own, which draws them.

Python runs one thread at a time, so every thread here takes its turn from the loop: the
recording's text is made in the loop itself (about 10 us a row, Python's formatting), where it
delays nothing but the loop's next wait; made by the recorder's thread, in blocks of rows with
pauses between, it interrupted the estimator's updates and set the 7 kHz soak's p99 (the
performance page). The recorder's thread only joins the lines and writes them (the system call
without the interpreter). The view redraws five times a second (about 20 us each), and Rerun's
work (about 2 ms a drawn sample) is in another process, which runs only on a core the
estimator's leave idle. The cyclic garbage collector's full
collections walk every object of the process (imports included: about 20 ms); the loop freezes
what exists when it starts (:func:`gc.freeze`), so that they walk only what the session made.

Receiving itself happens before the loop: for a Net F/T in softtip's receive thread and
queue (:mod:`softtip.io.netft`), so even a stalled loop does not lose packets until the queue
is full, and those it then drops are counted apart from the network's losses.
"""

from __future__ import annotations

import collections
import contextlib
import gc
import math
import operator
import os
import stat
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import TextIO

from softtip.core.fingertip import Fingertip
from softtip.errors import InputError
from softtip.estimator import Estimator, EstimatorConfig, SampleEstimate
from softtip.estimator.columns import COLUMNS
from softtip.io.sources import Reading, readings

__all__ = [
    "RECORD_COLUMNS",
    "KeyReader",
    "LiveStats",
    "Recorder",
    "TerminalView",
    "estimate_row",
    "run",
    "run_live",
]

_RAW_COLUMNS = ("t", "fx_raw", "fy_raw", "fz_raw", "mx_raw", "my_raw", "mz_raw")
# the estimate's columns but t: the row's t is the reading's (the same value)
_ESTIMATE_COLUMNS = tuple(c for c in COLUMNS if c.name != "t")
_STREAM_COLUMNS = ("seq", "lost", "dropped", "late", "duplicates", "malformed", "status", "host_time")
#: Columns of a live recording. First the samples as a log (``t`` and the raw, untared
#: wrench ``fx_raw … mz_raw``: a recording is a log that ``softtip estimate`` and ``--replay``
#: read as it is, :data:`softtip.io.formats.SOURCES` knows its header, and it reproduces the
#: recorded estimates), then the estimates with the columns of ``softtip estimate``, whose
#: ``fx … mz`` are the tared (and filtered) wrench in both, then the
#: stream's bookkeeping (see :class:`~softtip.io.sources.Reading`): the source's sequence
#: number; records missing just before this one (``lost``: network, or late) and dropped by
#: softtip's queue (``dropped``); late packets, duplicates and malformed datagrams
#: discarded since the previous row; the device's status word; the host receive time (s
#: since the Unix epoch). Column sums give the totals (network loss: ``lost − late``).
RECORD_COLUMNS: tuple[str, ...] = _RAW_COLUMNS + tuple(c.name for c in _ESTIMATE_COLUMNS) + _STREAM_COLUMNS
# Time and raw wrench exactly (shortest repr: re-reading the file gives the same doubles),
# the host time to the microsecond, the rest as softtip.io.tables.write_table formats numbers.
_FORMATS = {
    **{c: "%r" for c in _RAW_COLUMNS},
    **{c.name: {"str": "%s", "bool": "%d", "int64": "%d"}.get(c.dtype, "%.10g") for c in _ESTIMATE_COLUMNS},
    **{c: "%d" for c in _STREAM_COLUMNS}, "host_time": "%.6f", "stamp_ns": "%d",
}  # fmt: skip
#: The recording's last column where the source has its own absolute stamps (a replayed ROS
#: export): :attr:`~softtip.io.sources.Reading.stamp_ns`, ns since the Unix epoch, exact.
STAMP_COLUMN = "stamp_ns"
_DEG = 180.0 / math.pi


def _row_function(extra: tuple[str, ...] = ()) -> Callable[[SampleEstimate, Reading], tuple]:
    """:func:`estimate_row`, compiled once from the column registry into one tuple expression
    (as :func:`collections.namedtuple` compiles its methods): it runs per sample at the
    sensor's rate. A vector attribute whose components are all columns, in order (every one
    of softtip's: ``tests/test_columns.py`` checks it), is unpacked whole. ``extra``: the
    reading's fields appended (:data:`STAMP_COLUMN`)."""
    cells = ["float(r.t)", *(f"float(w[{i}])" for i in range(6))]
    for c in _ESTIMATE_COLUMNS:
        if c.index is None:
            cells.append(f"e.{c.attr} * _DEG" if c.degrees else f"e.{c.attr}")
        elif c.index == 0:
            cells.append(f"*e.{c.attr}")
    cells += [f"r.{name}" for name in _STREAM_COLUMNS + extra]
    namespace = {"_DEG": _DEG}
    exec(f"def estimate_row(e, r):\n    w = r.wrench\n    return ({', '.join(cells)},)\n", namespace)  # noqa: S102 - source made above from the registry's names
    row = namespace["estimate_row"]
    row.__module__, row.__doc__ = __name__, "One recording row (:data:`RECORD_COLUMNS`) from an estimate and its raw reading."
    row.__annotations__ = {"e": SampleEstimate, "r": Reading, "return": tuple}
    return row


estimate_row = _row_function()
_stamped_row = _row_function((STAMP_COLUMN,))


@dataclass
class LiveStats:
    """Counters of a live run, updated by the consumer loop, read by the view.

    Attributes
    ----------
    received : int
        Samples taken from the source.
    lost : int
        Sum of the samples' ``lost`` (records missing before each; used when the source
        has no ``counters``).
    dropped : Callable or None
        Returns samples dropped before softtip read them (receive queue overflow).
    counters : Callable or None
        Returns the source's counters by name (a Net F/T: ``lost``, ``dropped``,
        ``duplicates``, ``late``, ``malformed``, ``restarts``, ``stalls``,
        ``status_records``).
    warnings : Callable or None
        Returns the source's warnings so far (list of str).
    status : int
        Status word of the newest sample.
    last_nonzero_status : int
        The newest nonzero status word (0: none yet).
    started : float
        ``time.monotonic()`` at the first sample.
    last_at : float
        ``time.monotonic()`` when the newest sample was done.
    retares : list of float
        t (s) of each tare asked for again (``tare_request``), at the sample it began.
    latest : SampleEstimate or None
    """

    received: int = 0
    lost: int = 0
    dropped: Callable[[], int] | None = None
    started: float | None = None
    last_at: float | None = None
    retares: list[float] = field(default_factory=list)
    latest: SampleEstimate | None = None
    source_name: str = ""
    info: str = ""
    counters: Callable[[], dict[str, int]] | None = None
    warnings: Callable[[], list[str]] | None = None
    status: int = 0
    last_nonzero_status: int = 0
    rate_window: collections.deque = field(
        default_factory=lambda: collections.deque(maxlen=8)
    )

    def rate(self) -> float:
        """Samples per second over the last couple of seconds (needs calls a few times a second)."""
        now = time.monotonic()
        self.rate_window.append((now, self.received))
        (t0, n0), (t1, n1) = self.rate_window[0], self.rate_window[-1]
        return (n1 - n0) / (t1 - t0) if t1 > t0 else 0.0

    def totals(self) -> dict[str, int]:
        """Every counter by name: the source's own where it has them, else ``lost``/``dropped``."""
        c = dict(self.counters()) if self.counters else {}
        c.setdefault("lost", self.lost)
        c.setdefault("dropped", self.dropped() if self.dropped else 0)
        c["received"] = self.received
        return c


class Recorder:
    """Writes recording rows to a CSV file as they come: each formatted when handed over, the
    text written from a thread, in batches.

    The file is created when the first row is written (a run that fails before any sample
    leaves no file), and flushed to the OS every ``flush_interval`` seconds.

    Parameters
    ----------
    path : str or path-like
        CSV file; an existing file is replaced.
    flush_interval : float
        s between flushes (at most this much is lost if the process is killed).

    Attributes
    ----------
    columns : tuple of str
        The file's columns: :data:`RECORD_COLUMNS`, then :data:`STAMP_COLUMN` after
        :meth:`keep_stamps`.
    row : callable
        ``row(estimate, reading)``: the tuple :meth:`add` takes (:func:`estimate_row`, or with
        the reading's stamp after :meth:`keep_stamps`).
    """

    def __init__(
        self, path: str | os.PathLike[str], flush_interval: float = 0.05
    ) -> None:
        self.path = os.fspath(path)
        if os.path.isdir(self.path):
            raise InputError(
                f"{self.path}: is a directory; expected a file name for the recording"
            )
        try:
            special = not stat.S_ISREG(os.stat(self.path).st_mode)  # /dev/null, /dev/stdout, a FIFO: written into
        except OSError:
            special = False
        directory = os.path.dirname(os.path.abspath(self.path))
        if special:
            if not os.access(self.path, os.W_OK):
                raise InputError(f"{self.path}: cannot write there (permission denied); expected a writable file or device")
        elif not os.path.isdir(directory) or not os.access(directory, os.W_OK):
            raise InputError(
                f"{self.path}: cannot write there; expected an existing, writable directory"
            )
        self.flush_interval = flush_interval
        self._use(RECORD_COLUMNS, estimate_row)
        self.rows = 0
        self._pending: collections.deque = collections.deque()
        self._fh: TextIO | None = None
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(
            target=self._loop, daemon=True, name="softtip-recorder"
        )
        self._thread.start()

    def keep_stamps(self) -> None:
        """Record each reading's own absolute stamp too (:data:`STAMP_COLUMN`: a replayed log's,
        which ``softtip estimate`` keeps as a column as well); before the first row."""
        if self._fh is not None or self._pending:
            raise RuntimeError("keep_stamps() after the first row")
        self._use(RECORD_COLUMNS + (STAMP_COLUMN,), _stamped_row)

    def _use(self, columns: tuple[str, ...], row: Callable[[SampleEstimate, Reading], tuple]) -> None:
        self.columns, self.row = columns, row
        self._format = ",".join(_FORMATS[c] for c in columns) + "\n"

    def add(self, row: tuple) -> None:
        """Format one row and queue its line (from the consumer loop; never blocks on the disk).

        Raises
        ------
        InputError
            The writer thread could not write (disk full, a pipe or FIFO whose reader quit).
        """
        if self._error is not None:
            self.close()  # raises the InputError naming the file and the reason
        # formatted here, in the loop's thread: the writer's thread then holds the interpreter
        # only to join the lines, and never in the middle of an estimator's update
        self._pending.append(self._format % row)

    def _write_pending(self) -> None:
        pending = self._pending
        n = len(pending)
        if not n:
            return
        if self._fh is None:
            self._fh = open(self.path, "w", encoding="utf-8", newline="")
            self._fh.write(",".join(self.columns) + "\n")
        self._fh.write("".join([pending.popleft() for _ in range(n)]))
        self._fh.flush()
        self.rows += n

    def _loop(self) -> None:
        try:
            while not self._stop.wait(self.flush_interval):
                self._write_pending()
        except BaseException as exc:  # noqa: BLE001 - reported to the consumer on its next add()/close()
            self._error = exc

    def close(self) -> None:
        """Write what is queued, flush, sync and close (idempotent)."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join()
        try:
            if self._error is None:
                self._write_pending()
        except OSError as exc:
            self._error = exc
        finally:
            if self._fh is not None:
                try:
                    self._fh.flush()
                    if stat.S_ISREG(os.fstat(self._fh.fileno()).st_mode):  # no fsync of a pipe, FIFO or device
                        os.fsync(self._fh.fileno())
                except OSError as exc:
                    self._error = self._error or exc
                finally:
                    with contextlib.suppress(OSError):
                        self._fh.close()
        if self._error is not None:
            reason = getattr(self._error, "strerror", None) or str(self._error)
            raise InputError(
                f"{self.path}: cannot write the recording ({reason}); {self.rows} row(s) were written before"
            ) from None


class _DurationWatchdog:
    """Sets ``stop`` once ``deadline`` (``time.monotonic()``, adjustable) has passed; ``fired`` says it did."""

    def __init__(self, deadline: float, stop: threading.Event) -> None:
        self.deadline, self.stop, self.fired = deadline, stop, False
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="softtip-duration")
        self._thread.start()

    def _run(self) -> None:
        while not self._cancel.wait(min(0.05, max(0.0, self.deadline - time.monotonic()))):
            if time.monotonic() >= self.deadline:
                self.fired = True
                self.stop.set()
                return

    def cancel(self) -> None:
        self._cancel.set()
        self._thread.join(1.0)


def _fmt_vec(v, scale: float = 1.0, fmt: str = "{:+7.2f}") -> str:
    if any(math.isnan(x) for x in v):
        return "—"
    return "(" + ", ".join(fmt.format(x * scale) for x in v) + ")"


class TerminalView:
    """A one-screen live view, redrawn in place with ANSI escapes a few times a second.

    Parameters
    ----------
    stats : LiveStats
    out : text stream
        Where to draw (standard error by default, so standard output stays clean).
    interval : float
        s between redraws.
    config : EstimatorConfig, optional
        The estimator's settings: the line threshold shown next to ``|h|``
        (:meth:`EstimatorConfig.line_threshold`); the defaults when not given.
    recorder : Recorder, optional
        Its row count is shown.
    estimator : Estimator, optional
        Its tare, drift, contact count and warnings are shown.
    tare_key : bool
        Say that the ``t`` key tares again (:class:`KeyReader` is listening).
    """

    def __init__(
        self,
        stats: LiveStats,
        out: TextIO | None = None,
        interval: float = 0.2,
        config: EstimatorConfig | None = None,
        recorder: Recorder | None = None,
        estimator: Estimator | None = None,
        tare_key: bool = False,
    ) -> None:
        self.stats, self.out, self.interval = stats, out or sys.stderr, interval
        self.config, self.recorder, self.estimator, self.tare_key = config or EstimatorConfig(), recorder, estimator, tare_key
        self._lines = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=self._loop, daemon=True, name="softtip-view"
        )

    def start(self) -> TerminalView:
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop redrawing; the last screen stays."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self.draw()

    def _loop(self) -> None:
        while not self._stop.wait(self.interval):
            self.draw()

    def render(self) -> list[str]:
        """The screen as lines of text."""
        s, e = self.stats, self.stats.latest
        rate = s.rate()
        lines = [f"softtip stream  {s.source_name}  {s.info}".rstrip()]
        if e is None:
            lines.append("waiting for data ...")
        else:
            f_norm = (
                math.sqrt(sum(x * x for x in e.wrench[:3]))
                if not math.isnan(e.wrench[0])
                else math.nan
            )
            flags = " ".join(
                n
                for n, on in (("latched", e.latched), ("fallback", e.latch_fallback))
                if on
            )
            state = (
                "taring (keep the fingertip untouched)" if e.taring
                else e.state.upper() + (f" ({e.line_evidence})" if e.line_evidence else "")
            )
            lines += [
                f"t        {e.t:10.3f} s",
                f"state    {state:<8} {flags}",
                f"|f|      {f_norm:8.3f} N      f = {_fmt_vec(e.wrench[:3])} N",
                f"contact  r = {_fmt_vec(e.point, 1e3)} mm",
                f"normal   n = {_fmt_vec(e.normal, 1.0, '{:+6.3f}')}",
                f"|h|      {e.h_norm * 1e3:8.3f} N·mm   (significant above {float(self.config.line_threshold(e.h_std)) * 1e3:.3f} N·mm)"
                if not math.isnan(e.h_norm) else "|h|             —",
                f"edge     {e.angle * _DEG:+7.1f}° ± {e.angle_std * _DEG:.1f}°" if e.state == "line" else "edge            —",
            ]  # fmt: skip
        c = s.totals()
        lost = c["lost"]
        pct = 100.0 * lost / (s.received + lost) if s.received + lost > 0 else 0.0
        if s.counters is None:  # a log or a user's source: only what its readings say
            lines.append(
                f"rate     {rate:8.1f} Hz     samples {s.received}   lost {lost} ({pct:.2f} %)   dropped {c['dropped']}"
            )
        else:  # a sensor: what the network and the device did
            lines += [
                f"rate     {rate:8.1f} Hz     samples {s.received}",
                f"network  lost {lost} ({pct:.2f} %)   late {c.get('late', 0)}   duplicates {c.get('duplicates', 0)}"
                f"   malformed {c.get('malformed', 0)}   dropped by softtip {c['dropped']}",
                f"device   status 0x{s.status:08x}   nonzero in {c.get('status_records', 0)} samples"
                + (f" (last 0x{s.last_nonzero_status:08x})" if s.last_nonzero_status else "")
                + f"   restarts {c.get('restarts', 0)}   stalled {c.get('stalls', 0)}",
            ]
        warnings = s.warnings() if s.warnings else []
        if warnings:
            lines.append(f"warning  {warnings[-1]}" + (f"  (+{len(warnings) - 1} more)" if len(warnings) > 1 else ""))
        if self.recorder is not None:
            lines.append(f"record   {self.recorder.path}  {self.recorder.rows} rows")
        est = self.estimator
        if est is not None:
            rep = est.tare_report
            if rep is not None:
                d = est.drift
                lines.append(
                    f"tare     {rep.source if rep.source != 'tare' else rep.method} {rep.n_samples} samples, "
                    f"{rep.spikes} spike(s)   drift {math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2) * 1e3:.1f} mN   "
                    f"contacts {est.contacts}"
                )
            lines += [f"warning  {w[:150]}" for w in list(dict.fromkeys(est.warnings))[-3:]]
        lines.append("t: tare again (untouched)   Ctrl-C to stop" if self.tare_key else "Ctrl-C to stop")
        return lines

    def draw(self) -> None:
        # each line cut to the terminal's width: a line that wraps takes two rows, and the move back
        # up by a line count then stops short, stacking the screens (an 80-column terminal's network line)
        width = self._width()
        lines = [line if len(line) < width else line[: width - 2] + "…" for line in self.render()]
        # back to the top of the previous screen, then rewrite each line and clear the rest
        up = f"\x1b[{self._lines}F" if self._lines else ""
        text = up + "".join(f"\x1b[2K{line}\n" for line in lines) + "\x1b[J"
        self._lines = len(lines)
        try:
            self.out.write(text)
            self.out.flush()
        except (OSError, ValueError):  # terminal gone
            pass

    def _width(self) -> int:
        """Columns of the terminal drawn on (its current size: it may be resized); a large number
        for a file or a pipe, which do not wrap."""
        try:
            return max(20, os.get_terminal_size(self.out.fileno()).columns)
        except (OSError, ValueError, AttributeError):
            return 1 << 16


class KeyReader:
    """Calls ``actions[key]`` for each key pressed on a terminal, from a thread.

    The terminal is put in cbreak mode (keys arrive unbuffered, Ctrl-C still interrupts)
    until :meth:`close`. Does nothing when ``stream`` is not a terminal.
    """

    def __init__(self, actions: dict[str, Callable[[], None]], stream: TextIO | None = None) -> None:
        self.actions, self.stream = actions, stream or sys.stdin
        self._stop = threading.Event()
        self._saved = None
        self._thread = None
        try:
            import termios
            import tty

            fd = self.stream.fileno()
            if not os.isatty(fd):
                return
            self._saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        except (ImportError, OSError, ValueError, AttributeError):  # no terminal (or no termios)
            self._saved = None
            return
        self._thread = threading.Thread(target=self._loop, args=(fd,), daemon=True, name="softtip-keys")
        self._thread.start()

    def _loop(self, fd: int) -> None:
        import select

        while not self._stop.is_set():
            ready, _, _ = select.select([fd], [], [], 0.1)
            if ready:
                key = os.read(fd, 1).decode(errors="ignore").lower()
                action = self.actions.get(key)
                if action is not None:
                    action()

    def close(self) -> None:
        """Stop reading keys and give the terminal back as it was."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.stream.fileno(), termios.TCSADRAIN, self._saved)
            self._saved = None


@dataclass
class LiveSummary:
    """How a live run ended. ``reason``: ``end`` (source exhausted), ``duration``, ``interrupt``,
    or ``fault`` (the source raised, e.g. a fault named in ``--strict`` or ``--timeout``).

    ``counters`` has every counter of :meth:`LiveStats.totals`; ``warnings`` the source's.
    """

    samples: int
    lost: int
    dropped: int
    seconds: float
    reason: str
    last: SampleEstimate | None
    counters: dict[str, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    retares: list[float] = field(default_factory=list)  # t (s) of each tare asked for again

    @classmethod
    def of(cls, stats: LiveStats, reason: str) -> LiveSummary:
        """The summary of a run whose counters are ``stats``, ended for ``reason`` (a fault: its
        seconds end at the last sample, not after the silence that ended it)."""
        end = stats.last_at if reason == "fault" and stats.last_at is not None else time.monotonic()
        seconds = end - stats.started if stats.started is not None else 0.0
        totals = stats.totals()
        return cls(
            stats.received,
            totals["lost"],
            totals["dropped"],
            seconds,
            reason,
            stats.latest,
            totals,
            list(stats.warnings()) if stats.warnings else [],
            list(stats.retares),
        )


def run(
    source: Iterable,
    tip: Fingertip | str = "murakami2006",
    config: EstimatorConfig | None = None,
) -> Iterator[SampleEstimate]:
    """Run the streaming :class:`~softtip.estimator.Estimator` over a source.

    Parameters
    ----------
    source : iterable of (t, wrench) or Reading
        ``t`` in s, increasing; ``wrench`` raw, shape (6,), N and N·m. A source with a length
        (a list) is the estimator's ``expected_samples``: below 20 000 its steps run as Python
        unless numba is loaded already (the same bits).
    tip : Fingertip or str
        Fingertip, preset name or TOML path.
    config : EstimatorConfig, optional

    Yields
    ------
    SampleEstimate
        One per sample, as soon as it is computed.

    Examples
    --------
    >>> import softtip
    >>> log = softtip.load_example()
    >>> states = [e.state for e in softtip.run(zip(log.t, log.wrench))]
    >>> states[-1]
    'line'
    """
    # a source of known length (a list, a replayed log) tells the estimator whether compiling pays
    estimator = Estimator(tip, config, expected_samples=operator.length_hint(source) or None)
    update = estimator.update
    for item in source:
        yield update(item[0], item[1])


def run_live(
    source: Iterable,
    estimator: Estimator,
    *,
    recorder: Recorder | None = None,
    view: TerminalView | None = None,
    stats: LiveStats | None = None,
    duration: float | None = None,
    stop: threading.Event | None = None,
    on_estimate: Callable[[SampleEstimate, Reading], None] | None = None,
    tare_request: threading.Event | None = None,
    freeze_gc: bool = True,
) -> LiveSummary:
    """Run ``source`` through ``estimator`` until it ends, ``duration`` passes or ``stop`` is set.

    Parameters
    ----------
    source : iterable of Reading or (t, wrench)
    estimator : Estimator
    recorder : Recorder, optional
        Gets one row per sample; closed (flushed) at the end, also on errors.
    view : TerminalView, optional
        Started here, stopped at the end.
    stats : LiveStats, optional
        Counters to update (the view's); a new one otherwise.
    duration : float, optional
        s of wall-clock time after the first sample (its arrival on this host, for a device).
    stop : threading.Event, optional
        Set it (e.g. from a SIGINT handler) to end the run cleanly.
    on_estimate : callable, optional
        Called with each estimate and its reading, in the loop.
    tare_request : threading.Event, optional
        Set it (e.g. from a key) to re-tare (:meth:`Estimator.tare`) from the next sample.
    freeze_gc : bool
        Collect, then freeze (:func:`gc.freeze`) the objects that exist before the first
        sample, for the run: the cyclic garbage collector's full collections then walk only
        the objects the run made (with softtip and numpy loaded, a full collection of
        everything takes about 20 ms of CPU: 140 samples at 7 kHz). Unfrozen at the end.

    Returns
    -------
    LiveSummary
    """
    stats = stats or LiveStats()
    stop = stop or threading.Event()
    update = estimator.update
    add = recorder.add if recorder is not None else None
    row = recorder.row if recorder is not None else None
    reason = "end"
    if view is not None:
        view.start()
    deadline = math.inf
    # --duration also ends a session that never gives a sample (a device sending only
    # malformed or repeated datagrams): a watchdog sets ``stop`` at the duration counted
    # from now, then from the first sample
    watchdog = _DurationWatchdog(time.monotonic() + duration, stop) if duration is not None else None
    frozen = freeze_gc and gc.isenabled()
    if frozen:
        gc.collect()
        gc.freeze()
    try:
        for r in readings(source):
            if stats.started is None:
                # from the first sample's arrival (a device's), so a start-up backlog is not recorded on top
                stats.started = r.arrival_ns * 1e-9 if r.arrival_ns else time.monotonic()
                if duration is not None:
                    deadline = stats.started + duration
                    watchdog.deadline = deadline
            if tare_request is not None and tare_request.is_set():
                tare_request.clear()
                estimator.tare()
                stats.retares.append(r.t)
            e = update(r.t, r.wrench)
            stats.received += 1
            stats.lost += r.lost
            if r.status:
                stats.last_nonzero_status = r.status
            stats.status = r.status
            stats.latest = e
            if add is not None:
                add(row(e, r))
            if on_estimate is not None:
                on_estimate(e, r)
            stats.last_at = now = time.monotonic()
            if now >= deadline:
                reason = "duration"
                break
            if stop.is_set():
                reason = "duration" if watchdog is not None and watchdog.fired else "interrupt"
                break
        else:
            if stop.is_set():  # the source ended because it was asked to stop
                reason = "duration" if watchdog is not None and watchdog.fired else "interrupt"
    finally:
        if frozen:
            gc.unfreeze()
        if watchdog is not None:
            watchdog.cancel()
        try:
            if recorder is not None:
                recorder.close()
        finally:
            if view is not None:
                view.stop()  # after the recorder, so the last screen shows every row
    return LiveSummary.of(stats, reason)
