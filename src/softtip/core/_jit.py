"""Compiled step functions (numba), imported and compiled only when first needed.

Each stateful stage of the estimator is one step function over an explicit state record
(:func:`lazy_jit`), run per sample by the stream and in one loop over the log by the batch.
With numba (a dependency of softtip) both run it compiled, ``cache=True`` on disk: importing
numba costs about 0.3 s of CPU once per process and loading the cached steps about 0.4 s (the
first run after installing compiles them, about 11 s of CPU). Without numba, or with ``SOFTTIP_NUMBA=0``
in the environment, the same source runs as Python (tested equal, about 90 times slower);
``SOFTTIP_NUMBA=1`` insists on numba. :func:`jit_enabled` (from :data:`JIT_MIN_SAMPLES` samples)
still decides for the CSV formatter of :mod:`softtip.io._csvtext`, whose fallback
is pyarrow's writer (the same bytes).

A compiled function may call another :func:`lazy_jit` function and the plain kernels marked
:func:`jitable` (registered with numba when the first compiled function is built; Python calls
them as they are). numba's disk cache only watches the file of the function it caches, not those
of the functions compiled into it, so the cache of every function here is stamped with the
sources of ``softtip.core`` and ``softtip.estimator`` too.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["JIT_MIN_SAMPLES", "STEP_MIN_SAMPLES", "jit_enabled", "jitable", "lazy_jit", "set_jit", "use_numba"]

#: Logs of at least this many samples use the compiled kernels (when allowed).
JIT_MIN_SAMPLES = 100_000

_state: dict[str, Any] = {"enabled": None}


def _numba_importable() -> bool:
    if "importable" not in _state:
        try:
            import numba  # noqa: F401
        except ImportError:  # a dependency, but an environment may lack it: the steps then run as Python
            _state["importable"] = False
        else:
            _state["importable"] = True
    return _state["importable"]


def _from_environment() -> bool | None:
    value = os.environ.get("SOFTTIP_NUMBA", "").strip()
    if value == "0":
        return False
    if value == "1":
        return _numba_importable()
    return None


def jit_enabled(n: int) -> bool:
    """Whether a batch stage over ``n`` samples uses the compiled kernels: always or never
    when :func:`set_jit` or ``SOFTTIP_NUMBA`` says so, else from :data:`JIT_MIN_SAMPLES`
    samples on (when numba is installed)."""
    forced = _state["enabled"]
    if forced is None:
        forced = _from_environment()
    if forced is not None:
        return bool(forced)
    return n >= JIT_MIN_SAMPLES and _numba_importable()


def set_jit(enabled: bool | None) -> bool | None:
    """Use the compiled kernels always (``True``), never (``False``), or by the log's length
    and the environment (``None``, the default); returns the previous setting. For tests
    and benchmarks."""
    old = _state["enabled"]
    _state["enabled"] = None if enabled is None else bool(enabled) and _numba_importable()
    return old


#: A batch loop over fewer samples runs its steps as Python unless numba is loaded already:
#: below this, importing numba and loading the cached steps (about 0.7 s of CPU) costs more than
#: running them as Python (about 30 µs a sample for every stage together).
STEP_MIN_SAMPLES = 20_000


def use_numba(n: int | None = None) -> bool:
    """Whether the step functions (:func:`lazy_jit`) run compiled: as :func:`set_jit` or
    ``SOFTTIP_NUMBA`` say when they do; else, when numba is installed, always for a stream of
    unknown length (``n`` None) and for a batch loop or a stream of ``n`` samples from
    :data:`STEP_MIN_SAMPLES` on, or at any length once numba is loaded in this process (the
    same bits either way)."""
    forced = _state["enabled"]
    if forced is None:
        forced = _from_environment()
    if forced is not None:
        return bool(forced)
    if n is not None and n < STEP_MIN_SAMPLES and "numba" not in sys.modules:
        return False
    return _numba_importable()


#: Plain functions compiled code may call (:func:`jitable`), and those registered with numba so far.
_JITABLE: list[Callable] = []
_REGISTERED: set[int] = set()
#: Folders whose sources a compiled function may include (its cache is stamped with them).
_SOURCES = ("core", "estimator")


def jitable(func: Callable) -> Callable:
    """Decorator: let compiled code call ``func``, a plain function (a kernel written for the
    ``xp`` back ends, a helper of a step); ``func`` itself is returned unchanged. It is
    registered with ``numba.extending.register_jitable`` when a compiled function is first built."""
    _JITABLE.append(func)
    return func


def _register_jitables() -> None:
    from numba.extending import register_jitable

    for func in _JITABLE:
        if id(func) not in _REGISTERED:
            register_jitable(func)
            _REGISTERED.add(id(func))


def _sources_stamp() -> tuple:
    root = Path(__file__).resolve().parents[1]
    stamp = []
    for folder in _SOURCES:
        for path in sorted((root / folder).glob("*.py")):
            st = path.stat()
            stamp.append((path.name, st.st_mtime, st.st_size))
    return tuple(stamp)


class _Lazy:
    """A function compiled by ``numba.njit(cache=True, nogil=...)`` on its first compiled call."""

    def __init__(self, func: Callable, nogil: bool = True):
        self.py_func = func
        self.nogil = nogil
        self._compiled: Callable | None = None
        self._python: Callable | None = None
        self.__doc__ = func.__doc__
        self.__name__ = func.__name__

    def compiled(self) -> Callable:
        """The numba dispatcher (built on first use; loaded from numba's disk cache when fresh)."""
        if self._compiled is None:
            import numba

            _register_jitables()
            compiled = numba.njit(cache=True, nogil=self.nogil)(self.py_func)
            cache_file = getattr(getattr(compiled, "_cache", None), "_cache_file", None)
            if cache_file is not None:  # stale when a function compiled into it or the flag changed (module docs)
                cache_file._source_stamp = (cache_file._source_stamp, _sources_stamp(), self.nogil)
            self._compiled = compiled
        return self._compiled

    def function(self, n: int | None = None) -> Callable:
        """What a call runs: :meth:`compiled` when numba is used (:func:`use_numba`: ``n`` the
        samples of a batch loop or of a stream when known, else None), else :attr:`python`. A caller that calls
        it per sample keeps this instead."""
        return self.compiled() if use_numba(n) else self.python

    @property
    def _numba_type_(self):
        # how a compiled caller sees this function: as its numba dispatcher
        from numba.core import types

        return types.Dispatcher(self.compiled())

    @property
    def python(self) -> Callable:
        """:attr:`py_func` calling the Python forms of the lazy functions it calls: the same
        source run as Python throughout, with numba installed or not (tests compare the two)."""
        if self._python is None:
            import types

            f = self.py_func
            names = {k: v.python for k, v in f.__globals__.items() if isinstance(v, _Lazy) and k in f.__code__.co_names}
            self._python = f if not names else types.FunctionType(
                f.__code__, {**f.__globals__, **names}, f.__name__, f.__defaults__, f.__closure__
            )  # fmt: skip
        return self._python

    def __call__(self, *args):
        return self.function()(*args)


def lazy_jit(func: Callable | None = None, *, nogil: bool = True) -> Any:
    """Decorator: compile ``func`` with numba (cached on disk) the first time it is called.

    ``nogil`` (numba's option): a call from Python releases the interpreter while it runs, as
    the batch's loops over a log do, so that pieces of a log run on several threads. A step
    the stream calls once per sample from Python is declared ``nogil=False``: a release is
    cheap, but taking the interpreter back waits while another thread (a live run's receive
    thread, its recorder) holds it, in the middle of an update (the performance page's live
    soak). Compiled callers call a step directly, whatever its flag.
    """
    if func is None:
        return lambda f: _Lazy(f, nogil)
    return _Lazy(func, nogil)
