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

__all__ = ["latch_scan_kernel"]


@lazy_jit
def latch_scan_kernel(begin, contact, t, f_norm, valid, rx, ry, rz, lo, hi, stall, n_fallback,
                      n_win, sum_win, n_fb, sum_fb, rising, seg_end, seg_fixed, seg_total, seg_stop):  # pragma: no cover
    """The running quantities of the latch (:func:`softtip.estimator.latch.latch_points`)
    for every segment (a new one at every ``begin`` within ``contact``) in one pass.

    Per sample in contact: ``rising`` (before the first rise ends: ``|f| > hi`` or no new
    maximum for ``stall`` s), the count and running sums of the soft-finger solutions inside
    the light-force window while rising (``n_win``, ``sum_win`` (3, N)) and of the first
    ``n_fallback`` valid ones (``n_fb``, ``sum_fb``). Per segment: ``seg_end`` the sample
    ending the rise (or the segment's stop), ``seg_total`` the window samples of the rise and
    ``seg_fixed`` the sample from which the latch is fixed (after it, the latch is held;
    ``seg_stop`` when never), ``seg_stop`` one past its last sample.
    """
    n = t.shape[0]
    s = -1
    start = 0
    open_ = False
    over = False
    peak = -np.inf
    t_pk = 0.0
    nw = 0
    nv = 0
    nf = 0
    wx = wy = wz = 0.0
    fx = fy = fz = 0.0
    fixed_fb = -1
    for i in range(n + 1):
        stop = i == n or not contact[i] or begin[i]
        if open_ and stop:  # close segment s at i
            end = seg_end[s] if over else i
            seg_end[s] = end
            total = n_win[end - 1] if end > start else 0
            seg_total[s] = total
            seg_stop[s] = i
            if total > 0:
                seg_fixed[s] = end
            else:
                seg_fixed[s] = fixed_fb if fixed_fb >= 0 else i
            open_ = False
        if i == n or not contact[i]:
            continue
        if begin[i]:
            s += 1
            start = i
            open_ = True
            over = False
            peak = -np.inf
            t_pk = t[i]
            nw = 0
            nv = 0
            nf = 0
            wx = wy = wz = 0.0
            fx = fy = fz = 0.0
            fixed_fb = -1
        f = f_norm[i]
        if f > peak:
            peak = f
            t_pk = t[i]
        if not over and (f > hi or t[i] - t_pk > stall):
            over = True
            seg_end[s] = i
        rising[i] = not over
        ok = valid[i]
        win = (not over) and lo <= f and f <= hi and ok
        if win:
            nw += 1
        wx += rx[i] if win else 0.0
        wy += ry[i] if win else 0.0
        wz += rz[i] if win else 0.0
        n_win[i] = nw
        sum_win[0, i] = wx
        sum_win[1, i] = wy
        sum_win[2, i] = wz
        if ok:
            nv += 1
        fb = ok and nv <= n_fallback
        if fb:
            nf += 1
        fx += rx[i] if fb else 0.0
        fy += ry[i] if fb else 0.0
        fz += rz[i] if fb else 0.0
        n_fb[i] = nf
        sum_fb[0, i] = fx
        sum_fb[1, i] = fy
        sum_fb[2, i] = fz
        if over and fixed_fb < 0 and nf >= n_fallback:
            fixed_fb = i
    return s + 1
