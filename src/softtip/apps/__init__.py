"""Applications: runs that drive the estimator and the simulator over files and devices.

Above the formats (:mod:`softtip.io`) and below the command line (:mod:`softtip.cli`):
chunked estimation of a long log (:mod:`~softtip.apps.chunked`), the live loop over a
sensor (:mod:`~softtip.apps.live`) and the papers' reproduction (:mod:`~softtip.apps.reproduce`).
"""
