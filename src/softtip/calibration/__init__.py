"""Calibration of the fingertip (probing presses, meshes) and of the payload."""

# the public names it had as one module, before it became this package
from softtip.calibration.probing import *  # noqa: F403
from softtip.calibration.probing import __all__  # noqa: F401
