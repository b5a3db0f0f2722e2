import numpy as np
import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("softtip", deadline=None, max_examples=150, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("softtip")


@pytest.fixture
def rng():
    return np.random.default_rng(8380)
