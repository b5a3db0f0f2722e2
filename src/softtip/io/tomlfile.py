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

__all__ = ["read_toml"]


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
