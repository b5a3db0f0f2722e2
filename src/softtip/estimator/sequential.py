"""The sequential parts of the batch stages as single-pass loops, compiled with numba.

Each kernel does, over a whole log in one pass, what the stage's numpy path does segment
by segment, with the same floating-point operations in the same order as the streaming
class (running sums restarted at segment starts, window sums as differences of running
sums), so the results are the same to the last bit. Compiled on first use
(:mod:`softtip.core._jit`); callers fall back to their numpy paths when it is disabled.
"""

from __future__ import annotations

import numpy as np

from softtip.core._jit import lazy_jit

__all__ = ["contact_window_sums_kernel", "point_moves_kernel", "running_best_kernel", "track_kernel", "vote_kernel",
           "window_sums_kernel"]


@lazy_jit
def point_moves_kernel(begin, located, px, py, pz, distance2, out):  # pragma: no cover - compiled
    """``out``: ``begin`` with a new segment wherever the located contact point ``p`` has
    moved farther than ``sqrt(distance2)`` (m) from the first located point of its segment.

    ``begin``, ``located`` (N,) bool; ``px, py, pz`` (N,) m; ``out`` (N,) bool, written.
    """
    have = False
    ax = ay = az = 0.0
    for i in range(begin.shape[0]):
        b = begin[i]
        out[i] = b
        if b:
            have = False
        if located[i]:
            if not have:
                ax, ay, az = px[i], py[i], pz[i]
                have = True
            else:
                dx, dy, dz = px[i] - ax, py[i] - ay, pz[i] - az
                if dx * dx + dy * dy + dz * dz > distance2:
                    out[i] = True
                    ax, ay, az = px[i], py[i], pz[i]
    return out


@lazy_jit
def window_sums_kernel(t, located, begin, prods, window, lo, hi, cum, cum_first, state, sums, count):  # pragma: no cover
    """Sums of ``prods`` over a sliding window of the located samples of each segment, for
    the samples ``lo .. hi − 1`` (blocks in order, the state carried from one to the next).

    The window of located sample ``k`` is the located samples ``i`` of its segment (a new
    one at every ``begin``) with ``t_i > t_k − window``. Its sums are ``C_k − C_j``, ``C``
    the running sums from the segment's start (the stream's order of additions) and ``j``
    the window's first sample.

    Parameters
    ----------
    t : (N,) s, non-decreasing
    located, begin : (N,) bool
    prods : (M, N) float
    window : float, s
    lo, hi : int
        The block.
    cum, cum_first : (M,) float
        Running sums to the current sample and to the window's first (zeros at ``lo = 0``).
    state : (3,) int
        The window's first sample, and the located samples of the segment so far and before
        the window's first (zeros at ``lo = 0``).
    sums : (M, hi − lo) float
        Written (NaN at samples not located).
    count : (hi − lo,) float
        Samples in the window, written (NaN at samples not located).
    """
    m = prods.shape[0]
    j, n_in, n_out = state[0], state[1], state[2]
    for k in range(lo, hi):
        b = k - lo
        if begin[k]:
            for q in range(m):
                cum[q] = 0.0
                cum_first[q] = 0.0
            j = k
            n_in = 0
            n_out = 0
        if not located[k]:
            for q in range(m):
                sums[q, b] = np.nan
            count[b] = np.nan
            continue
        for q in range(m):
            cum[q] += prods[q, k]
        n_in += 1
        start = t[k] - window
        while j <= k:
            if located[j]:
                if t[j] > start:
                    break
                for q in range(m):
                    cum_first[q] += prods[q, j]
                n_out += 1
            j += 1
        for q in range(m):
            sums[q, b] = cum[q] - cum_first[q]
        count[b] = n_in - n_out
    state[0], state[1], state[2] = j, n_in, n_out
    return count


@lazy_jit
def contact_window_sums_kernel(onset, has, prods, k, first, sums):  # pragma: no cover - compiled
    """Sums of ``prods`` over the samples ``first[q] .. k[q]`` (inclusive) of one contact,
    as differences of running sums from the contact's onset (adding 0 at samples without
    ``has``, as the numpy path's masked cumulative sums).

    ``onset``, ``has`` (N,) bool; ``prods`` (M, N) float; ``k``, ``first`` (Q,) int,
    non-decreasing, each pair within one contact; ``sums`` (M, Q) float, written.
    """
    m = prods.shape[0]
    cum = np.zeros(m)
    cum_first = np.zeros(m)
    i = 0  # next sample to add to cum
    j = 0  # next sample to add to cum_first
    for q in range(k.shape[0]):
        while i <= k[q]:
            if onset[i]:
                for r in range(m):
                    cum[r] = 0.0
                    cum_first[r] = 0.0
                j = i
            h = has[i]
            for r in range(m):
                cum[r] += prods[r, i] if h else 0.0
            i += 1
        while j < first[q]:
            h = has[j]
            for r in range(m):
                cum_first[r] += prods[r, j] if h else 0.0
            j += 1
        for r in range(m):
            sums[r, q] = cum[r] - cum_first[r]
    return sums


@lazy_jit
def running_best_kernel(group, key, held):  # pragma: no cover - compiled
    """``held[q]``: the index of the smallest ``key`` so far within ``group[q]``'s run (a new
    one replaces it only when strictly smaller; -1 before any finite one).

    ``group`` (Q,) int, ``key`` (Q,) float, ``held`` (Q,) int, written.
    """
    best = np.inf
    cur = -1
    for q in range(key.shape[0]):
        if q == 0 or group[q] != group[q - 1]:
            best = np.inf
            cur = -1
        if key[q] < best:
            best = key[q]
            cur = q
        held[q] = cur
    return held


@lazy_jit
def vote_kernel(t, located, seg_start, side, window, share, out):  # pragma: no cover - compiled
    """``out``: the vote of each located sample (see :func:`softtip.estimator.evidence._vote`):
    1 or 0 when more than ``share`` of the located samples of its segment with
    ``t_j > t − window`` (and itself) are on that side, else −1.

    ``t`` (N,) s non-decreasing; ``located`` (N,) bool; ``seg_start`` (N,) int, the index of
    each sample's segment start; ``side`` (N,) int (1, 0, −1); ``out`` (N,) int, written
    (−1 where not located). One pass, a window of located samples between two pointers.
    """
    n = t.shape[0]
    left = 0  # the window's first located sample
    above = below = m = 0
    seg = -1
    for i in range(n):
        out[i] = -1
        if not located[i]:
            continue
        if seg_start[i] != seg:  # a new segment: an empty window
            seg = seg_start[i]
            left = i
            above = below = m = 0
        m += 1
        if side[i] == 1:
            above += 1
        elif side[i] == 0:
            below += 1
        start = t[i] - window
        while left < i and (not located[left] or t[left] <= start):
            if located[left]:
                m -= 1
                if side[left] == 1:
                    above -= 1
                elif side[left] == 0:
                    below -= 1
            left += 1
        if above > share * m:
            out[i] = 1
        elif below > share * m:
            out[i] = 0
    return out


@lazy_jit
def track_kernel(t, dt, x, alpha, start, on, off, min_dur, blk, tiny, avg, iavg, cid, busy, drift, y):  # pragma: no cover
    """Contacts and drift of :func:`softtip.estimator.contact.track_contacts` (``drift_tracking``
    on) in one pass: per sample what the numpy path does with running products and sums
    over chunks of untouched samples (the same operations in the same order).

    Parameters
    ----------
    t, dt, alpha : (N,) float
        Times (s), intervals (s) and drift weights.
    x : (N, 6) float
        The tared wrench.
    start : int
        First sample tracked.
    on, off : float
        Onset and release thresholds, N.
    min_dur : float
        Minimum contact duration, s.
    blk : int
        Samples per block of the drift average.
    tiny : float
        The block also ends once its product of ``(1 − α)`` falls below this.
    avg : (19,) float
        The drift average's state, read and written: the drift ``b`` (0:6), the open block's
        start ``b0`` (6:12), its sums (12:18) and product (18).
    iavg : (3,) int
        Read and written: the block is open (0/1), its samples, the contacts so far.
    cid : (N,) int, busy : (N,) bool, drift, y : (N, 6) float
        Written from ``start`` on: contact numbers, samples pending or held, the drift
        before each sample and the wrench minus it.
    """
    n = t.shape[0]
    b = avg[0:6].copy()
    b0 = avg[6:12].copy()
    acc = avg[12:18].copy()
    p = avg[18]
    is_open, count, contacts = iavg[0], iavg[1], iavg[2]
    after = np.empty(6)
    i = start
    while i < n:
        dx, dy, dz = x[i, 0] - b[0], x[i, 1] - b[1], x[i, 2] - b[2]
        if np.sqrt(dx * dx + dy * dy + dz * dz) < on:  # untouched: the average follows
            if not is_open:
                for q in range(6):
                    b0[q] = b[q]
                    acc[q] = 0.0
                p, count, is_open = 1.0, 0, 1
            for q in range(6):
                drift[i, q] = b[q]
                y[i, q] = x[i, q] - b[q]
            p = p * (1.0 - alpha[i])
            w = alpha[i] / p
            for q in range(6):
                acc[q] = acc[q] + w * x[i, q]
                after[q] = p * (b0[q] + acc[q])
            for q in range(6):
                b[q] = after[q]
            count += 1
            if count >= blk or p < tiny:
                is_open = 0
            i += 1
            continue
        # onset at j: the block ends, the drift is held until the release
        is_open = 0
        j = i
        m = j + 1
        while m < n:
            dx, dy, dz = x[m, 0] - b[0], x[m, 1] - b[1], x[m, 2] - b[2]
            if np.sqrt(dx * dx + dy * dy + dz * dz) < off:
                break
            m += 1
        first = -1
        for k in range(j, m):
            for q in range(6):
                drift[k, q] = b[q]
                y[k, q] = x[k, q] - b[q]
            busy[k] = True
            if first < 0 and (t[k] - t[j]) + dt[k] >= min_dur:
                first = k
        if first >= 0:
            contacts += 1
            for k in range(first, m):
                cid[k] = contacts
        i = m
    avg[0:6] = b
    avg[6:12] = b0
    avg[12:18] = acc
    avg[18] = p
    iavg[0], iavg[1], iavg[2] = is_open, count, contacts
    return contacts
