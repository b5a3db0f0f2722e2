"""Imported once by the server that forks the workers of :func:`softtip.io.chunked.estimate_pieces`
(``jobs`` > 1): softtip, numba and the compiled kernels are loaded there, before any worker is
forked, so that no worker loads them again (about 0.7 s of CPU each)."""

from softtip.io.chunked import warm_kernels

warm_kernels()
