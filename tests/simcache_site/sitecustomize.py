"""Put on a ``softtip`` subprocess's PYTHONPATH by ``simcache.subprocess_env()``: its simulated
grasps come from the tests' cache (tests/simcache.py)."""

import os
import sys
from pathlib import Path

if os.environ.get("SOFTTIP_TEST_SIM_CACHE_DIR"):
    sys.path.append(str(Path(__file__).resolve().parents[1]))
    import simcache

    simcache.install(Path(os.environ["SOFTTIP_TEST_SIM_CACHE_DIR"]))
