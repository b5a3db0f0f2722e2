"""Tare: the sensor bias from the first samples, while the fingertip is untouched.

Unless a bias is given, the mean of the samples in the first ``tare_duration`` seconds is the
bias; those samples are reported as ``none`` (``taring``). :func:`tare_log` does it for a
whole log, :class:`StreamTare` one sample at a time; both use the same comparison
``t − t₀ < tare_duration`` so they agree on the boundary sample.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.estimator.config import EstimatorConfig

__all__ = ["Tare", "tare_log", "StreamTare"]


class Tare(NamedTuple):
    """The tare of a log."""

    bias: NDArray[np.float64]  #: (6,) N and N·m; NaN when the log never leaves the tare period
    taring: NDArray[np.bool_]  #: (N,) samples used for the bias
    force_std: float  #: N, largest standard deviation of a force component while taring (NaN without)


def tare_log(t: NDArray, w: NDArray, config: EstimatorConfig) -> Tare:
    """The bias of a whole log ``w`` (N, 6) sampled at ``t`` (N,)."""
    n = len(t)
    taring = np.zeros(n, dtype=bool)
    if config.bias is not None:
        return Tare(np.asarray(config.bias, dtype=float), taring, math.nan)
    if config.tare_duration <= 0 or not n:
        return Tare(np.zeros(6), taring, math.nan)
    n_tare = int(np.count_nonzero(t - t[0] < config.tare_duration))
    taring[:n_tare] = True
    # a log that never leaves the tare period has no bias (as in the stream)
    bias = np.mean(w[:n_tare], axis=0) if n_tare < n else np.full(6, np.nan)
    return Tare(bias, taring, float(np.max(np.std(w[:n_tare, :3], axis=0))))


class StreamTare:
    """The tare of :func:`tare_log`, one sample at a time.

    :meth:`update` returns ``None`` while taring, then the bias; the samples it was made of
    are in :attr:`samples` until :meth:`release` (the stream primes its filter with them, as
    the batch filters the whole log).
    """

    def __init__(self, config: EstimatorConfig):
        self.config = config
        self.reset()

    def reset(self) -> None:
        """Forget the bias (unless one is given) and start taring again."""
        cfg = self.config
        self.bias: tuple[float, ...] | None = cfg.bias
        if self.bias is None and cfg.tare_duration <= 0:
            self.bias = (0.0,) * 6
        self.samples: list[tuple[float, ...]] = []
        self._t0: float | None = None

    def update(self, t: float, w: list[float]) -> tuple[float, ...] | None:
        """The bias, or ``None`` while sample ``w`` at ``t`` is one of the tare's."""
        if self.bias is not None:
            return self.bias
        if self._t0 is None:
            self._t0 = t
        if t - self._t0 < self.config.tare_duration:
            self.samples.append(tuple(w))
            return None
        self.bias = tuple(np.mean(np.array(self.samples), axis=0).tolist())
        return self.bias

    def release(self) -> list[tuple[float, ...]]:
        """The tare's samples (once; the buffer is emptied)."""
        s, self.samples = self.samples, []
        return s
