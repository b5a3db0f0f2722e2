"""Example data shipped with softtip, so that it runs without a sensor."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["EXAMPLE_PATH", "load_example"]

#: A 10 s, 50 Hz grasp on the murakami2006 fingertip: contact at 2 s on the tip, force
#: rising to 0.55 kgf by 4 s, a line contact at 45° whose tangential spin torque builds up
#: from 4.5 s; Nano17-class noise and a constant bias. Made by
#: ``scripts/make_example_data.py`` with :func:`softtip.synthetic.synthetic_grasp`.
EXAMPLE_PATH = Path(str(resources.files("softtip") / "data" / "example_grasp.csv"))


def load_example():
    """The example grasp as a :class:`softtip.io.Log` (SI units)."""
    from softtip.io import read_log

    return read_log(EXAMPLE_PATH, units="si")
