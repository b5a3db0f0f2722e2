"""Simulated logs shared by the tests: computed once, kept on disk between runs.

Many test files simulate the same grasps (a second or more each, on every run and on every
pytest-xdist worker). :func:`simulate_grasp` and :func:`simulate_probing` here are drop-ins for
softtip's that look the result up first in a cache under pytest's cache directory
(``.pytest_cache/d/softtip-sim/<version>/``), keyed by

- the simulator's inputs: the function and every argument, pickled (the bytes, hashed);
- a version key: softtip's version, a hash of the sources of ``softtip/sim`` and ``softtip/core``
  (the simulator and the shapes it touches), and the versions of Python, numpy, scipy, numba
  and trimesh. A change to any of them gives a new version directory (the old ones are removed).

An entry is the result pickled, written to a temporary file and renamed into place, so two
workers that make the same entry at once both leave a whole file. A hit is unpickled afresh
for every call: a test that changes the arrays it got changes no other test's. The result is
bit-identical to recomputing (``test_simcache.py`` checks it).

Refused (computed directly, never cached): inputs that cannot be pickled, inputs that refer
to code outside softtip, numpy and the standard library (a class or function defined in a
test could change without changing the version key), random generators passed in (the
simulation would advance them: pass a seed), and a call that changes its inputs (checked on
every miss, an error: a hit would skip that change).

A ``softtip`` subprocess (the README's ``softtip reproduce`` and ``softtip simulate`` lines, the
CLI tests' ``simulate`` runs) shares the cache when started with :func:`subprocess_env`: a
``sitecustomize`` on its PYTHONPATH puts the cached ``simulate_grasp`` where softtip looks it
up (:data:`GRASP_CALLERS`), if the subprocess's softtip has the same version key.

The simulator's own test files (``test_sim_*.py``) do not use the cache: they check the
simulator, and simulate every time.

Without a pytest cache (``-p no:cacheprovider``) the cache lives for the run only: a temporary
directory made by the process that starts pytest-xdist's workers (they inherit its environment,
:data:`_RUN_ENV`) and removed when that process ends, so that a grasp is still simulated once per
run. With ``SOFTTIP_TEST_SIM_CACHE=0`` the functions simulate every time.
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
import pickle
import shutil
import tempfile
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import softtip
import softtip.sim
from softtip.sim.digest import simulator_digest

#: Roots of the modules whose code an input may refer to (their versions are in the key)
TRUSTED_MODULES = frozenset({"softtip", "numpy", "builtins", "copyreg", "collections", "math", "functools", "_codecs"})
_PROTOCOL = 5
#: Where a run without a pytest cache keeps its cache (set by the process that starts the workers)
_RUN_ENV = "SOFTTIP_TEST_SIM_RUN_DIR"


def version_key() -> str:
    """softtip's version and :func:`softtip.sim.simulator_digest` (the simulator's sources and the
    numeric libraries' versions), hashed."""
    digest = simulator_digest(Path(softtip.__file__).parent)
    h = hashlib.sha256(f"{softtip.__version__}\0{digest}".encode())
    return h.hexdigest()[:20]


class NotCacheable(Exception):
    """The inputs of a call cannot key a cache entry safely."""


class _KeyPickler(pickle.Pickler):
    """Pickles a call's inputs and refuses code from outside :data:`TRUSTED_MODULES`."""

    def reducer_override(self, obj):
        if isinstance(obj, (np.random.Generator, np.random.RandomState, np.random.BitGenerator)):
            raise NotCacheable("a random generator is an input (the call would advance it): pass a seed")
        if isinstance(obj, (type, types.FunctionType, types.BuiltinFunctionType, types.MethodType)):
            self._check(getattr(obj, "__module__", None), obj)
            return NotImplemented
        self._check(type(obj).__module__, type(obj))
        # a functools.cached_property filled in is a cache of the object's fields, not an input:
        # left out, so that an object keys the same before and after a call used it
        cached = _cached_properties(type(obj))
        state = getattr(obj, "__dict__", None)
        if cached and isinstance(state, dict) and not cached.isdisjoint(state):
            reduced = obj.__reduce_ex__(_PROTOCOL)
            if isinstance(reduced, tuple) and len(reduced) >= 3 and reduced[2] is state:
                return (*reduced[:2], {k: v for k, v in state.items() if k not in cached}, *reduced[3:])
        return NotImplemented

    @staticmethod
    def _check(module: str | None, what: Any) -> None:
        if module is None or module.split(".")[0] not in TRUSTED_MODULES:
            raise NotCacheable(f"an input refers to {what!r} of module {module}, outside the version key")


@functools.cache
def _cached_properties(cls: type) -> frozenset[str]:
    return frozenset(k for c in cls.__mro__ for k, v in vars(c).items() if isinstance(v, functools.cached_property))


def input_bytes(fn: Callable, args: tuple, kwargs: dict) -> bytes:
    """The call's inputs pickled (raises :class:`NotCacheable`)."""
    # the function by its name: a subprocess may have put the cached one in its place
    _KeyPickler._check(getattr(fn, "__module__", None), fn)
    name = getattr(fn, "__qualname__", "<unknown>")
    if "<" in name:
        raise NotCacheable(f"{name} has no importable name")
    buf = io.BytesIO()
    try:
        _KeyPickler(buf, protocol=_PROTOCOL).dump((fn.__module__, name, args, sorted(kwargs.items())))
    except NotCacheable:
        raise
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise NotCacheable(f"the inputs cannot be pickled: {exc}") from exc
    return buf.getvalue()


class SimCache:
    """An on-disk cache of simulator results in ``directory`` (None: no cache, compute always).

    Attributes
    ----------
    hits, misses, refused : int
        Calls served from the cache, computed and stored, computed without a key.
    """

    def __init__(self, directory: Path | None):
        self.directory = directory
        self.hits = self.misses = self.refused = 0

    @classmethod
    def in_pytest_cache(cls, config) -> SimCache:
        """The cache of this checkout's pytest cache, under the current version key."""
        if os.environ.get("SOFTTIP_TEST_SIM_CACHE", "1") == "0":
            return cls(None)
        cache = getattr(config, "cache", None)
        if cache is None:
            return cls.for_this_run(config)
        base = Path(cache.mkdir("softtip-sim"))
        version = version_key()
        for old in base.iterdir():  # entries of an older simulator are never read again
            if old.name != version and old.is_dir():
                shutil.rmtree(old, ignore_errors=True)
        directory = base / version
        directory.mkdir(exist_ok=True)
        return cls(directory)

    @classmethod
    def for_this_run(cls, config) -> SimCache:
        """A cache for this run alone (no pytest cache): a temporary directory, made by the process
        that was started (a pytest-xdist worker takes its controller's, from :data:`_RUN_ENV`)
        and removed when that process's pytest ends."""
        base = os.environ.get(_RUN_ENV)
        if base is None or not hasattr(config, "workerinput") or not Path(base).is_dir():
            base = tempfile.mkdtemp(prefix="softtip-sim-")
            os.environ[_RUN_ENV] = base  # before the workers start: they inherit it
            config.add_cleanup(functools.partial(shutil.rmtree, base, ignore_errors=True))
        directory = Path(base) / version_key()
        directory.mkdir(exist_ok=True)
        return cls(directory)

    def path(self, fn: Callable, args: tuple, kwargs: dict) -> Path:
        """Where the entry of this call is (raises :class:`NotCacheable`)."""
        if self.directory is None:
            raise NotCacheable("no cache directory")
        return self.directory / f"{hashlib.sha256(input_bytes(fn, args, kwargs)).hexdigest()}.pickle"

    def call(self, fn: Callable, *args, **kwargs):
        """``fn(*args, **kwargs)``, from the cache when it holds the same call."""
        try:
            path = self.path(fn, args, kwargs)
        except NotCacheable:
            self.refused += 1
            return fn(*args, **kwargs)
        try:
            result = pickle.loads(path.read_bytes())
        except FileNotFoundError:
            pass
        except (pickle.UnpicklingError, EOFError, AttributeError, ImportError, ValueError):
            path.unlink(missing_ok=True)  # damaged by hand, or not ours: made again below
        else:
            self.hits += 1
            return result
        before = input_bytes(fn, args, kwargs)
        result = fn(*args, **kwargs)
        if input_bytes(fn, args, kwargs) != before:
            raise AssertionError(f"{fn.__qualname__} changed its inputs: its result cannot be cached")
        data = pickle.dumps(result, protocol=_PROTOCOL)
        # a whole file or none: another worker may write the same entry at the same moment
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem[:16], suffix=".part")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        self.misses += 1
        return pickle.loads(data)  # the same objects a hit gives (fresh, never shared)


#: The session's cache (conftest.py sets it when pytest starts)
active = SimCache(None)
# softtip's own functions, held here: install() puts the cached ones in their places
_simulate_grasp = softtip.sim.simulate.simulate_grasp
_simulate_probing = softtip.sim.probing.simulate_probing


def simulate_grasp(*args, **kwargs) -> softtip.sim.SimLog:
    """:func:`softtip.sim.simulate_grasp`, cached (same arguments)."""
    return active.call(_simulate_grasp, *args, **kwargs)


def simulate_probing(*args, **kwargs):
    """:func:`softtip.sim.probing.simulate_probing`, cached (same arguments)."""
    return active.call(_simulate_probing, *args, **kwargs)


#: Where softtip's simulating code looks ``simulate_grasp`` up when it runs
GRASP_CALLERS = ("softtip.sim", "softtip.sim.simulate", "softtip.sim.hand")
_SITE = Path(__file__).resolve().parent / "simcache_site"
_ENV = "SOFTTIP_TEST_SIM_CACHE_DIR"


def install(directory: Path) -> None:
    """In a ``softtip`` subprocess: use the cache in ``directory`` for every simulated grasp
    (the reproduction, ``softtip simulate``, the two-finger hand). Run by
    ``simcache_site/sitecustomize.py`` when :func:`subprocess_env` set the variable."""
    import importlib

    global active
    if directory.name != version_key():  # another softtip than the tests' (e.g. another checkout's)
        return
    active = SimCache(directory)
    for name in GRASP_CALLERS:  # test_simcache checks that each holds simulate_grasp
        module = importlib.import_module(name)
        if hasattr(module, "simulate_grasp"):
            module.simulate_grasp = simulate_grasp


def subprocess_env() -> dict[str, str] | None:
    """The environment for a ``softtip`` subprocess that shares the session's cache (None:
    no cache this session, the subprocess simulates)."""
    if active.directory is None:
        return None
    env = dict(os.environ)
    env[_ENV] = str(active.directory)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(_SITE), env.get("PYTHONPATH", "")) if p)
    return env
