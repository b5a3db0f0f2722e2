"""Causal low-pass filtering of the wrench.

A Butterworth filter from :func:`scipy.signal.butter` in second-order sections. The batch
path runs :func:`scipy.signal.sosfilt`; the streaming path carries the same state
sample by sample with the same transposed direct-form II recurrence in plain floats,
because one ``sosfilt`` call per sample costs ~60 µs in CPython, three times the whole
per-sample budget. Both start from the steady state for the first sample
(:func:`scipy.signal.sosfilt_zi`), so the filter has no start-up transient, and agree to
rounding (tested).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["lowpass_sos", "noise_gain", "sosfilt_batch", "SosStream"]


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
    signal = _signal()
    if zi is None:
        zi = signal.sosfilt_zi(sos)[:, :, None] * x[0][None, None, :]
    return signal.sosfilt(sos, x, axis=0, zi=zi)


class SosStream:
    """The same filter as :func:`sosfilt_batch`, one sample of ``C`` channels at a time.

    Transposed direct-form II per section, the recurrence scipy's ``sosfilt`` uses, written
    out for one and two sections (the 2nd- and 4th-order low-pass) and looped for more.
    """

    __slots__ = ("_coef", "_zi0", "_state")

    def __init__(self, sos: NDArray[np.float64]):
        # b0, b1, b2, a1, a2 of each section (a0 = 1)
        self._coef = [(float(r[0]), float(r[1]), float(r[2]), float(r[4]), float(r[5])) for r in np.asarray(sos)]
        self._zi0 = [tuple(float(v) for v in row) for row in _signal().sosfilt_zi(sos)]
        self._state: list[list[float]] | None = None

    def reset(self) -> None:
        """Forget the state; the next sample starts the filter again in steady state."""
        self._state = None

    def __call__(self, x: list[float]) -> list[float]:
        """Filter one sample (a sequence of ``C`` floats); returns the filtered sample."""
        state = self._state
        if state is None:  # the state of each channel's sections, channel after channel
            state = self._state = [[z0 * xc, z1 * xc] for xc in x for (z0, z1) in self._zi0]
        coef = self._coef
        out = []
        if len(coef) == 1:
            b0, b1, b2, a1, a2 = coef[0]
            for xc, z in zip(x, state):
                y = b0 * xc + z[0]
                z[0] = b1 * xc - a1 * y + z[1]
                z[1] = b2 * xc - a2 * y
                out.append(y)
            return out
        it = iter(state)
        if len(coef) == 2:
            (b0, b1, b2, a1, a2), (c0, c1, c2, d1, d2) = coef
            for xc, z, w in zip(x, it, it):
                y = b0 * xc + z[0]
                z[0] = b1 * xc - a1 * y + z[1]
                z[1] = b2 * xc - a2 * y
                u = c0 * y + w[0]
                w[0] = c1 * y - d1 * u + w[1]
                w[1] = c2 * y - d2 * u
                out.append(u)
            return out
        for xc in x:
            for (b0, b1, b2, a1, a2), z in zip(coef, it):  # this channel's sections
                y = b0 * xc + z[0]
                z[0] = b1 * xc - a1 * y + z[1]
                z[1] = b2 * xc - a2 * y
                xc = y
            out.append(xc)
        return out
