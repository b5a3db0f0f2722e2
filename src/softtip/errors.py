"""Exceptions raised for bad user input."""

from __future__ import annotations


class InputError(ValueError):
    """User input (a log, a fingertip file, an option) is not what softtip expects.

    The message names where the problem is (file, line, column or key) and what was
    expected. The command line turns it into exit code 2.
    """
