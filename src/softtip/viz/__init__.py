"""Views: the Rerun 3-D view and the papers' plots."""

# the public names it had as one module, before it became this package
from softtip.viz.rerun import *  # noqa: F403
from softtip.viz.rerun import __all__  # noqa: F401
