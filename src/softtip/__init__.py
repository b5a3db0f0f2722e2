"""softtip: intrinsic tactile sensing with a soft fingertip on a six-axis F/T sensor.

From the six numbers of a force/torque sensor under a soft-skinned fingertip: where the
fingertip is touched, the contact normal, the spin torque, whether the contact is a point
or a strip (line), and the direction of the edge, stick, thin plate, thin cylinder or fringe
being touched (Murakami & Hasegawa 2004, 2006; Bicchi 1990). SI units, sensor frame.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the names, for readers and type checkers; at run time :func:`__getattr__` imports them
    from softtip.apps.live import run
    from softtip.core.axial import axial_difference, axial_mean, axial_median
    from softtip.core.fingertip import (
        PRESETS,
        Capsule,
        Ellipsoid,
        Fingertip,
        ImplicitSurface,
        Sphere,
        load_fingertip,
        murakami2006,
    )
    from softtip.core.lever import check_wrench_units
    from softtip.core.location import Contact, contact_from_wrench
    from softtip.core.mesh import MeshFingertip
    from softtip.core.mounting import Mounted
    from softtip.core.noise import NANO17, SensorNoise, direction_angle_std, tangential_spin_torque_std
    from softtip.core.spin import direction_angle, edge_direction, spin_torque, tangent_frame, tangential_spin_torque
    from softtip.core.units import KGF, KGF_MM, wrench_from_si, wrench_to_si
    from softtip.errors import InputError
    from softtip.estimator import (
        STATES,
        Estimates,
        Estimator,
        EstimatorConfig,
        EstimatorWarning,
        SampleEstimate,
        estimate,
    )
    from softtip.io.examples import EXAMPLE_PATH, load_example

#: Each public name -> the module that defines it, imported the first time the name is used:
#: ``import softtip`` itself stays light (the ``softtip`` command starts without the estimator,
#: the fingertips or the live loop when the command does not need them).
_HOMES = {
    "run": "softtip.apps.live",
    **dict.fromkeys(("axial_difference", "axial_mean", "axial_median"), "softtip.core.axial"),
    **dict.fromkeys(("PRESETS", "Capsule", "Ellipsoid", "Fingertip", "ImplicitSurface", "Sphere", "load_fingertip",
                     "murakami2006"), "softtip.core.fingertip"),
    "check_wrench_units": "softtip.core.lever",
    **dict.fromkeys(("Contact", "contact_from_wrench"), "softtip.core.location"),
    "MeshFingertip": "softtip.core.mesh",
    "Mounted": "softtip.core.mounting",
    **dict.fromkeys(("NANO17", "SensorNoise", "direction_angle_std", "tangential_spin_torque_std"), "softtip.core.noise"),
    **dict.fromkeys(("direction_angle", "edge_direction", "spin_torque", "tangent_frame", "tangential_spin_torque"),
                    "softtip.core.spin"),
    **dict.fromkeys(("KGF", "KGF_MM", "wrench_from_si", "wrench_to_si"), "softtip.core.units"),
    "InputError": "softtip.errors",
    **dict.fromkeys(("STATES", "Estimates", "Estimator", "EstimatorConfig", "EstimatorWarning", "SampleEstimate",
                     "estimate"), "softtip.estimator"),
    **dict.fromkeys(("EXAMPLE_PATH", "load_example"), "softtip.io.examples"),
}  # fmt: skip


def __getattr__(name: str):
    """A public name, imported from its module the first time it is used (then it is an
    attribute of the package like any other)."""
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_HOMES[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


try:  # written by setuptools-scm from the git tag when softtip is built or installed
    from softtip._version import __version__
except ImportError:  # a source tree on sys.path that was never built: the installed metadata, if any
    from importlib.metadata import PackageNotFoundError, version

    try:
        __version__ = version("softtip")
    except PackageNotFoundError:
        __version__ = "0+unknown"

__all__ = [
    "Capsule",
    "Contact",
    "EXAMPLE_PATH",
    "Ellipsoid",
    "Estimates",
    "Estimator",
    "EstimatorConfig",
    "EstimatorWarning",
    "Fingertip",
    "ImplicitSurface",
    "InputError",
    "KGF",
    "KGF_MM",
    "Mounted",
    "MeshFingertip",
    "NANO17",
    "PRESETS",
    "STATES",
    "SampleEstimate",
    "SensorNoise",
    "Sphere",
    "axial_difference",
    "axial_mean",
    "axial_median",
    "check_wrench_units",
    "contact_from_wrench",
    "direction_angle",
    "direction_angle_std",
    "edge_direction",
    "estimate",
    "load_example",
    "load_fingertip",
    "murakami2006",
    "run",
    "spin_torque",
    "tangent_frame",
    "tangential_spin_torque",
    "tangential_spin_torque_std",
    "wrench_from_si",
    "wrench_to_si",
]
