"""3-D view of the estimates with Rerun: live (``softtip stream --rerun``) or offline.

Needs the ``rerun-sdk`` package (``pip install rerun-sdk``; the ``viz`` extra). What
is logged, sensor frame, metres, on the timeline ``t`` (s of the log):

* ``tip/skin`` (static): the fingertip's skin, a triangle mesh from its geometry (a mesh
  fingertip's own triangles; a mounted fingertip where its mount puts it);
* ``tip/contact``: the contact point; ``tip/normal``: the outward normal there (arrow,
  1 cm); ``tip/force``: the force the object exerts, drawn *ending* at the contact point
  (``force_scale`` m per N); ``tip/edge``: the edge direction as a line on the skin
  through the contact point (``line`` contacts only); ``tip/h_trace``: the trace of the
  tangential spin torque ``h`` over the last ``trace_samples`` logged samples, drawn from
  the contact point (``h_scale`` m per N·m): a line for a strip, a blob for an area
  contact; all cleared when there is no contact;
* ``series/...``: time series of force, moment, ``|h|`` with its significance level, the
  edge angle (degrees) and the state code (0 none, 1 point, 2 line, 3 area).

Live, :class:`LiveRerun` draws in a process of its own, so that Rerun's work (about 2 ms of
CPU per drawn sample) never runs on the estimator's thread nor holds its interpreter (a
thread would: Python runs one thread at a time), and at the lowest priority (Linux's idle
scheduling class, the viewer it spawns too), so that it takes no core the estimator wants.
``rerun FILE.rrd`` opens a saved recording.
"""

from __future__ import annotations

import math
import os
import pickle
import queue
import subprocess
import sys
import tempfile
import threading
from collections import deque
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Fingertip
from softtip.errors import InputError
from softtip.estimator import STATES, Estimates, SampleEstimate

__all__ = ["LiveRerun", "RerunLogger", "RerunView", "check_viewer", "import_rerun", "surface_mesh"]

#: The time series of the view, by entity path: ``fx … mz`` (N, N·m), ``|h|`` (N·m), the angle (°)
#: and the state's index in :data:`~softtip.estimator.STATES`.
SERIES = (
    "series/force/fx", "series/force/fy", "series/force/fz", "series/moment/mx", "series/moment/my",
    "series/moment/mz", "series/h_norm", "series/angle_deg", "series/state",
)  # fmt: skip
#: s of ``t`` over which :meth:`RerunLogger.log_sample` keeps the series' samples before it sends
#: them, as columns (one call per series, where a call per sample and series cost Rerun's Python
#: SDK about 50 us each, in the process that shares the cores with the estimator): 10 samples of
#: the live view's 50 a second; the plots lag the 3-D view by at most this much.
SERIES_BATCH_S = 0.2


def import_rerun():
    """Import ``rerun`` or raise an :class:`ImportError` that names the extra to install."""
    try:
        import rerun
    except ImportError as exc:
        raise ImportError(
            "the 3-D view needs the 'rerun-sdk' package: pip install 'rerun-sdk>=0.23' "
            "(or, from a softtip checkout, pip install -e '.[viz]')"
        ) from exc
    return rerun


def surface_mesh(
    tip: Fingertip, n_around: int = 48, n_along: int = 32
) -> tuple[NDArray, NDArray, NDArray]:
    """A triangle mesh of the skin, in the sensor frame: the shape's own
    (:meth:`~softtip.core.shape.Fingertip.surface_mesh`).

    A mesh fingertip gives its own triangles; a capsule, sphere or ellipsoid is tessellated;
    a mounted fingertip (:class:`~softtip.core.mounting.Mounted`) is its shape's mesh placed by
    the mount; any other shape, a sphere grid projected onto its skin.

    Parameters
    ----------
    tip : Fingertip
    n_around, n_along : int
        Vertices around the shape's z axis and along the profile (tessellated shapes).

    Returns
    -------
    vertices : (V, 3) m
    triangles : (T, 3) int32 vertex indices
    normals : (V, 3) outward unit normals
    """
    return tip.surface_mesh(n_around, n_along)


def _edge_line(tip: Fingertip, r, d, half_length: float) -> NDArray:
    """Points of the edge direction drawn on the skin: ``r + s d`` projected, ``|s| ≤ half_length``."""
    s = np.linspace(-half_length, half_length, 21)[:, None]
    return tip.project(np.asarray(r) + s * np.asarray(d))


def check_viewer() -> None:
    """Raise :class:`~softtip.errors.InputError` at once when no Rerun viewer can be shown here.

    On Linux a viewer needs a display: ``DISPLAY`` (X11) or ``WAYLAND_DISPLAY``. Without one
    the viewer process fails only after many seconds; saving a recording works anywhere.
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise InputError(
            "--rerun: no display to open the Rerun viewer on (DISPLAY and WAYLAND_DISPLAY are unset, e.g. over ssh); "
            "save the view instead with --rerun-save FILE.rrd (in Python: RerunLogger(tip, save='FILE.rrd')) and open "
            "it with `rerun FILE.rrd` on a machine with a display"
        )


@dataclass(frozen=True)
class RerunView:
    """How the view looks and how often it is drawn: the settings of :class:`RerunLogger` and
    :class:`LiveRerun` besides where it goes.

    Parameters
    ----------
    force_scale : float
        Length of the force arrow, m per N.
    max_rate_hz : float
        Live: at most this many samples per second of ``t`` are logged in 3-D (the rest is
        skipped, the consumer loop must not slow down).
    application_id : str
        Rerun's application id of the recording.
    h_scale : float
        Length of the ``h`` trace, m per N·m.
    trace_samples : int
        Logged samples the ``h`` trace holds.
    """

    force_scale: float = 0.005
    max_rate_hz: float = 50.0
    application_id: str = "softtip"
    h_scale: float = 1.0
    trace_samples: int = 100


class RerunLogger:
    """Logs a fingertip and its estimates to Rerun.

    Parameters
    ----------
    tip : Fingertip
    save : str or path-like, optional
        Write a ``.rrd`` file.
    spawn : bool
        Open (or connect to) a Rerun viewer.
    view : RerunView, optional
        The look and the drawing rate (default :class:`RerunView`'s).
    """

    def __init__(
        self,
        tip: Fingertip,
        save: str | os.PathLike[str] | None = None,
        spawn: bool = False,
        view: RerunView = RerunView(),
    ) -> None:
        rr = import_rerun()
        self.rr, self.tip = rr, tip
        self.h_scale = view.h_scale
        self._trace: deque[NDArray[np.float64]] = deque(maxlen=view.trace_samples)
        self.force_scale, self.min_dt = view.force_scale, 1.0 / view.max_rate_hz
        self.rec = rr.RecordingStream(view.application_id)
        sinks = [rr.FileSink(os.fspath(save))] if save is not None else []
        if spawn:
            check_viewer()
            try:
                self.rec.spawn(connect=False)  # starts a viewer (or finds a running one)
            except Exception as exc:  # noqa: BLE001 - whatever rerun raises, the user gets one message
                raise InputError(
                    f"--rerun: could not start the Rerun viewer ({exc}); save the view instead with "
                    "--rerun-save FILE.rrd and open it with `rerun FILE.rrd`"
                ) from None
            sinks.append(rr.GrpcSink())
        if sinks:
            self.rec.set_sinks(*sinks)
        _, radius = tip.bounding_sphere
        self.edge_half = 0.5 * radius
        v, tri, n = surface_mesh(tip)
        self.rec.log("tip", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self.rec.log(
            "tip/skin",
            rr.Mesh3D(
                vertex_positions=v,
                triangle_indices=tri,
                vertex_normals=n,
                albedo_factor=[200, 200, 210, 110],
            ),
            static=True,
        )
        self._last_t = -math.inf
        self._series_t: list[float] = []  # the series' samples not sent yet (SERIES_BATCH_S)
        self._series_v: list[tuple[float, ...]] = []

    # -- per sample (live) --------------------------------------------------------------------

    def log_sample(self, e: SampleEstimate) -> None:
        """Log one estimate, unless one was logged less than ``1 / max_rate_hz`` s before."""
        if e.t - self._last_t < self.min_dt:
            return
        self._last_t = e.t
        self.rec.set_time("t", duration=e.t)
        self._log_geometry(e.state, e.point, e.normal, e.wrench[:3], e.direction, e.h)
        self._series_t.append(e.t)
        self._series_v.append((*e.wrench, e.h_norm, math.degrees(e.angle), STATES.index(e.state)))
        if e.t - self._series_t[0] >= SERIES_BATCH_S - 1e-9:
            self._send_kept_series()

    def _send_kept_series(self) -> None:
        """Send the series' samples :meth:`log_sample` kept."""
        if self._series_t:
            self._send_series(np.array(self._series_t), np.array(self._series_v, dtype=float))
            self._series_t, self._series_v = [], []

    def _send_series(self, t: NDArray[np.float64], values: NDArray[np.float64]) -> None:
        """Send the :data:`SERIES` of samples at ``t`` (s), ``values`` (N, 9) in their order, as columns."""
        rr, rec = self.rr, self.rec
        times = [rr.TimeColumn("t", duration=t)]
        for k, path in enumerate(SERIES):
            rec.send_columns(path, indexes=times, columns=rr.Scalars.columns(scalars=values[:, k]))

    def _log_geometry(self, state: str, r, n, f, d, h=None) -> None:
        rr, rec = self.rr, self.rec
        if state == "none" or any(math.isnan(x) for x in r):
            for path in ("tip/contact", "tip/normal", "tip/force", "tip/edge", "tip/h_trace"):
                rec.log(path, rr.Clear(recursive=False))
            self._trace.clear()
            return
        if h is not None and not any(math.isnan(x) for x in h):
            self._trace.append(np.asarray(r) + self.h_scale * np.asarray(h))
            if len(self._trace) > 1:
                rec.log("tip/h_trace", rr.LineStrips3D([np.array(self._trace)], radii=0.0002, colors=[[200, 80, 220]]))
        r, n, f = np.asarray(r), np.asarray(n), np.asarray(f)
        vf = f * self.force_scale
        rec.log("tip/contact", rr.Points3D([r], radii=0.0008, colors=[[255, 200, 0]]))
        rec.log(
            "tip/normal",
            rr.Arrows3D(origins=[r], vectors=[0.01 * n], colors=[[80, 160, 255]]),
        )
        rec.log(
            "tip/force",
            rr.Arrows3D(origins=[r - vf], vectors=[vf], colors=[[255, 60, 60]]),
        )
        if state == "line":
            rec.log(
                "tip/edge",
                rr.LineStrips3D(
                    [_edge_line(self.tip, r, d, self.edge_half)],
                    radii=0.0004,
                    colors=[[40, 220, 90]],
                ),
            )
        else:
            rec.log("tip/edge", rr.Clear(recursive=False))

    # -- whole log (offline) ----------------------------------------------------------------

    def log_estimates(self, est: Estimates, max_frames: int = 5000) -> None:
        """Log a whole :class:`~softtip.estimator.Estimates`.

        Time series go in as columns (every sample); the 3-D view gets at most
        ``max_frames`` evenly spaced samples.
        """
        rec = self.rec
        values = np.column_stack((est.wrench, est.h_norm, np.degrees(est.angle), est.state)).astype(float)
        self._send_series(np.asarray(est.t, dtype=float), values)
        names = est.state_names
        step = max(1, math.ceil(len(est) / max_frames))
        for k in range(0, len(est), step):
            rec.set_time("t", duration=float(est.t[k]))
            self._log_geometry(
                str(names[k]),
                est.point[k],
                est.normal[k],
                est.wrench[k, :3],
                est.direction[k],
                est.h[k],
            )

    def close(self) -> None:
        """Send the series' last samples, flush and close the recording (the ``.rrd`` file is
        complete afterwards)."""
        try:
            self._send_kept_series()
            self.rec.flush()
        except RuntimeError as exc:  # the spawned viewer died (no display, no GPU, closed early)
            raise InputError(
                f"--rerun: the Rerun viewer could not be reached ({exc}); save the view instead with "
                "--rerun-save FILE.rrd and open it with `rerun FILE.rrd`"
            ) from None
        self.rec.disconnect()


class LiveRerun:
    """The Rerun view of a live session (``softtip stream --rerun``, ``--rerun-save``), drawn by a
    :class:`RerunLogger` in a process of its own.

    :meth:`log_sample` is called by the consumer loop with every estimate: it keeps at most
    ``max_rate_hz`` samples per second of ``t`` (the rest is skipped, as :meth:`RerunLogger.log_sample`
    does) and queues them; a thread of this process sends them to the drawing process. The loop
    never waits for Rerun, and Rerun's Python work does not share the estimator's interpreter.
    If the drawing process falls behind, the oldest queued samples are skipped.

    Parameters
    ----------
    tip : Fingertip
    save, spawn, view
        As in :class:`RerunLogger`.
    wait : bool
        Wait here until the drawing process has started (imported Rerun, logged the skin,
        opened the viewer or the file: a second or more), raising its error. Otherwise it
        starts while the session runs (samples queue meanwhile), and an error that stopped it
        is raised by the next :meth:`log_sample` or by :meth:`close`.
    start_timeout : float
        s to wait for the drawing process to start.

    Raises
    ------
    ImportError
        ``rerun-sdk`` is not installed.
    InputError
        The viewer or the file could not be opened (also raised by :meth:`log_sample` and
        :meth:`close` when drawing fails later).
    """

    def __init__(
        self,
        tip: Fingertip,
        save: str | os.PathLike[str] | None = None,
        spawn: bool = False,
        view: RerunView = RerunView(),
        *,
        wait: bool = True,
        start_timeout: float = 120.0,
    ) -> None:
        import_rerun()  # here, so that a missing package says so at once
        max_rate_hz = view.max_rate_hz
        self.min_dt = 1.0 / max_rate_hz
        self.start_timeout = start_timeout
        self._last_t = -math.inf
        self._pending: deque[SampleEstimate] = deque(maxlen=max(1, int(60 * max_rate_hz)))  # 60 s of drawing
        self._wake = threading.Event()
        self._stop = self._closed = self._failed = False
        self._error: BaseException | None = None
        self._log = tempfile.TemporaryFile()  # the drawing process's stderr, for messages
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "softtip.viz.rerun"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._log,
        )  # fmt: skip
        self._answers: queue.SimpleQueue = queue.SimpleQueue()
        self._reader = threading.Thread(target=self._read_answers, daemon=True, name="softtip-rerun-answers")
        self._reader.start()
        # the drawing process draws every sample it gets: the rate is kept here
        setup = (tip, None if save is None else os.fspath(save), spawn, replace(view, max_rate_hz=math.inf))
        try:
            pickle.dump(setup, self._proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.flush()
        except OSError:
            pass  # the process ended at once: its answer says why
        self._started = False
        if wait:
            self._answer(start_timeout)
            self._started = True
        self._thread = threading.Thread(target=self._send, daemon=True, name="softtip-rerun-send")
        self._thread.start()

    def _read_answers(self) -> None:
        """The drawing process's answers (``ok`` when started and when closed, else an error), as
        they come; ``None`` when it ended."""
        while True:
            try:
                answer = pickle.load(self._proc.stdout)
            except Exception:  # noqa: BLE001 - EOF or garbage: the process ended, its stderr says why
                answer = None
            if answer != "ok" and not self._closed:
                self._failed = True
            self._answers.put(answer)
            if answer is None:
                return

    def _answer(self, timeout: float) -> None:
        """Take the drawing process's next answer; raise its error (or its end's)."""
        try:
            answer = self._answers.get(timeout=timeout)
        except queue.Empty:
            answer = "timeout"
        if answer == "ok":
            return
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()
        self._log.seek(0)
        tail = self._log.read().decode(errors="replace").strip().splitlines()[-3:]
        self._end()
        if isinstance(answer, tuple) and answer[0] == "import":
            raise ImportError(answer[1])
        if isinstance(answer, tuple):
            raise InputError(answer[1])
        why = " / ".join(tail) if tail else ("no answer" if answer == "timeout" else f"exit code {self._proc.returncode}")
        raise InputError(f"--rerun: the process drawing the Rerun view failed ({why})")

    def _end(self) -> None:
        """Close the pipes and the message file of an ended drawing process."""
        self._closed = True
        for f in (self._proc.stdin, self._proc.stdout, self._log):
            try:
                f.close()
            except OSError:  # a broken pipe's buffered bytes: the process has ended anyway
                pass

    def log_sample(self, e: SampleEstimate) -> None:
        """Queue one estimate for drawing, unless one was queued less than ``1 / max_rate_hz`` s
        (of ``t``) before. Never waits.

        Raises
        ------
        InputError
            The drawing process failed (its message); the view is closed.
        """
        if e.t - self._last_t < self.min_dt:
            return
        if self._failed or self._error is not None:
            self.close()
        self._last_t = e.t
        self._pending.append(e)
        self._wake.set()

    def _send(self) -> None:
        pending, wake, pipe = self._pending, self._wake, self._proc.stdin
        dump = pickle.dumps
        try:
            while True:
                wake.clear()  # before looking: a sample queued from here on wakes the wait below
                while pending:
                    pipe.write(dump(pending.popleft(), protocol=pickle.HIGHEST_PROTOCOL))
                pipe.flush()  # waits while the drawing process starts or lags: samples queue meanwhile
                if not pending:
                    if self._stop:
                        return
                    wake.wait()
        except (OSError, ValueError) as exc:  # the drawing process ended
            self._error = exc

    def close(self) -> None:
        """Draw what is queued, then flush and close the recording (the ``.rrd`` file is complete
        afterwards) and end the drawing process (idempotent).

        Raises
        ------
        InputError
            Drawing failed (the viewer could not be reached, the file could not be written).
        """
        if self._closed:
            return
        self._stop = True
        self._wake.set()
        self._thread.join()
        try:
            pickle.dump(None, self._proc.stdin)
            self._proc.stdin.close()
        except OSError:
            pass
        if not self._started:
            self._answer(self.start_timeout)
            self._started = True
        self._closed = True  # from here, the answers are the end's
        self._answer(600.0)
        self._proc.wait()
        self._end()


def _draw(stdin, stdout) -> None:
    """The drawing process of :class:`LiveRerun`: a setup ``(tip, save, spawn, view)`` then estimates,
    pickled on ``stdin``, until ``None``; answers ``ok`` (started, then closed) or ``(kind, message)``."""

    def answer(value) -> None:
        pickle.dump(value, stdout)
        stdout.flush()

    tip, save, spawn, view = pickle.load(stdin)
    try:
        logger = RerunLogger(tip, save, spawn, view)
    except ImportError as exc:
        answer(("import", str(exc)))
        return
    except InputError as exc:
        answer(("input", str(exc)))
        return
    except Exception as exc:  # noqa: BLE001 - whatever rerun raises, the user gets one message
        answer(("input", f"--rerun: could not open the Rerun view ({exc})"))
        return
    answer("ok")
    try:
        while (e := pickle.load(stdin)) is not None:
            logger.log_sample(e)
        logger.close()
    except EOFError:  # the session ended without closing the view: keep what was drawn
        logger.close()
        return
    except InputError as exc:
        answer(("input", str(exc)))
        return
    except Exception as exc:  # noqa: BLE001
        answer(("input", f"--rerun: drawing the Rerun view failed ({exc})"))
        return
    answer("ok")


def _behind_the_estimator() -> None:
    """Give this process's CPU time to the estimator's first: the live view must never slow it,
    and on a machine with few cores its drawing (and the viewer it may spawn, which inherits
    this) would take a core from the estimator's threads. Linux's idle scheduling class (this
    thread's; the threads Rerun starts after it inherit it), elsewhere the lowest priority."""
    try:
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    except (AttributeError, OSError):  # not Linux, or not allowed: nice 19 is any process's right
        try:
            os.nice(19)
        except (AttributeError, OSError):
            pass


if __name__ == "__main__":
    _behind_the_estimator()
    # the answers go on the original standard output; anything printed goes to standard error
    _answers = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    _draw(sys.stdin.buffer, _answers)
