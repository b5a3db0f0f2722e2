"""Views: the Rerun 3-D view and the papers' plots."""

from softtip.viz.rerun import (
    RerunLogger,
    import_rerun,
    surface_mesh,
)

__all__ = [
    "RerunLogger",
    "import_rerun",
    "surface_mesh",
]
