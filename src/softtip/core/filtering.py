"""Causal low-pass filtering of the wrench.

A Butterworth filter from :func:`scipy.signal.butter` in second-order sections, run as one
per-sample step, :func:`sos_step`: transposed direct-form II per section, scipy's ``sosfilt``
recurrence in its order of operations, so the two give the same bits (tested). The stream
(:class:`SosStream`) calls the step per sample (one ``sosfilt`` call per sample would cost
~60 µs in CPython); the batch (:func:`sosfilt_state`) runs it in one compiled loop
(:func:`sos_run`, about 1.5 times as fast as ``sosfilt`` on a 1e6 × 6 log), and scipy's
``sosfilt`` where numba is off or not loaded for a short log (the step as Python would take
~10 µs a sample). Both start from the steady state for the first sample
(:func:`scipy.signal.sosfilt_zi`), so the filter has no start-up transient.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from softtip.core._jit import lazy_jit, use_numba

__all__ = [
    "lowpass_sos", "noise_gain", "sosfilt_batch", "sosfilt_state", "SosStream", "sos_step", "sos_run", "sos_coefficients",
    "sos_initial_state",
]  # fmt: skip


def _signal():
    # scipy.signal takes ~1.5 s to import; only pay for it when a filter is used
    from scipy import signal

    return signal


def lowpass_sos(cutoff_hz: float, sample_rate: float, order: int = 2) -> NDArray[np.float64]:
    """Butterworth low-pass in second-order sections, shape ``(n_sections, 6)``.

    Parameters
    ----------
    cutoff_hz : float
        -3 dB frequency, Hz; must be below the Nyquist frequency ``sample_rate / 2``.
    sample_rate : float
        Hz.
    order : int
        Filter order.
    """
    if not (math.isfinite(sample_rate) and sample_rate > 0):
        raise ValueError(f"sample rate must be positive, got {sample_rate!r} Hz")
    if not (0 < cutoff_hz < 0.5 * sample_rate):
        raise ValueError(
            f"low-pass cutoff {cutoff_hz!r} Hz must lie between 0 and the Nyquist frequency "
            f"{0.5 * sample_rate:g} Hz"
        )
    if int(order) < 1:
        raise ValueError(f"filter order must be at least 1, got {order!r}")
    return _signal().butter(int(order), cutoff_hz, btype="low", fs=sample_rate, output="sos")


def noise_gain(sos: NDArray[np.float64]) -> float:
    """Factor by which the filter scales the standard deviation of white noise.

    ``sqrt(Σ h[k]²)`` over the impulse response ``h``.
    """
    n = 1 << 16
    impulse = np.zeros(n)
    impulse[0] = 1.0
    return float(np.sqrt(np.sum(_signal().sosfilt(sos, impulse) ** 2)))


def sosfilt_batch(sos: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Filter ``x`` (shape ``(N, C)``) along axis 0, starting in steady state for ``x[0]``."""
    return sosfilt_state(sos, x)[0]


def sosfilt_state(
    sos: NDArray[np.float64], x: NDArray[np.float64], zi: NDArray[np.float64] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """:func:`sosfilt_batch` from the filter state ``zi`` (``None``: steady state for
    ``x[0]``); returns the filtered ``x`` and the state after it (``(sections, 2, C)``; ``zi``
    for an empty ``x``), to filter a log piece by piece with the bits of the whole."""
    if len(x) == 0:
        return x.copy(), zi
    if zi is None:
        zi = sos_initial_state(sos, x[0])
    if use_numba(len(x)):  # the stream's step, compiled: scipy's bits, ~1.5x faster
        z, y = np.array(zi, dtype=float), np.empty(x.shape)
        sos_run(sos_coefficients(sos), z, np.ascontiguousarray(x, dtype=float), y)
        return y, z
    return _signal().sosfilt(sos, x, axis=0, zi=zi)


@lazy_jit(nogil=False)
def sos_step(coef, z, x, y):  # pragma: no cover - compiled
    """One sample of the filter: ``x`` (C,) in, ``y`` (C,) written; the state ``z``
    (sections, 2, C), the layout of :func:`sosfilt_state`'s, read and written.

    Transposed direct-form II per section, the recurrence and order of operations of
    scipy's ``sosfilt`` (the same bits, tested); ``coef`` (sections, 5): ``b0, b1, b2, a1,
    a2`` (``a0 = 1``).
    """
    for c in range(x.shape[0]):
        v = x[c]
        for s in range(coef.shape[0]):
            u = coef[s, 0] * v + z[s, 0, c]
            z[s, 0, c] = coef[s, 1] * v - coef[s, 3] * u + z[s, 1, c]
            z[s, 1, c] = coef[s, 2] * v - coef[s, 4] * u
            v = u
        y[c] = v


@lazy_jit
def sos_run(coef, z, x, y):  # pragma: no cover - compiled
    """:func:`sos_step` over the samples of ``x`` (N, C) into ``y`` (N, C); ``z`` as there."""
    for i in range(x.shape[0]):
        sos_step(coef, z, x[i], y[i])


def sos_coefficients(sos: NDArray[np.float64]) -> NDArray[np.float64]:
    """``b0, b1, b2, a1, a2`` of each section (sections, 5), for :func:`sos_step`."""
    sos = np.asarray(sos, dtype=float)
    return np.ascontiguousarray(sos[:, [0, 1, 2, 4, 5]])


def sos_initial_state(sos: NDArray[np.float64], x0: NDArray[np.float64]) -> NDArray[np.float64]:
    """The steady state for the first sample ``x0`` (C,): (sections, 2, C), as :func:`sosfilt_state` starts."""
    return _signal().sosfilt_zi(sos)[:, :, None] * np.asarray(x0, dtype=float)[None, None, :]


class SosStream:
    """The same filter as :func:`sosfilt_batch`, one sample of ``C`` channels at a time:
    :func:`sos_step` (compiled unless numba is off or missing, then the same source as Python)."""

    __slots__ = ("_sos", "_coef", "_state", "_step", "_x", "_y")

    def __init__(self, sos: NDArray[np.float64], *, expected_samples: int | None = None):
        self._sos = np.asarray(sos, dtype=float)
        self._coef = sos_coefficients(sos)
        self._step = sos_step.function(expected_samples)
        self._state: NDArray[np.float64] | None = None
        # load (or compile) the step now, on scratch arrays, not at the first sample of a live run
        self._step(self._coef, np.zeros((len(self._coef), 2, 6)), np.zeros(6), np.empty(6))

    def reset(self) -> None:
        """Forget the state; the next sample starts the filter again in steady state."""
        self._state = None

    def __call__(self, x: list[float]) -> list[float]:
        """Filter one sample (a sequence of ``C`` floats); returns the filtered sample."""
        xa = np.array(x, dtype=float)
        if self._state is None:
            self._state = sos_initial_state(self._sos, xa)
            self._y = np.empty(len(xa))
        self._step(self._coef, self._state, xa, self._y)
        return self._y.tolist()
