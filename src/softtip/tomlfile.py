"""Reading the project's TOML files (fingertips, payloads, hands) with located errors."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from softtip.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

__all__ = ["read_toml", "read_toml_table"]


def read_toml(path: str | os.PathLike[str], what: str) -> dict:
    """The parsed TOML file at ``path``; ``what`` names the kind of file in messages.

    Raises
    ------
    InputError
        Unreadable file or malformed TOML (the message has the file, line and column).
    """
    name = os.fspath(path)
    try:
        return tomllib.loads(Path(name).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{name}: {what} file not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: malformed TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{name}: cannot read {what} file: {exc}") from None


def read_toml_table(path: str | os.PathLike[str], table: str, keys: tuple[str, ...], describe: str) -> dict:
    """The ``[table]`` of the TOML file at ``path``, checked to hold no key but ``keys``.

    ``describe`` says what the table holds (in the message when it is missing).

    Raises
    ------
    InputError
        As :func:`read_toml`; no ``[table]``; an unknown key (the message names the file).
    """
    name = os.fspath(path)
    found = read_toml(name, table).get(table)
    if not isinstance(found, dict):
        raise InputError(f"{name}: expected a [{table}] table with {describe}")
    unknown = sorted(set(found) - set(keys))
    if unknown:
        raise InputError(f"{name}: [{table}] unknown key(s) {', '.join(unknown)}; expected {', '.join(keys)}")
    return found
