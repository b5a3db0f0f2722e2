"""Former home of the estimator, kept so that ``softtip.pipeline`` imports keep working.

The estimator is the package :mod:`softtip.estimator`; import from there (or from
:mod:`softtip`).
"""

from softtip.estimator import (  # noqa: F401
    CONTACT_POINT_MODES,
    LINE,
    NONE,
    POINT,
    STATES,
    Estimates,
    Estimator,
    EstimatorConfig,
    SampleEstimate,
    estimate,
)

__all__ = ["STATES", "CONTACT_POINT_MODES", "EstimatorConfig", "Estimates", "SampleEstimate", "Estimator", "estimate"]
