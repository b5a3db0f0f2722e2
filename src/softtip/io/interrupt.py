"""SIGTERM and SIGHUP handled like Ctrl-C: unwind, remove temporary files, exit 128 + signal.

A batch command (``estimate``, ``simulate``, ``calibrate``) killed by ``kill``, by a job
scheduler's time limit or by closing its terminal must clean up as Ctrl-C does: the
exception unwinds through every ``with``/``finally`` (:class:`softtip.io.atomic.AtomicFile`
removes its temporary file) and the command exits with the shell's code for the signal:
130 for SIGINT (Ctrl-C), 143 for SIGTERM, 129 for SIGHUP.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

__all__ = ["Interrupted", "exit_code", "terminate_like_ctrl_c"]

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


def _raise(signum, frame) -> None:
    raise Interrupted(signum)


@contextlib.contextmanager
def terminate_like_ctrl_c() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise :class:`Interrupted`; handlers restored after.

    Signals left ignored by the parent (``nohup`` ignores SIGHUP) stay ignored. Does nothing
    outside the main thread, where Python cannot set signal handlers.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for sig in _SIGNALS:
        current = signal.getsignal(sig)
        if current is signal.SIG_IGN:
            continue
        previous[sig] = current
        signal.signal(sig, _raise)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
