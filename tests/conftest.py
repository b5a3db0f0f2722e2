import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import simcache

settings.register_profile("softtip", deadline=None, max_examples=150, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("softtip")


def pytest_configure(config):
    # the simulated logs that test files share: once per checkout and simulator version (simcache.py)
    simcache.active = simcache.SimCache.in_pytest_cache(config)


@pytest.fixture(scope="session")
def sim_cache() -> simcache.SimCache:
    """The session's cache of simulated logs (tests/simcache.py)."""
    return simcache.active


@pytest.fixture
def rng():
    return np.random.default_rng(8380)


#: Test files that take a minute or more (the README's commands run `softtip reproduce`):
#: collected first, so that pytest-xdist, which hands out whole files in collection order
#: (``make test``: ``--dist loadfile``), starts them at once rather than leaving one worker
#: alone with them at the end. The order within a file is kept.
SLOW_FILES_FIRST = ("test_readme_commands.py", "test_calibration.py", "test_cli_grammar.py", "test_fusion.py")


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(SLOW_FILES_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
