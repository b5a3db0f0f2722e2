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

__all__ = ["point_moves_kernel", "vote_kernel", "window_sums_kernel"]


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
