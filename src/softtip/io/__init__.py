"""Logs (CSV, Parquet), the atomic writer, TOML files, bags, the Net F/T receiver, sources."""

# the public names it had as one module, before it became this package
from softtip.io.tables import *  # noqa: F403
from softtip.io.tables import __all__  # noqa: F401
