"""Calibration of the fingertip from probing presses (:mod:`~softtip.calibration.probing`), of
a mesh fingertip's placement (:mod:`~softtip.calibration.mesh`) and of the payload
(:mod:`~softtip.calibration.payload`)."""
