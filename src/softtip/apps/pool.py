"""Ending a process pool at once: the applications' worker pools (the reproduction's
conditions, the pieces of ``softtip estimate --jobs``) on an error, an interrupt or a caller
that stops early."""

from __future__ import annotations

import contextlib
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["end_pool"]


def end_pool(pool: ProcessPoolExecutor, timeout: float = 5.0) -> None:
    """Cancel what is queued and end the workers (terminate, then kill after ``timeout`` s).

    ``ProcessPoolExecutor.shutdown`` alone waits for running tasks; an interrupted run must not.
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        with contextlib.suppress(Exception):
            p.terminate()
    deadline = time.monotonic() + timeout
    for p in processes:
        with contextlib.suppress(Exception):
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join(1.0)
