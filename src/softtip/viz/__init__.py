"""Views: the Rerun 3-D view and the papers' plots."""

# the public names of the former module softtip.viz
from softtip.viz.rerun import *  # noqa: F403
from softtip.viz.rerun import __all__  # noqa: F401
