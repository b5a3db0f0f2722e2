"""Ending a process pool at once: the applications' worker pools (the reproduction's
conditions, the pieces of ``softtip estimate --jobs``) on an error, an interrupt or a caller
that stops early."""

from __future__ import annotations

import contextlib
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["end_pool", "start_pool"]


def start_pool(jobs: int, initializer, initargs: tuple = ()) -> ProcessPoolExecutor:
    """``jobs`` worker processes, started at once, forked from a server that has imported softtip
    and loaded its compiled kernels (``softtip.apps._worker_preload``), not from this process
    (which may hold threads, gigabytes, and signal handlers that raise).

    ``initializer`` runs first in each worker; it should call
    :func:`softtip.apps.chunked._end_with_parent`, so that a worker started while a signal
    stops this process (before the pool knows the worker) ends with it. A signal while the
    workers start ends those already started (:func:`end_pool`) and is raised again.
    """
    import multiprocessing

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["softtip.apps._worker_preload"])
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=initializer, initargs=initargs)
    try:
        pool.submit(int)  # starts the workers now (a pool starts them on its first task)
    except BaseException:  # a signal while they start: none is left behind
        end_pool(pool)
        raise
    return pool


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
