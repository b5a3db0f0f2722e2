"""Imported once by the server that forks the worker processes of :func:`softtip.apps.pool.start_pool`:
softtip, numba and the compiled kernels are loaded there, before any worker is forked, so that
no worker loads them again (about 0.7 s of CPU each). The server ends with the run that started
it, also while it loads them (a run stopped at once leaves nothing behind)."""

from softtip.apps.pool import _end_with_parent, warm_kernels

_end_with_parent()
warm_kernels()
