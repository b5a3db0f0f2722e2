"""Worker processes for the reproduction's conditions (``softtip reproduce --jobs``): started
from a server that has loaded softtip's compiled kernels, ended at once on an error, an
interrupt or a caller that stops early."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["end_pool", "start_pool", "warm_kernels"]


def start_pool(jobs: int, initializer, initargs: tuple = ()) -> ProcessPoolExecutor:
    """``jobs`` worker processes, started at once, forked from a server that has imported softtip
    and loaded its compiled kernels (``softtip.apps._worker_preload``), not from this process
    (which may hold threads, gigabytes, and signal handlers that raise).

    ``initializer`` runs first in each worker; it should call
    :func:`_end_with_parent`, so that a worker started while a signal
    stops this process (before the pool knows the worker) ends with it. A signal while the
    workers start ends those already started (:func:`end_pool`) and is raised again.
    """
    import multiprocessing

    _socket_folder()
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["softtip.apps._worker_preload"])
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=initializer, initargs=initargs)
    try:
        pool.submit(int)  # starts the workers now (a pool starts them on its first task)
    except BaseException:  # a signal while they start: none is left behind
        end_pool(pool)
        raise
    return pool


#: the longest Unix socket path (``sun_path`` holds 108 bytes on Linux, 104 on macOS, with its NUL)
_SOCKET_PATH_MAX = 103
#: what multiprocessing adds to its folder's path for the forkserver's socket
#: (``/pymp-XXXXXXXX/listener-XXXXXXXX``)
_SOCKET_SUFFIX = len("/pymp-XXXXXXXX/listener-XXXXXXXX")


def _socket_folder() -> None:
    """Make multiprocessing's private folder (``pymp-*``, which holds the forkserver's Unix
    socket) now, with the termination signals held until multiprocessing has noted it: a signal
    between the folder's creation and that note (``multiprocessing.util.get_temp_dir``) would
    leave it behind, known neither to multiprocessing's exit handler nor to
    :func:`softtip.io.interrupt.exit_now`, which remove it. Held, the signal is handled right
    after, and the folder goes with the run.

    The folder is made in a folder with a short path when the temporary folder's is too long for
    a socket address: a long ``TMPDIR`` would otherwise stop every pool with ``AF_UNIX path too
    long`` (mode 0700, multiprocessing's own)."""
    from multiprocessing import process, util

    if process.current_process()._config.get("tempdir") is not None:
        return  # made already: its path was checked then
    base = tempfile.gettempdir()
    if len(os.fsencode(base)) + _SOCKET_SUFFIX > _SOCKET_PATH_MAX:
        shorts = ("/tmp", "/var/tmp", "/dev/shm", os.path.expanduser("~"))
        fits = (d for d in shorts if len(os.fsencode(d)) + _SOCKET_SUFFIX <= _SOCKET_PATH_MAX)
        base = next((d for d in fits if os.path.isdir(d) and os.access(d, os.W_OK | os.X_OK)), None)
        if base is None:
            return  # no short folder is writable: multiprocessing's own message names the limit
    held = {getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    saved, tempfile.tempdir = tempfile.tempdir, base
    try:
        util.get_temp_dir()  # made in ``base`` and remembered for this process
    finally:
        tempfile.tempdir = saved
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


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


def warm_kernels() -> None:
    """Load the compiled kernels the pipeline uses (numba's cache; compiled there the first time)
    by running the estimator on the example grasp, latched, line-fit and low-pass filtered, with them
    forced on."""
    import warnings

    from softtip.core._jit import jit_enabled, set_jit
    from softtip.estimator import EstimatorConfig, estimate
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
