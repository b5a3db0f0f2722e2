"""Logs (CSV, Parquet), the atomic writer, TOML files, bags, the Net F/T receiver, sources."""

from softtip.io.tables import (
    Log,
    read_log,
    write_table,
    REQUIRED_COLUMNS,
)

__all__ = [
    "Log",
    "read_log",
    "write_table",
    "REQUIRED_COLUMNS",
]
