"""Views: the Rerun 3-D view (:mod:`~softtip.viz.rerun`), the papers' plots
(:mod:`~softtip.viz.plot`) and their style (:mod:`~softtip.viz.style`)."""
