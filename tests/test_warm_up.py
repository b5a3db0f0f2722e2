"""An :class:`~softtip.Estimator` built for a sensor loads its compiled steps before the first
sample (:meth:`~softtip.Estimator.warm_up`), so that no step is compiled or loaded from numba's
cache while a live stream waits; and the warm-up leaves the estimator's own state untouched."""

import os
import subprocess
import sys

import numpy as np
import pytest

from softtip import Estimator, EstimatorConfig, load_example

pytest.importorskip("numba")

# In a fresh interpreter (the steps of this process may be loaded already by other tests): count
# numba's compilations (a load from its disk cache is one too) while the example log streams.
_COUNT = """
import sys
import numba.core.dispatcher as D
from softtip import Estimator, EstimatorConfig, load_example
compiled, streaming = [], [False]
original = D.Dispatcher.compile
def compile(self, sig):
    if streaming[0]:
        compiled.append(self.py_func.__name__)
    return original(self, sig)
D.Dispatcher.compile = compile
log = load_example()
for config in eval(sys.argv[2]):  # each configuration in turn: what it alone calls loads in its warm-up
    estimator = Estimator("murakami2006", EstimatorConfig(**config), expected_samples=eval(sys.argv[1]))
    streaming[0] = True
    states = {estimator.update(t, w).state for t, w in zip(log.t.tolist(), log.wrench.tolist())}
    streaming[0] = False
    print(sorted(states), sorted(set(compiled)))
    compiled.clear()
"""

CONFIGS = [{}, {"lowpass_hz": 5.0, "sample_rate": 50.0}, {"contact_point": "line-fit"}, {"contact_point": "track"},
           {"relatch_distance": 2e-3}]  # fmt: skip


def _compiled_while_streaming(expected_samples, configs):
    """(states estimated, steps compiled while streaming) per configuration, as text."""
    out = subprocess.run(
        [sys.executable, "-c", _COUNT, repr(expected_samples), repr(configs)],
        capture_output=True, text=True, check=True, env={**os.environ, "SOFTTIP_NUMBA": "1"},
    )  # fmt: skip
    return [line.split("] [") for line in out.stdout.strip().splitlines()]


def test_a_sensors_estimator_compiles_nothing_while_it_streams():
    runs = _compiled_while_streaming(None, CONFIGS)
    assert len(runs) == len(CONFIGS)
    for config, (states, compiled) in zip(CONFIGS, runs):
        assert "'line'" in states or "'point'" in states, config  # the log's contact was estimated
        assert compiled == "]", (config, compiled)


def test_without_the_warm_up_the_first_contact_loads_the_steps():
    # the check above can fail: a replay of known length (no warm-up) loads them in the stream
    ((states, compiled),) = _compiled_while_streaming(100_000, [{}])
    assert "latch_step" in compiled and "located_step" in compiled


def test_the_warm_up_leaves_the_estimators_state_untouched():
    log = load_example()
    config = EstimatorConfig(sample_rate=50.0)
    warmed = Estimator("murakami2006", config)
    warmed.warm_up()  # once more, by hand: it runs on a throwaway estimator
    replay = Estimator("murakami2006", config, expected_samples=len(log.t))
    a = [warmed.update(t, w) for t, w in zip(log.t.tolist(), log.wrench.tolist())]
    b = [replay.update(t, w) for t, w in zip(log.t.tolist(), log.wrench.tolist())]
    assert repr(a) == repr(b)
    assert warmed.contacts == replay.contacts and warmed.warnings == replay.warnings
    assert np.allclose(warmed.bias, replay.bias, rtol=0.0, atol=0.0)
