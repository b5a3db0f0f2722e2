"""Calibration of the fingertip (probing presses, meshes) and of the payload."""

# the public names it had as one module, before it became this package; __getattr__ resolves
# the probing simulator's former names (now softtip.sim.probing) on use
from softtip.calibration.probing import *  # noqa: F403
from softtip.calibration.probing import __all__, __getattr__  # noqa: F401
