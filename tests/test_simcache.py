"""The tests' cache of simulated logs (tests/simcache.py): a hit is the recomputed result to
the bit, concurrent writers leave one whole entry, unsafe inputs are never cached, and the
version key follows the simulator's sources."""

from __future__ import annotations

import math
import os
import pickle
import shutil
import struct
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import simcache
import softtip
from softtip.core.fingertip import murakami2006
from softtip.sim import Plate, SensorModel, paper_scenario
from softtip.sim.digest import SOURCE_PACKAGES
from softtip.sim.pose import rotation_matrix
from softtip.sim.simulate import simulate_grasp


def identical(a, b, path: str = "result", seen: set | None = None) -> int:
    """Assert that ``a`` and ``b`` are the same to the bit, walked through their attributes,
    items and arrays; returns how many arrays and numbers were compared."""
    seen = set() if seen is None else seen
    assert type(a) is type(b), f"{path}: {type(a)} != {type(b)}"
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, path
        assert a.tobytes() == b.tobytes(), path  # NaNs and signed zeros too
        return 1
    if isinstance(a, float):
        assert struct.pack("<d", a) == struct.pack("<d", b), f"{path}: {a!r} != {b!r}"
        return 1
    if a is None or isinstance(a, (bool, int, str, bytes, complex, np.generic, np.dtype, type)):
        assert a == b or (a != a and b != b), f"{path}: {a!r} != {b!r}"
        return 1
    if (id(a), id(b)) in seen:
        return 0
    seen.add((id(a), id(b)))
    if isinstance(a, dict):
        assert list(a) == list(b), path
        return sum(identical(a[k], b[k], f"{path}[{k!r}]", seen) for k in a)
    if isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        return sum(identical(x, y, f"{path}[{i}]", seen) for i, (x, y) in enumerate(zip(a, b)))
    if callable(a) and not hasattr(a, "__dict__"):
        assert a == b, path
        return 1
    state_a, state_b = dict(getattr(a, "__dict__", {})), dict(getattr(b, "__dict__", {}))
    for name in (n for c in type(a).__mro__ for n in getattr(c, "__slots__", ())):
        if hasattr(a, name):
            state_a[name], state_b[name] = getattr(a, name), getattr(b, name)
    return identical(state_a, state_b, path, seen)


def test_a_cached_grasp_is_the_recomputed_one_to_the_bit(sim_cache):
    # the papers' 1 mm plate at 45° with the reproduction's seed (test_joint and
    # test_reproduce simulate it): from the cache, and simulated again here
    args = (murakami2006(), Plate(0.001), paper_scenario(math.radians(45.0)))
    cached = sim_cache.call(simulate_grasp, *args, rng=2006)
    if sim_cache.directory is not None:
        assert sim_cache.path(simulate_grasp, args, {"rng": 2006}).is_file()
    fresh = simulate_grasp(*args, rng=2006)
    assert identical(cached, fresh) > 20
    assert cached.wrench.shape == (500, 6)
    # the comparison can fail: another noise seed differs in the sensor output only
    other = simulate_grasp(*args, rng=2007)
    with pytest.raises(AssertionError, match=r"result\['wrench'\]"):
        identical(cached, other)
    identical(cached.wrench_true, other.wrench_true)


def test_a_hit_is_a_fresh_copy(tmp_path):
    cache = simcache.SimCache(tmp_path)
    a = cache.call(rotation_matrix, np.array([0.0, 0.0, 1.0]), 0.3)
    b = cache.call(rotation_matrix, np.array([0.0, 0.0, 1.0]), 0.3)
    assert (cache.misses, cache.hits) == (1, 1)
    assert np.array_equal(a, rotation_matrix(np.array([0.0, 0.0, 1.0]), 0.3))
    a[0, 0] = 7.0  # a test that changes what it got changes nobody else's
    assert np.array_equal(b, cache.call(rotation_matrix, np.array([0.0, 0.0, 1.0]), 0.3)) and b[0, 0] != 7.0
    assert cache.call(rotation_matrix, np.array([0.0, 0.0, 1.0]), 0.4)[0, 0] == pytest.approx(math.cos(0.4))
    assert cache.misses == 2


def test_concurrent_writers_leave_one_whole_entry(tmp_path):
    cache = simcache.SimCache(tmp_path)
    axis = np.array([0.3, -0.2, 0.9])
    results, errors = [], []
    start = threading.Barrier(8)

    def work():
        try:
            start.wait()
            results.append(cache.call(rotation_matrix, axis, 1.1))
        except BaseException as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work) for _ in range(8)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors
    expected = rotation_matrix(axis, 1.1)
    assert len(results) == 8 and all(r.tobytes() == expected.tobytes() for r in results)
    files = sorted(p.name for p in tmp_path.iterdir())
    assert len(files) == 1 and files[0].endswith(".pickle")  # no temporary file left behind
    assert pickle.loads((tmp_path / files[0]).read_bytes()).tobytes() == expected.tobytes()


class _TestsOwn:
    """A class defined in a test: its code is not in the version key."""

    value = 1.0


def test_unsafe_inputs_are_computed_and_never_stored(tmp_path):
    cache = simcache.SimCache(tmp_path)
    gen = np.random.default_rng(5)
    drawn = cache.call(SensorModel().measure, np.zeros((4, 6)), gen)  # advances gen: must run
    assert np.array_equal(drawn, SensorModel().measure(np.zeros((4, 6)), np.random.default_rng(5)))
    assert gen.bit_generator.state != np.random.default_rng(5).bit_generator.state  # advanced, as by the function
    assert cache.call(getattr, _TestsOwn(), "value") == 1.0
    assert cache.call(lambda: 2.0) == 2.0
    assert cache.refused == 3 and list(tmp_path.iterdir()) == []
    with pytest.raises(simcache.NotCacheable, match="random generator"):
        cache.path(SensorModel().measure, (np.zeros((4, 6)), gen), {})
    with pytest.raises(simcache.NotCacheable, match="_TestsOwn"):
        cache.path(getattr, (_TestsOwn(), "value"), {})
    # a call that changes its inputs: a hit would skip the change
    dst = np.zeros(3)
    with pytest.raises(AssertionError, match="changed its inputs"):
        cache.call(np.copyto, dst, np.ones(3))
    assert list(tmp_path.iterdir()) == []


def test_a_damaged_entry_is_made_again(tmp_path):
    cache = simcache.SimCache(tmp_path)
    first = cache.call(rotation_matrix, np.array([0.0, 1.0, 0.0]), 0.5)
    (entry,) = tmp_path.iterdir()
    entry.write_bytes(entry.read_bytes()[:20])  # cut short
    again = cache.call(rotation_matrix, np.array([0.0, 1.0, 0.0]), 0.5)
    assert again.tobytes() == first.tobytes() and cache.misses == 2 and cache.hits == 0
    assert pickle.loads(entry.read_bytes()).tobytes() == first.tobytes()


def test_without_a_directory_every_call_computes():
    cache = simcache.SimCache(None)
    assert cache.call(rotation_matrix, np.array([1.0, 0.0, 0.0]), 0.2).shape == (3, 3)
    assert cache.refused == 1 and cache.hits == cache.misses == 0


def test_the_version_key_follows_the_simulators_sources(tmp_path, monkeypatch):
    root = Path(softtip.__file__).parent
    # softtip.sim.simulator_digest (the benchmarks' key) reads this package by default
    assert softtip.sim.simulator_digest() == softtip.sim.simulator_digest(root)
    copy = tmp_path / "softtip"
    for package in SOURCE_PACKAGES:
        shutil.copytree(root / package, copy / package, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "__init__.py").write_text("")
    monkeypatch.setattr(softtip, "__file__", str(copy / "__init__.py"))
    key = simcache.version_key()
    assert simcache.version_key() == key
    contact = copy / "sim" / "foundation.py"
    contact.write_text(contact.read_text() + "\n# a change\n")
    changed = simcache.version_key()
    assert changed != key
    shape = next((copy / "core").glob("*.py"))
    shape.write_text(shape.read_text() + "\n")
    assert simcache.version_key() not in (key, changed)
    monkeypatch.setattr(softtip, "__version__", softtip.__version__ + ".post1")
    assert simcache.version_key() not in (key, changed)


def test_the_session_cache_lives_in_pytests_cache_under_the_version(sim_cache, pytestconfig):
    if sim_cache.directory is None:
        pytest.skip("no cache in this run (SOFTTIP_TEST_SIM_CACHE=0)")
    if getattr(pytestconfig, "cache", None) is None:  # -p no:cacheprovider: the run's own
        assert sim_cache.directory.parent == Path(os.environ[simcache._RUN_ENV])
    else:
        assert sim_cache.directory.parent == Path(pytestconfig.cache.mkdir("softtip-sim"))
    assert sim_cache.directory.name == simcache.version_key()


def test_without_a_pytest_cache_the_workers_share_one_for_the_run(monkeypatch):
    # the process that starts the workers makes it (and removes it when it ends); a worker
    # takes the one in its environment, which it inherited
    cleanups = []
    controller = SimpleNamespace(cache=None, add_cleanup=cleanups.append)
    monkeypatch.delenv(simcache._RUN_ENV, raising=False)
    monkeypatch.delenv("SOFTTIP_TEST_SIM_CACHE", raising=False)
    made = simcache.SimCache.in_pytest_cache(controller)
    assert made.directory.is_dir() and made.directory.name == simcache.version_key()
    assert made.directory.parent == Path(os.environ[simcache._RUN_ENV])
    worker = SimpleNamespace(cache=None, workerinput={}, add_cleanup=cleanups.append)
    assert simcache.SimCache.in_pytest_cache(worker).directory == made.directory
    assert len(cleanups) == 1  # the worker leaves its removal to the controller
    cleanups[0]()
    assert not made.directory.parent.exists()
    monkeypatch.setenv("SOFTTIP_TEST_SIM_CACHE", "0")
    assert simcache.SimCache.in_pytest_cache(controller).directory is None


def test_the_subprocess_hook_knows_where_softtip_looks_up_simulate_grasp():
    import importlib

    for name in simcache.GRASP_CALLERS:  # a module moved: update simcache.GRASP_CALLERS
        assert importlib.import_module(name).simulate_grasp is simcache._simulate_grasp, name


def test_a_softtip_subprocess_shares_the_cache_and_writes_the_same_bytes(tmp_path, monkeypatch):
    # the README's `softtip simulate` / `softtip reproduce` lines run with simcache.subprocess_env()
    cache_dir = tmp_path / simcache.version_key()  # a subprocess of another softtip would not use it
    cache_dir.mkdir()
    monkeypatch.setattr(simcache, "active", simcache.SimCache(cache_dir))
    softtip_cmd = Path(sys.executable).with_name("softtip")
    args = ["simulate", "--object", "plate", "--size", "2mm", "--angle", "30", "--duration", "3", "--elements", "1500"]

    def run(out, env):
        r = subprocess.run([softtip_cmd, *args, "-o", tmp_path / out], capture_output=True, text=True, timeout=300, env=env)
        assert r.returncode == 0, r.stderr
        return (tmp_path / out).read_bytes()

    direct = run("direct.csv", None)
    assert list(cache_dir.iterdir()) == []
    first = run("first.csv", simcache.subprocess_env())
    entries = list(cache_dir.iterdir())
    assert len(entries) == 1 and entries[0].suffix == ".pickle"
    mtime = entries[0].stat().st_mtime_ns
    second = run("second.csv", simcache.subprocess_env())  # a hit: the entry is read, not written again
    assert list(cache_dir.iterdir()) == entries and entries[0].stat().st_mtime_ns == mtime
    assert direct == first == second
