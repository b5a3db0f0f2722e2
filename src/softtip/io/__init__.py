"""Logs (CSV, Parquet), the atomic writer, TOML files, bags, the Net F/T receiver, sources."""

# the public names of the former module softtip.io
from softtip.io.tables import *  # noqa: F403
from softtip.io.tables import __all__  # noqa: F401
