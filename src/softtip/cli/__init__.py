"""The ``softtip`` command: a thin shell over the library, one module per command.

Each command's module parses its options, calls one library function and writes what it
returns: :mod:`~softtip.cli.estimate`, :mod:`~softtip.cli.stream`, :mod:`~softtip.cli.simulate`,
:mod:`~softtip.cli.reproduce`, :mod:`~softtip.cli.calibrate`, :mod:`~softtip.cli.calibrate_payload`,
:mod:`~softtip.cli.fuse`. Option types with units are in :mod:`~softtip.cli.types`, the options
several commands share in :mod:`~softtip.cli.options`, the group in :mod:`~softtip.cli.app`.
"""

from softtip.cli.app import main, run

__all__ = ["main", "run"]
