"""Example data shipped with softtip, so that it runs without a sensor."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["EXAMPLE_ANGLE_DEG", "EXAMPLE_PATH", "EXAMPLE_PROBING_PATH", "EXAMPLE_STILL_PATH", "load_example"]

#: A 10 s, 50 Hz grasp on the murakami2006 fingertip: contact at 2 s on the tip, force
#: rising to 0.55 kgf by 4 s, a line contact at 45° whose tangential spin torque builds up
#: from 4.5 s; Nano17-class noise and a constant bias. Made by
#: ``scripts/make_example_data.py`` with :func:`softtip.sim.synthetic.synthetic_grasp`.
EXAMPLE_PATH = Path(str(resources.files("softtip") / "data" / "example_grasp.csv"))
#: The true direction of the example grasp's line contact, degrees (its plots draw it).
EXAMPLE_ANGLE_DEG = 45.0

#: A 45 s, 100 Hz probing log for ``softtip calibrate``: 30 plane presses with slides on a
#: sphere fingertip of radius 16 mm centred at (0.3, −0.2, 20.0) mm, Nano17-class noise.
#: Made by ``scripts/make_calibration_examples.py`` with :func:`softtip.sim.probing.simulate_probing`.
EXAMPLE_PROBING_PATH = Path(str(resources.files("softtip") / "data" / "example_probing.csv"))

#: A 12 s, 100 Hz contact-free log for ``softtip calibrate-payload``: a 20 g fingertip
#: (centre of mass (1, −0.5, 20) mm) still in 12 orientations, with sensor bias and noise,
#: and the orientation columns qw, qx, qy, qz. Made by ``scripts/make_calibration_examples.py``.
EXAMPLE_STILL_PATH = Path(str(resources.files("softtip") / "data" / "example_still.csv"))


def load_example():
    """The example grasp as a :class:`softtip.io.tables.Log` (SI units)."""
    from softtip.io.tables import read_log

    return read_log(EXAMPLE_PATH, units="si")
