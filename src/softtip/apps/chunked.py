"""A log larger than memory, estimated piece by piece with the bits of the one-shot run.

:func:`estimate_pieces` takes a log as an iterator of row blocks (``softtip.io.tables.iter_log``
reads CSV and Parquet that way) and yields :class:`~softtip.Estimates` for consecutive
pieces of it. A piece ends only where the estimator is out of contact: no contact pending
or held, the drift following the untouched wrench. Everything a contact accumulates (latch,
evidence windows, depth, joint window) is reset there, so what crosses the cut is small and
carried exactly (:class:`softtip.estimator.batch.Carry`): the tare's bias, the low-pass
filter's state, the contact tracker's drift average and hysteresis, the contact count. Each
piece is then the one-shot run's output for its samples, to the bit.

A piece holds at least ``rows`` samples, unless the log ends first, and more when a contact
(or a pending one) lasts past them: a contact longer than ``rows`` samples makes its piece
as long as the contact. The first piece holds the whole tare.

Two things are taken from the first block rather than the whole log (identical for a log
sampled at a constant rate): the sample rate a low-pass filter is designed for, when
``config.sample_rate`` is not given (the median step of the first block's stamps).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from softtip.core.filtering import lowpass_sos, sosfilt_state
from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.estimator.batch import Carry, estimate, infer_rate, validate_log
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.contact import track_contacts
from softtip.estimator.depth import resolve_depth
from softtip.estimator.measure import effective_noise
from softtip.estimator.results import Estimates
from softtip.estimator.tare import noise_in_use, tare_log

__all__ = ["DEFAULT_PIECE_ROWS", "estimate_pieces"]

#: Samples per piece unless a contact makes it longer (a peak of ~0.4 GB with the default pipeline).
DEFAULT_PIECE_ROWS = 1 << 17

Block = tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any]]


def estimate_pieces(
    blocks: Iterable[Block],
    tip: Fingertip | str = "murakami2006",
    config: EstimatorConfig | None = None,
    rows: int = DEFAULT_PIECE_ROWS,
) -> Iterator[tuple[Estimates, dict[str, Any]]]:
    """Estimate a log given block by block; yield each piece's estimates and extra columns.

    Parameters
    ----------
    blocks : iterable of (t, wrench, extra)
        Consecutive rows of one log: ``t`` (k,) s, ``wrench`` (k, 6) N and N·m (SI,
        sensor frame), ``extra`` a mapping of column name to (k,) values (numpy arrays).
        Time must not go back, within or across blocks.
    tip : Fingertip or str
    config : EstimatorConfig, optional
    rows : int
        Samples per piece (at least; see the module's notes), ≥ 1.

    Yields
    ------
    (Estimates, dict)
        A piece's estimates (``contact_id`` counts on across pieces) and its rows of the
        extra columns.
    """
    if rows < 1:
        raise ValueError(f"rows = {rows}; expected at least 1")
    tip = load_fingertip(tip)
    config = resolve_depth(config or EstimatorConfig(), tip)
    carry = Carry()
    t_buf: list[NDArray] = []
    w_buf: list[NDArray] = []
    x_buf: dict[str, list[NDArray]] = {}
    held = 0
    last_t = -np.inf
    for t, w, extra in blocks:
        t, w = validate_log(t, w)
        if len(t) and t[0] < last_t:
            raise ValueError(f"time must not go back: {t[0]!r} s follows {last_t!r} s across blocks")
        if not len(t):
            continue
        last_t = float(t[-1])
        if config.lowpass_hz is not None and config.sample_rate is None:
            config = dataclasses.replace(config, sample_rate=infer_rate(t))
        t_buf.append(t)
        w_buf.append(w)
        for name, values in extra.items():
            x_buf.setdefault(name, []).append(np.asarray(values))
        held += len(t)
        while held >= rows:
            tt, ww = _joined(t_buf), _joined(w_buf)
            cut = _cut(tt, ww, tip, config, carry, rows)
            if cut is None:
                break  # a contact goes on past the rows held: read more
            xx = {k: _joined(v) for k, v in x_buf.items()}
            yield _piece(tt[:cut], ww[:cut], tip, config, carry), {k: v[:cut] for k, v in xx.items()}
            t_buf, w_buf = [tt[cut:]], [ww[cut:]]
            x_buf = {k: [v[cut:]] for k, v in xx.items()}
            held = len(tt) - cut
    if held:
        tt, ww = _joined(t_buf), _joined(w_buf)
        yield _piece(tt, ww, tip, config, carry), {k: _joined(v) for k, v in x_buf.items()}


def _joined(parts: list[NDArray]) -> NDArray:
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _piece(t: NDArray, w: NDArray, tip: Fingertip, config: EstimatorConfig, carry: Carry) -> Estimates:
    import warnings

    from softtip.estimator.results import EstimatorWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)  # they are in Estimates.warnings
        return estimate(t, w, tip, config, carry=carry)


def _cut(t: NDArray, w: NDArray, tip: Fingertip, config: EstimatorConfig, carry: Carry, rows: int) -> int | None:
    """Where the held samples may be cut (the first sample of the next piece): the first
    sample at or after ``rows``, and after the tare, at which the estimator, run from
    ``carry``, is out of contact with nothing pending and the drift following. ``None``: no
    such sample yet (a contact goes on past the samples held)."""
    later = carry.tare is not None
    if later:
        bias, start, report = carry.tare.bias, 0, carry.tare
    else:
        bias, taring, report = tare_log(t, w, config)
        start = int(np.count_nonzero(taring))
        if not np.all(np.isfinite(bias)):
            return None  # still taring
    x = w - bias
    sos = None
    if config.lowpass_hz is not None:
        sos = lowpass_sos(config.lowpass_hz, config.sample_rate, config.lowpass_order)
        x, _ = sosfilt_state(sos, x, carry.zi if later else None)
    noise = effective_noise(noise_in_use(config, report), sos)
    ct = track_contacts(t, x, start, config, noise, carry.track if later else None)
    free = ~ct.busy
    free[: max(start + 1, rows)] = False
    idx = np.flatnonzero(free)
    return int(idx[0]) if len(idx) else None
