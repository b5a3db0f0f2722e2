"""SIGTERM and SIGHUP handled like Ctrl-C: unwind, remove temporary files, exit 128 + signal.

A batch command (``estimate``, ``simulate``, ``calibrate``) killed by ``kill``, by a job
scheduler's time limit or by closing its terminal must clean up as Ctrl-C does: the
exception unwinds through every ``with``/``finally`` (:class:`softtip.io.atomic.AtomicFile`
removes its temporary file) and the command exits with the shell's code for the signal:
130 for SIGINT (Ctrl-C), 143 for SIGTERM, 129 for SIGHUP.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator

__all__ = ["Interrupted", "check_interrupted", "exit_code", "exit_now", "ignore_signals_after_commit_until_exit",
           "interrupted_signal", "outputs_committed",
           "terminate_like_ctrl_c"]

_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


class Interrupted(KeyboardInterrupt):
    """A termination signal, raised in the main thread like ``KeyboardInterrupt``."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name


def exit_code(exc: BaseException) -> int:
    """128 + the signal number: 130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP."""
    return 128 + (exc.signum if isinstance(exc, Interrupted) else int(signal.SIGINT))


class _Flag:
    """Set once, never cleared, with no lock: the signal handlers set it, and Python may run a
    second signal's handler inside the first one's, at any line (a ``threading.Event`` there
    deadlocked on its own lock: two signals 5 ms apart, now and then a run that never ended)."""

    def __init__(self) -> None:
        self._set = False

    def set(self) -> None:
        self._set = True

    def is_set(self) -> bool:
        return self._set


_interrupted = _Flag()
_first_signal: list[int] = []


def interrupted_signal() -> int | None:
    """The signal that interrupted this process (within :func:`terminate_like_ctrl_c`), or None."""
    return _first_signal[0] if _first_signal else None


def check_interrupted() -> None:
    """Raise the interrupt again if a signal came (code that swallowed it must not go on to commit outputs).

    Raises
    ------
    KeyboardInterrupt
        :class:`Interrupted` for SIGTERM and SIGHUP.
    """
    sig = interrupted_signal()
    if sig is None:
        return
    if sig == signal.SIGINT:
        raise KeyboardInterrupt
    raise Interrupted(sig)


def _ignore(signum, frame) -> None:
    """A further signal while the first one unwinds: nothing to do (the run is ending)."""


def _ignore_further_signals() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP from now on (also those already pending: a Python
    handler that does nothing, not SIG_IGN, which makes Python report a "race condition"):
    the cleanup of the first one (temporary files, worker processes) must not be cut short
    by a second, and the exit code stays the first one's."""
    _interrupted.set()  # no lock: a second handler may run from here on (see _Flag)
    for sig in (signal.SIGINT, *_SIGNALS):
        with contextlib.suppress(OSError, ValueError):
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, _ignore)


def exit_now(code: int) -> None:
    """End the process at once with ``code`` after a signal was handled (the cleanup is done).

    Skips the interpreter's finalisation: it restores the default signal actions (a second
    signal would then kill the process with another status) and runs exit handlers that may
    wait (multiprocessing joins its workers). Returns without exiting when no signal was
    received (an in-process ``KeyboardInterrupt``, e.g. under a test runner).
    """
    if not _interrupted.is_set():
        return
    import sys

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    _remove_multiprocessing_tempdir()
    os._exit(code)


def _remove_multiprocessing_tempdir() -> None:
    """Remove the folder multiprocessing made in the temporary folder (``pymp-*``: a process
    pool's forkserver socket), which its exit handler, skipped by ``os._exit``, would remove."""
    import sys

    mp = sys.modules.get("multiprocessing.process")
    if mp is None:
        return
    with contextlib.suppress(Exception):
        tempdir = mp.current_process()._config.get("tempdir")
        if tempdir:
            import shutil

            shutil.rmtree(tempdir, ignore_errors=True)


_after_commit = {"committed": False, "until_exit": False}


def ignore_signals_after_commit_until_exit() -> None:
    """For the console command: once a run's outputs are committed, termination signals stay
    ignored after :func:`terminate_like_ctrl_c`'s block too, until the process ends (a signal
    during the interpreter's exit would otherwise kill a finished run: exit -15, every output
    written). In-process callers (tests) do not call it: their handlers come back."""
    _after_commit["until_exit"] = True


def outputs_committed() -> None:
    """A run's outputs are in place: from now on a termination signal is ignored within
    :func:`terminate_like_ctrl_c` (also one already pending). The run is complete; unwinding
    would exit 143 with every output written, which a caller reads as a failed run."""
    if threading.current_thread() is not threading.main_thread():
        return
    _after_commit["committed"] = True
    for sig in (signal.SIGINT, *_SIGNALS):
        with contextlib.suppress(OSError, ValueError):
            if _after_commit["until_exit"] and signal.getsignal(sig) in (_raise, _raise_keyboard_interrupt, _ignore):
                # the console command: ignored by the kernel, which lasts through the interpreter's
                # exit (Python puts its own handlers back to the default action there: a SIGTERM
                # then killed a finished run, -15 with every output written)
                signal.signal(sig, signal.SIG_IGN)
            elif signal.getsignal(sig) in (_raise, _raise_keyboard_interrupt):
                signal.signal(sig, _ignore)
    if hasattr(signal, "SIGALRM") and signal.getsignal(signal.SIGALRM) is _raise_again:
        # a signal swallowed during the commit (after its last check): the run is complete all the same
        with contextlib.suppress(OSError, ValueError):
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, _ignore)


def _raise(signum, frame) -> None:
    _first_signal.append(signum)
    _ignore_further_signals()
    raise Interrupted(signum)


def _raise_keyboard_interrupt(signum, frame) -> None:
    _first_signal.append(signum)
    _ignore_further_signals()
    raise KeyboardInterrupt


@contextlib.contextmanager
def terminate_like_ctrl_c() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise :class:`Interrupted` (SIGINT ``KeyboardInterrupt``);
    handlers restored after. After the first, further signals are ignored until the block is
    left, so that two signals in quick succession still unwind cleanly once.

    Signals left ignored by the parent (``nohup`` ignores SIGHUP) stay ignored. Does nothing
    outside the main thread, where Python cannot set signal handlers.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    hook = sys.unraisablehook
    sys.unraisablehook = _deliver_again_if_swallowed
    for sig in (signal.SIGINT, *_SIGNALS):
        current = signal.getsignal(sig)
        if current is signal.SIG_IGN:
            continue
        previous[sig] = current
        signal.signal(sig, _raise_keyboard_interrupt if sig == signal.SIGINT else _raise)
    try:
        yield
    finally:
        # after a signal the others stay ignored until the process ends; so after a commit, for the
        # console command
        if not _interrupted.is_set() and not (_after_commit["committed"] and _after_commit["until_exit"]):
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            sys.unraisablehook = hook


def _deliver_again_if_swallowed(unraisable) -> None:
    """:data:`sys.unraisablehook` within :func:`terminate_like_ctrl_c`: a signal's exception
    raised where Python can only print it (a callback from native code, such as llvmlite's
    object-cache notice while numba compiles; a ``__del__``) was lost, the run going on with
    further signals ignored and a traceback on standard error. It is raised again instead, by
    an alarm a moment later (a real signal: it also ends a blocking call), from the next line of
    Python outside that callback; an alarm that lands in such a place again is set again. Code
    that checks :func:`check_interrupted` meanwhile stops too."""
    exc = unraisable.exc_value
    if _after_commit["committed"] and isinstance(exc, OSError) and "ignored due to race condition" in str(exc):
        return  # a signal that came as it was set to be ignored after the commit: ignored, as meant
    alarm = getattr(signal, "SIGALRM", None)
    if isinstance(exc, KeyboardInterrupt) and _first_signal and alarm is not None and hasattr(signal, "setitimer") \
            and threading.current_thread() is threading.main_thread():  # fmt: skip
        while True:  # no thread started, no lock taken: this may run inside any finaliser
            try:
                signal.signal(alarm, _raise_again)
                signal.setitimer(signal.ITIMER_REAL, 0.02)
                return
            except KeyboardInterrupt:  # the alarm came while this was still running: once more
                continue
            except (OSError, ValueError):
                break
    sys.__unraisablehook__(unraisable)


def _raise_again(signum, frame) -> None:
    """The alarm of :func:`_deliver_again_if_swallowed`: the first signal's exception, again
    (not once the outputs are committed: the run is complete)."""
    if not _after_commit["committed"]:
        check_interrupted()
