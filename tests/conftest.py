import functools
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import simcache

settings.register_profile("softtip", deadline=None, max_examples=150, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("softtip")


def _bytecode_for_the_run(config) -> None:
    """The run's Python processes (pytest-xdist's workers and the ``softtip`` commands they start)
    keep the bytecode they compile, in a temporary directory removed when the run ends
    (:func:`softtip.testing._bytecode.keep_bytecode`): else several hundred commands compile
    softtip from source again."""
    from softtip.testing._bytecode import keep_bytecode

    prefix = keep_bytecode()
    if prefix is not None:
        config.add_cleanup(functools.partial(shutil.rmtree, prefix, ignore_errors=True))


def pytest_configure(config):
    if not hasattr(config, "workerinput"):
        _bytecode_for_the_run(config)
        # the workers pytest-xdist starts now share the cores: each with a BLAS thread pool
        # would spend CPU starting it and then oversubscribe them; one thread each, as the
        # softtip command runs (softtip.cli.app._one_blas_thread), unless the user said otherwise
        from softtip.cli.app import _one_blas_thread

        _one_blas_thread()
    # the simulated logs that test files share: once per checkout and simulator version (simcache.py)
    simcache.active = simcache.SimCache.in_pytest_cache(config)
    # pytest-xdist's loadfile hands out the files ordered by their number of tests unless told
    # not to: that number says little about their time here (168 tests in the longest file, 4
    # in the docs build), so the collection order (SLOW_FILES_FIRST) is kept
    if getattr(config.option, "dist", "no") == "loadfile":
        config.option.loadscopereorder = False


@pytest.fixture(scope="session")
def sim_cache() -> simcache.SimCache:
    """The session's cache of simulated logs (tests/simcache.py)."""
    return simcache.active


@pytest.fixture
def rng():
    return np.random.default_rng(8380)


#: The test files that take longest, longest first (CPU seconds of each, measured on one core
#: with ``-n 0``: 205, 70, 63, 55, 39, 38, 38, 37, 30, 22, 20, 19, 19, 17, 15, 15, 13, 13, 13, 12):
#: collected first, in this order, so that pytest-xdist, which hands out whole files in
#: collection order (``make test``: ``--dist loadfile``, reordering by size turned off in
#: :func:`pytest_configure`), starts them early and fills in with the short ones, rather than
#: leaving one worker alone with a long file at the end. The order within a file is kept.
SLOW_FILES_FIRST = (
    "test_nothing_lost.py", "test_memory.py", "test_readme_commands.py", "test_foreign.py", "test_fusion.py",
    "test_calibration.py", "test_cli.py", "test_cli_grammar.py", "test_docs.py", "test_bag.py", "test_mesh.py",
    "test_netft.py", "test_output_safety.py", "test_jobs.py", "test_chunked.py", "test_bagout.py", "test_replay.py",
    "test_line_fit.py", "test_cli_evidence.py", "test_depth_online.py",
)  # fmt: skip


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(SLOW_FILES_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
