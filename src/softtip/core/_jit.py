"""Compiled sequential kernels (numba), imported and compiled only when first needed.

Some batch stages are sequential by nature: running sums restarted at segment starts, a
sliding window over the samples of a segment, a test that depends on the previous
decision. numpy can only do them segment by segment (a Python loop per segment, thousands
per log); a compiled loop does them in one pass. Each kernel here is plain Python over
arrays (the same additions in the same order as the streaming classes), compiled by
numba with ``cache=True`` the first time it runs; every caller keeps a pure-numpy path
(segment by segment), tested equal.

Importing numba and loading the cached kernels costs about 0.4 s of CPU once per process
(a first compile ~0.4 s more), so logs shorter than :data:`JIT_MIN_SAMPLES` take the numpy
paths, which are faster than that for them. ``SOFTTIP_NUMBA=0`` in the environment (or no
numba installed) selects the numpy paths always, ``SOFTTIP_NUMBA=1`` the compiled ones always.
"""

from __future__ import annotations

import os
import types
from collections.abc import Callable
from typing import Any

__all__ = ["JIT_MIN_SAMPLES", "jit_allowed", "jit_enabled", "lazy_jit", "pick", "set_jit"]

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


def jit_allowed() -> bool:
    """Whether the step functions of the stages run compiled (whatever the log's length): as
    :func:`set_jit` or ``SOFTTIP_NUMBA`` say, else when numba is installed."""
    forced = _state["enabled"]
    if forced is None:
        forced = _from_environment()
    if forced is not None:
        return bool(forced)
    return _numba_importable()


def set_jit(enabled: bool | None) -> bool | None:
    """Use the compiled kernels always (``True``), never (``False``), or by the log's length
    and the environment (``None``, the default); returns the previous setting. For tests
    and benchmarks."""
    old = _state["enabled"]
    _state["enabled"] = None if enabled is None else bool(enabled) and _numba_importable()
    return old


class _Lazy:
    """A function compiled by ``numba.njit(cache=True)`` on its first call.

    It may call other ``lazy_jit`` functions of its module's globals (a stage's loop calling
    its step): :attr:`compiled` calls their compiled forms, :attr:`python` their Python ones
    (the same source either way).
    """

    def __init__(self, func: Callable):
        self.py_func = func
        self._compiled: Callable | None = None
        self._python: Callable | None = None
        self.__doc__ = func.__doc__
        self.__name__ = func.__name__

    def _calling(self, form: Callable[[_Lazy], Callable]) -> Callable:
        """``py_func`` with the ``lazy_jit`` functions it names replaced by ``form`` of them."""
        func = self.py_func
        names = {n: form(g) for n in func.__code__.co_names if isinstance(g := func.__globals__.get(n), _Lazy)}
        if not names:
            return func
        out = types.FunctionType(func.__code__, {**func.__globals__, **names}, func.__name__, func.__defaults__,
                                 func.__closure__)  # fmt: skip
        out.__qualname__, out.__module__, out.__doc__ = func.__qualname__, func.__module__, func.__doc__
        return out

    @property
    def compiled(self) -> Callable:
        """The numba dispatcher (compiled, or loaded from numba's cache, on first use)."""
        if self._compiled is None:
            import numba

            self._compiled = numba.njit(cache=True, nogil=True)(self._calling(lambda f: f.compiled))
        return self._compiled

    @property
    def python(self) -> Callable:
        """The function as plain Python, calling the Python forms of the others."""
        if self._python is None:
            self._python = self._calling(lambda f: f.python)
        return self._python

    def __call__(self, *args):
        return self.compiled(*args)


def lazy_jit(func: Callable) -> _Lazy:
    """Decorator: compile ``func`` with numba (cached on disk) the first time it is called."""
    return _Lazy(func)


def pick(func: _Lazy) -> Callable:
    """``func`` compiled when :func:`jit_allowed`, else its Python form (``SOFTTIP_NUMBA=0``, no numba)."""
    return func.compiled if jit_allowed() else func.python
