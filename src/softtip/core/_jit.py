"""Compiled sequential kernels (numba), imported and compiled only when first needed.

Some batch stages are sequential by nature: running sums restarted at segment starts, a
sliding window over the samples of a segment, a test that depends on the previous
decision. numpy can only do them segment by segment (a Python loop per segment, thousands
per log); a compiled loop does them in one pass. Each kernel here is plain Python over
arrays (the same additions in the same order as the streaming classes), compiled by
numba with ``cache=True`` the first time it runs; every caller keeps a pure-numpy path
(segment by segment), tested equal, or runs the same source as Python (``.python``).

A stage written as one step function (a scalar step over a state record, called per sample
by the stream) and a loop over a log that calls it: both lazy; compiled, the loop calls the
step's compiled code (numba inlines it), and ``loop.python`` is the whole source as Python,
the step's Python form included.

Importing numba and loading the cached kernels costs about 0.4 s of CPU once per process
(a first compile ~0.4 s more), so logs shorter than :data:`JIT_MIN_SAMPLES` take the numpy
paths, which are faster than that for them. ``SOFTTIP_NUMBA=0`` in the environment (or no
numba installed) selects the numpy paths always, ``SOFTTIP_NUMBA=1`` the compiled ones always.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from typing import Any

__all__ = ["JIT_MIN_SAMPLES", "jit_enabled", "lazy_jit", "set_jit", "use_compiled"]

#: Logs of at least this many samples use the compiled kernels (when allowed).
JIT_MIN_SAMPLES = 100_000

_state: dict[str, Any] = {"enabled": None}


def _numba_importable() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:  # numba is the optional extra softtip[fast]
        return False
    return True


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


def use_compiled(n: int) -> bool:
    """Whether a loop over ``n`` samples runs compiled: when :func:`jit_enabled` says so, and for
    any length once numba is loaded in this process (by a stream or another stage) and allowed,
    since then only the loop's cached code is loaded (a few ms)."""
    return jit_enabled(n) or ("numba" in sys.modules and jit_enabled(JIT_MIN_SAMPLES))


def set_jit(enabled: bool | None) -> bool | None:
    """Use the compiled kernels always (``True``), never (``False``), or by the log's length
    and the environment (``None``, the default); returns the previous setting. For tests
    and benchmarks."""
    old = _state["enabled"]
    _state["enabled"] = None if enabled is None else bool(enabled) and _numba_importable()
    return old


class _Lazy:
    """A function compiled by ``numba.njit(cache=True)`` on its first call.

    A lazy function may call another one (a stage's loop calls its step): compiled, numba
    sees the callee as its dispatcher (:func:`_register_typeof`); :attr:`python` is the
    same source run as Python throughout, the callees' Python forms included.
    """

    def __init__(self, func: Callable):
        self.py_func = func
        self._compiled: Callable | None = None
        self._python: Callable | None = None
        self.__doc__ = func.__doc__
        self.__name__ = func.__name__

    @property
    def dispatcher(self) -> Callable:
        """The numba dispatcher (compiles, or loads from the disk cache, on its first call)."""
        if self._compiled is None:
            import numba

            _register_typeof()
            self._compiled = numba.njit(cache=True, nogil=True)(self.py_func)
        return self._compiled

    @property
    def python(self) -> Callable:
        """``py_func`` calling the Python forms of the lazy functions it calls (no numba)."""
        if self._python is None:
            import types

            f = self.py_func
            names = {k: v.python for k, v in f.__globals__.items() if isinstance(v, _Lazy) and k in f.__code__.co_names}
            if not names:
                self._python = f
            else:
                self._python = types.FunctionType(
                    f.__code__, {**f.__globals__, **names}, f.__name__, f.__defaults__, f.__closure__
                )
        return self._python

    def __call__(self, *args):
        return self.dispatcher(*args)


def _register_typeof() -> None:
    """Let numba type a :class:`_Lazy` global as its dispatcher (once per process)."""
    if _state.get("typeof"):
        return
    from numba.extending import typeof_impl

    @typeof_impl.register(_Lazy)
    def _typeof_lazy(val, c):
        return typeof_impl(val.dispatcher, c)

    _state["typeof"] = True


def lazy_jit(func: Callable) -> _Lazy:
    """Decorator: compile ``func`` with numba (cached on disk) the first time it is called."""
    return _Lazy(func)
