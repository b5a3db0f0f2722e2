"""The batch pipeline after the sequential stages, as compiled loops over the log: :func:`fused_columns`.

:func:`~softtip.estimator.batch.estimate` runs the tare, the low-pass filter and the contact
tracking first (their state crosses a cut of the log); what follows is per contact, and for
the closed-form fingertips (:class:`~softtip.core.fingertip.Sphere`,
:class:`~softtip.core.fingertip.Capsule`, :class:`~softtip.core.fingertip.Ellipsoid`) it runs
here in compiled loops that call, per sample, the same step functions the stream
(:class:`~softtip.estimator.stream.Estimator`) calls, in the stream's order:

1. :func:`points_run`: the soft-finger solution (the shape's own kernel, compiled), the latch
   (:func:`~softtip.estimator.latch.latch_step`, the mean put back on the skin at once, as the
   stream does) or the tracked point;
2. in ``line-fit`` mode, :func:`line_fit_run`: the line-fit stage's anchor, window and hold
   steps with the window's solve (:func:`~softtip.core.line_fit.line_fit_solve_kernel`, the
   fingertip a :class:`ShapeRecord`) per sample, as the stream's
   :class:`~softtip.estimator.line_fit.LineFitTracker`; with a skin law the stage's batch form
   :func:`~softtip.estimator.line_fit.line_fit_points` (its solve vectorised);
3. :func:`tail_run`: the normal and the tangent frame (once per contact point, as the stream's
   :class:`~softtip.estimator.floats.PointGeometry`), then :func:`located_step`, which the
   stream calls too: the depth (:func:`~softtip.estimator.depth.depth_step`), the measurement
   (:func:`~softtip.estimator.measure.measure_kernel`), the line evidence
   (:func:`~softtip.estimator.evidence.evidence_step`); every output column written once, NaN
   where the sample has no value (no separate blanking pass).

Each step is the stage's one source; this module only sequences them (no stage is written
again), for the stream too: :func:`sample_step` is one sample in contact, the contact tracking's
step then :func:`latch_point` (which :func:`points_run` calls) and :func:`located_step`. The results are the staged path's to the bit (the stream's, which the staged batch
equals): the kernels do the same IEEE operations compiled as in numpy, and a line-fit window
statistic that is NaN (the square root of a negative number) is +NaN on both paths, as in the
stream (the staged path rewrites numpy's −NaN), so a written log's bytes do not depend on the
path. Other fingertips (a mesh,
an implicit surface, a mounted shape), a skin law whose exponent is not 2 (numpy's power,
which compiled code cannot reproduce to the bit) and a run whose steps are not compiled (a
short log in a process without numba, ``SOFTTIP_NUMBA=0``) take the staged path of
:mod:`softtip.estimator.batch`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core import _xp_scalar as XS
from softtip.core._blocks import ring_capacity, ring_rows
from softtip.core._jit import jitable, lazy_jit, use_numba
from softtip.core.depth import square_depth_kernel
from softtip.core.fingertip import (
    Capsule,
    Ellipsoid,
    Fingertip,
    Sphere,
    _capsule_kernel,
    _ellipsoid_kernel,
    capsule_normal_kernel,
    capsule_project_kernel,
    ellipsoid_normal_kernel,
    ellipsoid_project_kernel,
    sphere_normal_kernel,
    sphere_project_kernel,
)
from softtip.core.line_fit import N_SUMS, line_fit_products, line_fit_solve_kernel
from softtip.core.noise import SensorNoise, noise_moment_part, noise_variances
from softtip.core.shape import SoftFinger, sphere_kernel
from softtip.core.spin import spin_torque_kernel, tangent_frame_kernel
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.contact import contact_step
from softtip.estimator.depth import (
    RING_COLUMNS,
    depth_gap,
    depth_params,
    depth_start_contact,
    depth_step,
    new_depth_state,
)
from softtip.estimator.evidence import (
    evidence_params,
    evidence_start,
    evidence_step,
    new_evidence_state,
    twist_curvature,
)
from softtip.estimator.latch import (
    _HAD,
    _LX,
    _LY,
    _LZ,
    FIX,
    HELD,
    MEAN,
    SOFT,
    latch_hold,
    latch_keeps,
    latch_params,
    latch_step,
    new_latch_state,
)
from softtip.estimator.latch import (
    _N_PARAMS as _N_LATCH_PARAMS,
)
from softtip.estimator.line_fit import (
    _start_anchor,
    _start_window,
    line_fit_accept,
    line_fit_anchor_step,
    line_fit_hold_step,
    line_fit_points,
    line_fit_start_segment,
    line_fit_window_step,
    new_line_fit_state,
)
from softtip.estimator.measure import measure_kernel

__all__ = [
    "ShapeRecord", "shape_record", "soft_finger_step", "soft_finger_function", "points_run", "line_fit_run",
    "located_step", "held_record", "latch_point", "sample_setup", "sample_step", "STEP_NOT_DONE", "STEP_HELD", "STEP_POINT",
    "STEP_NO_POINT", "NO_SHAPE", "tail_run", "fused_columns",
]  # fmt: skip

#: Shape codes of :func:`shape_record`.
SPHERE, CAPSULE, ELLIPSOID = 0, 1, 2
#: :func:`sample_setup`'s shape code for a fingertip without a :func:`shape_record`: only a held
#: latch's samples are done in :func:`sample_step`.
NO_SHAPE = -1
#: Contact-point modes of :func:`points_run`.
TRACK, LATCH = 0, 1
#: Depth modes of :func:`tail_run`.
DEPTH_OFF, DEPTH_LAW, DEPTH_ONLINE = 0, 1, 2
_NAN = math.nan
#: State codes (:data:`softtip.estimator.results.STATES`).
_NONE_CODE, _LINE_CODE = 0, 2


class ShapeRecord(NamedTuple):
    """A closed-form fingertip as compiled code takes it (:func:`shape_record`): its shape code and
    parameters, with the :class:`~softtip.core.shape.Fingertip` kernels that
    :func:`~softtip.core.line_fit.line_fit_solve_kernel` calls (in compiled code too, by
    :func:`_register_methods`)."""

    kind: int  #: :data:`SPHERE`, :data:`CAPSULE` or :data:`ELLIPSOID`
    sp: NDArray[np.float64]  #: sphere (radius, centre), capsule (radius, length, axis offset), ellipsoid (semi-axes, centre), m

    def _normal_kernel(self, x, y, z, xp):
        return _normal(self.kind, self.sp, x, y, z, xp)

    def _project_kernel(self, x, y, z, xp):
        return _project(self.kind, self.sp, x, y, z, xp)


class NoiseRecord(NamedTuple):
    """A :class:`~softtip.core.noise.SensorNoise` as compiled code reads it (standard deviations, N and N·m)."""

    force_std: tuple[float, float, float]
    moment_std: tuple[float, float, float]


class AcceptRecord(NamedTuple):
    """The limits of :func:`~softtip.estimator.line_fit.line_fit_accept`, as compiled code reads them."""

    line_fit_max_angle_std: float
    line_fit_max_offset_std: float
    line_fit_max_residual: float


def shape_record(tip: Fingertip) -> ShapeRecord | None:
    """The :class:`ShapeRecord` of a closed-form fingertip: a sphere ``(radius, centre)``, a capsule
    ``(radius, length, axis offset)``, an ellipsoid ``(semi-axes, centre)`` (m); None for any
    other (subclasses included)."""
    if type(tip) is Sphere:
        return ShapeRecord(SPHERE, np.array([tip.radius, *tip.center], dtype=float))
    if type(tip) is Capsule:
        return ShapeRecord(CAPSULE, np.array([tip.radius, tip.length, *tip.axis_offset], dtype=float))
    if type(tip) is Ellipsoid:
        return ShapeRecord(ELLIPSOID, np.array([*tip.semi_axes, *tip.center], dtype=float))
    return None


_REGISTERED: list[bool] = []


def _register_methods() -> None:
    """Let compiled code call a :class:`ShapeRecord`'s ``_normal_kernel`` and ``_project_kernel``
    (numba's ``overload_method``), once, before :func:`line_fit_run` is compiled."""
    if _REGISTERED:
        return
    from numba.core import types
    from numba.extending import overload_method

    @overload_method(types.NamedTuple, "_normal_kernel")
    def _normal_method(tip, x, y, z, xp):
        if getattr(tip, "instance_class", None) is ShapeRecord:
            return lambda tip, x, y, z, xp: _normal(tip.kind, tip.sp, x, y, z, xp)
        return None

    @overload_method(types.NamedTuple, "_project_kernel")
    def _project_method(tip, x, y, z, xp):
        if getattr(tip, "instance_class", None) is ShapeRecord:
            return lambda tip, x, y, z, xp: _project(tip.kind, tip.sp, x, y, z, xp)
        return None

    _REGISTERED.append(True)


@jitable
def _contact(kind, sp, fx, fy, fz, mx, my, mz, xp):
    """The shape's soft-finger solution (``Fingertip._contact_kernel``) on floats (``xp``: :mod:`softtip.core._xp_scalar`)."""
    if kind == SPHERE:
        return sphere_kernel(fx, fy, fz, mx, my, mz, sp[0], sp[1], sp[2], sp[3], xp)
    if kind == CAPSULE:
        return _capsule_kernel(fx, fy, fz, mx, my, mz, sp[0], sp[1], sp[2], sp[3], xp)
    return _ellipsoid_kernel(fx, fy, fz, mx, my, mz, sp[0], sp[1], sp[2], sp[3], sp[4], sp[5], xp)


@lazy_jit(nogil=False)
def soft_finger_step(kind, sp, fx, fy, fz, mx, my, mz):  # pragma: no cover - compiled
    """:func:`_contact` of one sample, compiled: the stream's soft-finger solution on a
    closed-form fingertip (:func:`soft_finger_function`)."""
    return _contact(kind, sp, fx, fy, fz, mx, my, mz, XS)


def soft_finger_function(tip: Fingertip, expected_samples: int | None = None):
    """The soft-finger solution of one sample's six floats on ``tip`` (the 8-tuple of
    :func:`~softtip.core.location.contact_kernel`): a closed-form fingertip's kernel compiled
    (:func:`soft_finger_step`: :func:`_contact`, as :func:`points_run` calls it) when the steps are
    (:func:`~softtip.core._jit.lazy_jit`'s ``function``), else None (the tip's own, as Python)."""
    rec = shape_record(tip)
    step = soft_finger_step.function(expected_samples)
    if rec is None or step is soft_finger_step.python:
        return None
    kind, sp = rec
    return lambda fx, fy, fz, mx, my, mz: step(kind, sp, fx, fy, fz, mx, my, mz)


@jitable
def _normal(kind, sp, x, y, z, xp):
    """The shape's outward normal (``Fingertip._normal_kernel``) on floats."""
    if kind == SPHERE:
        return sphere_normal_kernel(x, y, z, sp[1], sp[2], sp[3], xp)
    if kind == CAPSULE:
        return capsule_normal_kernel(x, y, z, sp[1], sp[2], sp[3], xp)
    return ellipsoid_normal_kernel(x, y, z, sp[0], sp[1], sp[2], sp[3], sp[4], sp[5], xp)


@jitable
def _project(kind, sp, x, y, z, xp):
    """The shape's nearest skin point (``Fingertip._project_kernel``) on floats."""
    if kind == SPHERE:
        return sphere_project_kernel(x, y, z, sp[0], sp[1], sp[2], sp[3], xp)
    if kind == CAPSULE:
        return capsule_project_kernel(x, y, z, sp[0], sp[1], sp[2], sp[3], xp)
    return ellipsoid_project_kernel(x, y, z, sp[0], sp[1], sp[2], sp[3], sp[4], sp[5], xp)


@jitable
def latch_point(kind, sp, lstate, lparams, onset, t, f_norm, valid, rx, ry, rz):
    """The latch's step (:func:`~softtip.estimator.latch.latch_step`) of a sample in contact with
    its soft-finger solution ``valid, r`` (m), and the sample's point: the solution's, a mean
    put back on the skin (the shape's projection; a latch held when fixed) or the latch held;
    NaN without one. Returns ``(code, px, py, pz, latched, fallback, relatched, begin)``."""
    code, qx, qy, qz, lat, fb, rel, begin = latch_step(lstate, lparams, onset, t, f_norm, True, valid, rx, ry, rz)
    if code == SOFT:
        px, py, pz = rx, ry, rz
    elif code == MEAN or code == FIX:
        px, py, pz = _project(kind, sp, qx, qy, qz, XS)
        if code == FIX:
            latch_hold(lstate, px, py, pz)
    elif code == HELD:
        px, py, pz = lstate[_LX], lstate[_LY], lstate[_LZ]
    else:
        px = py = pz = _NAN
    return code, px, py, pz, lat, fb, rel, begin


@lazy_jit
def points_run(t, x, contact, kind, sp, mode, lparams, lstate, point, has, sc, sc_valid, latched, fallback,
               relatched):  # pragma: no cover - compiled
    """The contact point of every sample in contact, in one loop (the stream's order).

    ``t`` (N,) s, ``x`` (N, 6) the tared wrench, ``contact`` (N,) bool; ``kind``, ``sp`` the
    fingertip (:func:`shape_record`); ``mode`` :data:`TRACK` (the soft-finger point, its
    validity in ``has``) or :data:`LATCH` (:func:`~softtip.estimator.latch.latch_step` on
    ``lstate`` with ``lparams``, each mean put back on the skin when returned, a latch held
    when fixed). Written: ``point`` (N, 3) (NaN without one), ``has`` (N,) bool, ``sc`` (N, 7)
    the soft-finger solution (point, normal, σ; NaN out of contact or invalid in latch mode) and
    ``sc_valid`` (N,) its validity when they have N rows (line-fit and track mode), ``latched``, ``fallback``, ``relatched`` (N,) bool.
    """
    n = t.shape[0]
    keep = sc.shape[0] == n  # the soft-finger solutions are wanted (else sc, sc_valid are placeholders)
    for i in range(n):
        latched[i] = False
        fallback[i] = False
        relatched[i] = False
        if not contact[i]:
            for k in range(3):
                point[i, k] = _NAN
            has[i] = False
            if keep:
                for k in range(7):
                    sc[i, k] = _NAN
                sc_valid[i] = False
            continue
        fx, fy, fz, mx, my, mz = x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], x[i, 5]
        onset = i == 0 or not contact[i - 1]
        f_norm = math.sqrt(fx * fx + fy * fy + fz * fz)
        if mode == LATCH and not keep:
            # a latch held and no re-latch test due needs no soft-finger solution (as in the stream)
            code, qx, qy, qz, lat, fb, rel, _ = latch_step(lstate, lparams, onset, t[i], f_norm, False, False, 0.0,
                                                           0.0, 0.0)  # fmt: skip
            if code == HELD:
                px, py, pz = lstate[_LX], lstate[_LY], lstate[_LZ]
                point[i, 0], point[i, 1], point[i, 2] = px, py, pz
                has[i] = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
                latched[i] = lat
                fallback[i] = fb
                relatched[i] = rel
                continue
        rx, ry, rz, nx, ny, nz, sig, valid = _contact(kind, sp, fx, fy, fz, mx, my, mz, XS)
        if mode == TRACK:
            point[i, 0], point[i, 1], point[i, 2] = rx, ry, rz
            has[i] = valid
        elif not valid:
            rx = ry = rz = nx = ny = nz = sig = _NAN
        if keep:
            sc_valid[i] = valid
            sc[i, 0], sc[i, 1], sc[i, 2], sc[i, 3], sc[i, 4], sc[i, 5], sc[i, 6] = rx, ry, rz, nx, ny, nz, sig
        if mode == TRACK:
            continue
        _, px, py, pz, lat, fb, rel, _ = latch_point(kind, sp, lstate, lparams, onset, t[i], f_norm, valid, rx, ry, rz)
        point[i, 0], point[i, 1], point[i, 2] = px, py, pz
        has[i] = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
        latched[i] = lat
        fallback[i] = fb
        relatched[i] = rel


@lazy_jit
def line_fit_run(t, x, contact, relatched, sc, sc_valid, point, tip, noise, accept, lstate, ring, window, drift2,
                 iterations, corr, stats, moved, latched, fallback, joint_fb):  # pragma: no cover - compiled
    """The ``line-fit`` stage over a log in one loop: per sample in contact, as the stream's
    :class:`~softtip.estimator.line_fit.LineFitTracker` (no skin law), its anchor, window and hold
    steps with the window's solve (:func:`~softtip.core.line_fit.line_fit_solve_kernel` on the
    fingertip ``tip``, a :class:`ShapeRecord`) between them.

    ``sc`` (N, 7) and ``sc_valid`` the soft-finger solutions, ``point`` (N, 3) the latched points
    (where a window is held, its point written in place); ``noise`` a :class:`NoiseRecord`,
    ``accept`` an :class:`AcceptRecord`; ``lstate`` and ``ring`` the stage's state record and
    window ring; ``window`` (s), ``drift2`` (m²/s), ``iterations``, ``corr`` as in the stream.
    Written: ``stats`` (4, N) (conditioning, angle std, offset std, residual; NaN where none),
    ``moved``, ``joint_fb`` (N,) bool; ``latched`` and ``fallback`` cleared where moved.
    """
    prods, sums = np.empty(N_SUMS), np.empty(N_SUMS)
    for i in range(t.shape[0]):
        moved[i] = False
        joint_fb[i] = False
        for k in range(4):
            stats[k, i] = _NAN
        if not contact[i]:
            continue
        onset = i == 0 or not contact[i - 1]
        if onset:
            _start_anchor(lstate)
            _start_window(lstate)
        if onset or relatched[i]:  # a new first rise of the latch
            line_fit_start_segment(lstate, t[i])
        accepted, offset_std, jx, jy, jz = False, _NAN, _NAN, _NAN, _NAN
        if sc_valid[i]:
            ax, ay, az = line_fit_anchor_step(lstate, True, sc[i, 0], sc[i, 1], sc[i, 2])
            # line_fit_moment without a skin law: the moment about the anchor
            qx, qy, qz = spin_torque_kernel(x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], x[i, 5], ax, ay, az)
            pr = line_fit_products(x[i, 0], x[i, 1], x[i, 2], qx, qy, qz)
            for q in range(N_SUMS):
                prods[q] = pr[q]
            count = line_fit_window_step(lstate, ring, t[i], window, prods, sums)
            px, py, pz = point[i, 0], point[i, 1], point[i, 2]
            if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
                out = line_fit_solve_kernel(sums, float(count), px, py, pz, ax, ay, az, tip, iterations, noise, corr,
                                            XS)  # fmt: skip
                jx, jy, jz = out[0], out[1], out[2]
                stats[0, i], stats[1, i], stats[2, i], stats[3, i] = out[6], out[7], out[8], out[9]
                accepted = line_fit_accept(out[6], out[7], out[8], out[9], accept) and math.isfinite(jx + jy + jz)
                offset_std = out[8]
        _, mv, hx, hy, hz = line_fit_hold_step(lstate, t[i], accepted, offset_std, jx, jy, jz, drift2)
        moved[i] = mv
        joint_fb[i] = not mv
        if mv:
            point[i, 0], point[i, 1], point[i, 2] = hx, hy, hz
            latched[i] = False
            fallback[i] = False


@lazy_jit(nogil=False)
def located_step(t, fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, m1, m2,
                 sfx, sfy, sfz, depth_mode, d0, dparams, dstate, dring, eparams, wconst, estate, counts,
                 ring):  # fmt: skip
    """The depth, measurement and line evidence of a sample in contact at a finite contact point:
    one call per sample for the stream (:class:`~softtip.estimator.stream.Estimator`) and for
    :func:`tail_run`, the steps in one order.

    ``t`` s; the tared wrench ``fx … mz`` (N, N·m); the point ``p`` (m), its outward normal ``n``,
    its tangent frame ``e1, e2`` and moment-noise parts ``m1, m2``
    (:class:`~softtip.estimator.floats.PointGeometry`); the force noise's variances ``sfx, sfy,
    sfz`` (N²); ``depth_mode`` (:data:`DEPTH_OFF`, :data:`DEPTH_LAW`, :data:`DEPTH_ONLINE`) with
    the skin law's depth at the normal force ``d0`` (m) and the depth stage's ``dparams``,
    ``dstate``, ``dring`` (:func:`~softtip.estimator.depth.depth_step`; the ring with room for
    one more); the evidence stage's ``eparams``, ``wconst``, ``estate``, ``counts``, ``ring``
    (:func:`~softtip.estimator.evidence.evidence_step`; its ring with room for one more).

    Returns ``(located, depth, depth_std, from_data, sigma, hx, hy, hz, h_norm, h_std, state,
    evidence, dx, dy, dz, angle, angle_std, angle_noise_std, h_ratio, f_ratio)``: ``located``
    False (the force not pushing in; the depth stepped, nothing else, the rest NaN) or the
    measurement about ``p − depth · n`` and the evidence step's returns.
    """
    d = d_std = 0.0
    data = False
    if depth_mode == DEPTH_ONLINE:
        d, d_std, data = depth_step(dstate, dring, dparams, t, fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, d0)
    elif depth_mode == DEPTH_LAW:
        d = d0
    if not fx * nx + fy * ny + fz * nz < 0.0:  # not pushing
        return (False, d, d_std, data, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, 0, 0, _NAN, _NAN, _NAN, _NAN, _NAN,
                _NAN, _NAN, _NAN)  # fmt: skip
    # friction acts at r − δ n, inside the skin: the moment is taken about it
    ex, ey, ez = px - d * nx, py - d * ny, pz - d * nz
    sg, hx, hy, hz, hn, hs = measure_kernel(fx, fy, fz, mx, my, mz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z,
                                            e2x, e2y, e2z, m1, m2, sfx, sfy, sfz, d_std * d_std, XS)  # fmt: skip
    r = evidence_step(estate, counts, ring, eparams, wconst, t, px, py, pz, nx, ny, nz, e1x, e1y, e1z, e2x,
                      e2y, e2z, ex, ey, ez, hx, hy, hz, fx, fy, fz, hn, hs, sg)  # fmt: skip
    return True, d, d_std, data, sg, hx, hy, hz, hn, hs, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]


#: The entries of :func:`sample_step`'s ``held`` record (:func:`held_record`), where each starts:
#: the latch's keep window (:func:`~softtip.estimator.latch.latch_keeps`: low, high force, N;
#: squared distance, m²), the held point (m), its normal, tangent frame ``e1``, ``e2`` and
#: moment-noise parts ``m1, m2`` (:class:`~softtip.estimator.floats.PointGeometry`).
_H_WINDOW, _H_POINT, _H_NORMAL, _H_E1, _H_E2, _H_M = 0, 3, 6, 9, 12, 15
HELD_RECORD = 17  #: its length


def held_record(window, geo) -> NDArray[np.float64]:
    """:func:`sample_step`'s record of a held latch's point ``geo``
    (:class:`~softtip.estimator.floats.PointGeometry`); ``window`` the latch's keep window."""
    rec = np.array((
        *window, *geo.point, geo.nx, geo.ny, geo.nz, geo.e1x, geo.e1y, geo.e1z, geo.e2x, geo.e2y, geo.e2z, geo.m1, geo.m2,
    ), dtype=np.float64)  # fmt: skip
    assert rec.shape == (HELD_RECORD,)
    return rec


#: The entries of :func:`sample_step`'s ``setup`` record (:func:`sample_setup`), where each
#: starts: ``track`` (1.0 in ``track`` mode), the shape code (:data:`NO_SHAPE` for a fingertip
#: without a :func:`shape_record`), the noise's variances (fx … mz: N², (N·m)²), the skin law of
#: exponent 2 (stiffness N/m², cap m; zeros without one), the latch's parameters
#: (:func:`~softtip.estimator.latch.latch_params`), then the shape's parameters to the end.
_S_TRACK, _S_KIND, _S_VAR, _S_LAW, _S_LATCH = 0, 1, 2, 8, 10
_S_SHAPE = _S_LATCH + _N_LATCH_PARAMS


def sample_setup(track: bool, shape: ShapeRecord | None, variances, law, lparams) -> NDArray[np.float64]:
    """:func:`sample_step`'s record of what stays the same from sample to sample: ``track`` mode,
    the fingertip's :func:`shape_record` (None: no closed form), the noise's ``variances`` (6),
    the skin ``law`` (exponent 2) or None, the latch's parameter record ``lparams``. One array:
    a compiled call takes each argument apart, and an array is one."""
    kind, sp = (NO_SHAPE, ()) if shape is None else shape
    stiffness, cap = (law.stiffness, law.max_depth) if law is not None else (0.0, 0.0)
    setup = np.array((float(track), float(kind), *variances, stiffness, cap, *lparams, *sp), dtype=np.float64)
    assert setup.shape == (_S_SHAPE + len(sp),)
    return setup


#: :func:`sample_step`'s ``status``: the sample was not done there (the caller goes on from the
#: contact step with the stages in turn); done at the held latch; done at a point of the first
#: rise (or re-latch test, or ``track`` mode); in contact without a contact point.
STEP_NOT_DONE, STEP_HELD, STEP_POINT, STEP_NO_POINT = 0, 1, 2, 3


@lazy_jit(nogil=False)
def sample_step(cstate, cparams, t, dt, x0, x1, x2, x3, x4, x5, held, setup, lstate, depth_mode, dparams, dstate,
                dring, eparams, wconst, estate, counts, ring):  # fmt: skip
    """A stream sample after the low-pass filter, in one compiled call: the contact tracking's
    step (:func:`~softtip.estimator.contact.contact_step`) and, if the contact goes on (not its
    onset):

    * while a latch is held (``held``, :func:`held_record`; empty when none) and keeps its point
      (:func:`~softtip.estimator.latch.latch_keeps`: nearly every sample of a contact),
      :func:`located_step` at that point;
    * else, on a closed-form fingertip, the shape's soft-finger solution, the latch
      (:func:`latch_point` on its state ``lstate``; in ``track`` mode the solution's point and
      normal), the point's
      normal, tangent frame and moment-noise parts (as
      :class:`~softtip.estimator.floats.PointGeometry`) and :func:`located_step`.

    The stages' own steps in the stream's order (:class:`~softtip.estimator.stream.Estimator`,
    ``latch`` mode without the line fit, or ``track`` mode; a skin law of exponent 2 or none).
    ``setup`` is :func:`sample_setup` (the mode, the fingertip, the noise, the skin law, the
    latch's parameters); the depth and evidence records as for :func:`located_step` (their rings
    with room for one more).

    Returns ``(contact, status, code, point, normal, flags, located)``: the contact step's
    returns; :data:`STEP_NOT_DONE` … :data:`STEP_NO_POINT`; the latch's code
    (:data:`~softtip.estimator.latch.FIX`: a latch fixed at ``point``); the point (m) and its
    normal (NaN at a held latch: the caller has them); ``(latched, fallback, relatched, begin)``;
    :func:`located_step`'s returns (NaN unless done).
    """
    nan3 = (_NAN, _NAN, _NAN)
    none = (False, _NAN, _NAN, False, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, 0, 0, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN,
            _NAN, _NAN)  # fmt: skip
    c = contact_step(cstate, cparams, t, dt, x0, x1, x2, x3, x4, x5)
    if c[0] != 1:  # out of contact, or its onset
        return c, STEP_NOT_DONE, 0, nan3, nan3, (False, False, False, False), none
    fx, fy, fz, mx, my, mz = c[5], c[6], c[7], c[8], c[9], c[10]
    f_norm = math.sqrt(fx * fx + fy * fy + fz * fz)
    sfx, sfy, sfz = setup[_S_VAR], setup[_S_VAR + 1], setup[_S_VAR + 2]
    law_k, law_cap = setup[_S_LAW], setup[_S_LAW + 1]
    if held.shape[0] and latch_keeps(True, False, f_norm, held[_H_WINDOW], held[_H_WINDOW + 1], held[_H_WINDOW + 2]):
        nx, ny, nz = held[_H_NORMAL], held[_H_NORMAL + 1], held[_H_NORMAL + 2]
        d0 = 0.0
        if depth_mode != DEPTH_OFF:
            d0 = square_depth_kernel(-(fx * nx + fy * ny + fz * nz), law_k, law_cap, XS)
        r = located_step(
            t, fx, fy, fz, mx, my, mz, held[_H_POINT], held[_H_POINT + 1], held[_H_POINT + 2], nx, ny, nz,
            held[_H_E1], held[_H_E1 + 1], held[_H_E1 + 2], held[_H_E2], held[_H_E2 + 1], held[_H_E2 + 2],
            held[_H_M], held[_H_M + 1], sfx, sfy, sfz, depth_mode, d0, dparams, dstate, dring, eparams, wconst, estate, counts, ring,
        )  # fmt: skip
        return c, STEP_HELD, HELD, nan3, nan3, (True, False, False, False), r
    kind = int(setup[_S_KIND])
    if kind == NO_SHAPE:
        return c, STEP_NOT_DONE, 0, nan3, nan3, (False, False, False, False), none
    sp = setup[_S_SHAPE:]
    smx, smy, smz = setup[_S_VAR + 3], setup[_S_VAR + 4], setup[_S_VAR + 5]
    rx, ry, rz, qx, qy, qz, _, valid = _contact(kind, sp, fx, fy, fz, mx, my, mz, XS)
    code = 0
    lat = fb = rel = begin = False
    if setup[_S_TRACK] > 0.0:
        px, py, pz, nx, ny, nz = rx, ry, rz, qx, qy, qz
        has = valid
    else:
        lparams = setup[_S_LATCH:_S_SHAPE]
        code, px, py, pz, lat, fb, rel, begin = latch_point(kind, sp, lstate, lparams, False, t, f_norm, valid, rx, ry,
                                                            rz)  # fmt: skip
        if begin:  # a re-latch: a new segment of the line evidence
            evidence_start(estate, counts)
        has = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
        nx = ny = nz = _NAN
        if has:
            nx, ny, nz = _normal(kind, sp, px, py, pz, XS)
    flags = (lat, fb, rel, begin)
    if not has:
        if depth_mode == DEPTH_ONLINE:
            depth_gap(dstate)
        return c, STEP_NO_POINT, code, (px, py, pz), (nx, ny, nz), flags, none
    e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(nx, ny, nz, XS)
    m1 = noise_moment_part(e1x, e1y, e1z, smx, smy, smz)
    m2 = noise_moment_part(e2x, e2y, e2z, smx, smy, smz)
    d0 = 0.0
    if depth_mode != DEPTH_OFF:
        d0 = square_depth_kernel(-(fx * nx + fy * ny + fz * nz), law_k, law_cap, XS)
    r = located_step(t, fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, m1, m2, sfx,
                     sfy, sfz, depth_mode, d0, dparams, dstate, dring, eparams, wconst, estate, counts,
                     ring)  # fmt: skip
    return c, STEP_POINT, code, (px, py, pz), (nx, ny, nz), flags, r


@lazy_jit
def tail_run(t, x, drift, contact, taring, kind, sp, normal_from_tip, point, has, normal_in, relatched,
             depth_mode, law, dparams, noise_var, eparams, wconst, estate, counts, ring,
             latched, fallback, joint_fb, normal, sigma, h, h_norm, h_std, depth, depth_std, from_data,
             state, line_evidence, direction, angle, angle_std, angle_noise_std, h_ratio, f_ratio,
             pulling, stats, fill_stats):  # pragma: no cover - compiled
    """Normal, depth, measurement and line evidence of every sample, outputs written once.

    Inputs (N rows): ``t``; ``x`` (N, 6) the tared wrench and ``drift`` (N, 6) (both set to NaN
    in place where ``taring``); ``contact``; the fingertip ``kind``, ``sp``; ``point`` (N, 3)
    with ``has`` (the sample has a contact point) and, unless ``normal_from_tip``, the normal
    ``normal_in`` (N, 3) (track mode: the soft-finger one); ``relatched``. ``depth_mode``
    (:data:`DEPTH_OFF`, :data:`DEPTH_LAW`, :data:`DEPTH_ONLINE`) with ``law`` (stiffness N/m²,
    cap m; exponent 2) and ``dparams`` (:func:`~softtip.estimator.depth.depth_params`);
    ``noise_var`` the noise's variances (fx, fy, fz, mx, my, mz); the evidence stage's
    ``eparams``, ``wconst``, ``estate``, ``counts``, ``ring``
    (:func:`~softtip.estimator.evidence.new_evidence_state`).

    Outputs, where the sample is located (in contact, a point, the force pushing in): the
    normal, σ, ``h``, ``|h|``, ``h``'s noise level, the depth, its standard deviation and
    whether the data gave it, the state and evidence codes, the direction, its angle, standard
    deviation and noise share (NaN unless a line) and the window ratios; NaN (0, False)
    elsewhere. ``point``, ``latched``, ``fallback``, ``joint_fb`` and the line fit's ``stats``
    (4, N) are masked in place (``stats`` all NaN with ``fill_stats``); ``pulling`` is in
    contact and not located.
    """
    n = t.shape[0]
    dstate = new_depth_state()
    dring = np.empty((1, RING_COLUMNS))
    if depth_mode == DEPTH_ONLINE:
        dring = np.empty((ring_capacity(t, dparams[0]), RING_COLUMNS))
    sfx, sfy, sfz, smx, smy, smz = noise_var[0], noise_var[1], noise_var[2], noise_var[3], noise_var[4], noise_var[5]
    # the geometry of the last point (its normal, tangent frame): recomputed when the point changes
    lpx = lpy = lpz = _NAN
    nx = ny = nz = _NAN
    lnx = lny = lnz = _NAN
    e1x = e1y = e1z = e2x = e2y = e2z = m1 = m2 = _NAN
    for i in range(n):
        if taring[i]:
            for k in range(6):
                x[i, k] = _NAN
                drift[i, k] = _NAN
        onset = contact[i] and (i == 0 or not contact[i - 1])
        if onset or (relatched[i] and contact[i]):  # a new segment of the line evidence
            evidence_start(estate, counts)
        located = False
        if contact[i]:
            fx, fy, fz, mx, my, mz = x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], x[i, 5]
            px, py, pz = point[i, 0], point[i, 1], point[i, 2]
            finite = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
            if normal_from_tip:
                if not (px == lpx and py == lpy and pz == lpz):
                    nx, ny, nz = _normal(kind, sp, px, py, pz, XS)
                    lpx, lpy, lpz = px, py, pz
            else:
                nx, ny, nz = normal_in[i, 0], normal_in[i, 1], normal_in[i, 2]
            if depth_mode == DEPTH_ONLINE and onset:
                depth_start_contact(dstate)
            if finite:
                if not (nx == lnx and ny == lny and nz == lnz):
                    e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(nx, ny, nz, XS)
                    m1 = noise_moment_part(e1x, e1y, e1z, smx, smy, smz)
                    m2 = noise_moment_part(e2x, e2y, e2z, smx, smy, smz)
                    lnx, lny, lnz = nx, ny, nz
                d0 = 0.0
                if depth_mode != DEPTH_OFF:
                    d0 = square_depth_kernel(-(fx * nx + fy * ny + fz * nz), law[0], law[1], XS)
                if has[i]:
                    r = located_step(t[i], fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y,
                                     e2z, m1, m2, sfx, sfy, sfz, depth_mode, d0, dparams, dstate, dring, eparams,
                                     wconst, estate, counts, ring)  # fmt: skip
                    located = r[0]
                    if located:
                        pulling[i] = False
                        depth[i], depth_std[i], from_data[i] = r[1], r[2], r[3]
                        normal[i, 0], normal[i, 1], normal[i, 2] = nx, ny, nz
                        sigma[i], h[i, 0], h[i, 1], h[i, 2], h_norm[i], h_std[i] = r[4], r[5], r[6], r[7], r[8], r[9]
                        state[i] = r[10]
                        line_evidence[i] = r[11] if r[10] == _LINE_CODE else 0
                        direction[i, 0], direction[i, 1], direction[i, 2] = r[12], r[13], r[14]
                        angle[i], angle_std[i], angle_noise_std[i] = r[15], r[16], r[17]
                        h_ratio[i], f_ratio[i] = r[18], r[19]
                elif depth_mode == DEPTH_ONLINE:  # a finite point without a valid solution (track mode)
                    depth_step(dstate, dring, dparams, t[i], fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, d0)
            elif depth_mode == DEPTH_ONLINE:
                depth_gap(dstate)
        if fill_stats or not located:
            for k in range(4):
                stats[k, i] = _NAN
        if not located:
            pulling[i] = contact[i]
            latched[i] = False
            fallback[i] = False
            joint_fb[i] = False
            from_data[i] = False
            state[i] = _NONE_CODE
            line_evidence[i] = 0
            for k in range(3):
                point[i, k] = _NAN
                normal[i, k] = _NAN
                h[i, k] = _NAN
                direction[i, k] = _NAN
            sigma[i] = h_norm[i] = h_std[i] = depth[i] = depth_std[i] = _NAN
            angle[i] = angle_std[i] = angle_noise_std[i] = h_ratio[i] = f_ratio[i] = _NAN


def fused_columns(t: NDArray, x: NDArray, drift: NDArray, contact: NDArray, taring: NDArray, tip: Fingertip,
                  config: EstimatorConfig, noise: SensorNoise, corr: float, had_latch: bool,
                  out: dict | None = None) -> dict | None:  # fmt: skip
    """The per-contact stages of :func:`~softtip.estimator.batch.estimate` over a log in the
    compiled loops, or None where they do not apply (module docs: the staged path then runs).

    ``t`` (N,) s; ``x`` (N, 6) the tared (filtered, drift-corrected) wrench and ``drift`` (N, 6),
    both this call's to change (NaN where ``taring``); ``contact`` (N,) bool; ``config``
    resolved (:func:`~softtip.estimator.depth.resolve_depth`); ``noise`` the noise after any
    filter and ``corr`` its samples per independent sample; ``had_latch`` an earlier piece of
    the log latched; ``out``: arrays to write into, by name, kept from an earlier call of the
    same length and settings (filled in with new ones; a benchmark's reused buffers). Returns
    the :class:`~softtip.Estimates` columns by name, ``pulling`` and ``had_latch`` (after
    these samples).
    """
    n = len(t)
    rec = shape_record(tip)

    def new(name, shape, dtype=float):
        # an output or work array: the caller's (``out``, reused: benchmarks) or a new one
        shape = shape if isinstance(shape, tuple) else (shape,)
        a = None if out is None else out.get(name)
        if a is None or a.shape != shape or a.dtype != np.dtype(dtype):
            a = np.empty(shape, dtype=dtype)
            if out is not None:
                out[name] = a
        return a

    law = config.skin_law
    if rec is None or (law is not None and law.exponent != 2.0) or not use_numba(n):
        return None
    kind, sp = rec
    contact = np.ascontiguousarray(contact, dtype=bool)
    mode = TRACK if config.contact_point == "track" else LATCH
    rows = n if config.contact_point != "latch" else 1  # the soft-finger solutions, kept for line-fit and track
    point, has, sc, sc_valid = new("point", (n, 3)), new("has", n, bool), new("sc", (rows, 7)), new("sc_valid", rows, bool)
    latched, fallback, relatched = new("latched", n, bool), new("fallback", n, bool), new("relatched", n, bool)
    lstate = new_latch_state(had_latch)
    points_run.compiled()(t, x, contact, kind, sp, mode, latch_params(config), lstate, point, has, sc, sc_valid,
                          latched, fallback, relatched)  # fmt: skip
    joint_fb = new("joint_fb", n, bool)
    joint_fb[:] = False
    stats = new("stats", (4, n))
    fill_stats = True  # no line fit: every sample's statistics NaN
    if config.contact_point == "line-fit" and law is None:
        fill_stats = False
        moved = new("moved", n, bool)
        window = float(config.line_fit_window)
        ring = np.zeros((int(ring_rows.compiled()(t, window)), 1 + N_SUMS))
        accept = AcceptRecord(config.line_fit_max_angle_std, config.line_fit_max_offset_std, config.line_fit_max_residual)
        _register_methods()
        line_fit_run.compiled()(
            t, x, contact, relatched, sc, sc_valid, point, rec, NoiseRecord(noise.force_std, noise.moment_std), accept,
            new_line_fit_state(), ring, window, float(config.line_fit_drift**2), int(config.line_fit_iterations),
            float(corr), stats, moved, latched, fallback, joint_fb,
        )  # fmt: skip
        has = np.all(np.isfinite(point), axis=-1)
    elif config.contact_point == "line-fit":  # with a skin law: the stage's batch form (its solve vectorised)
        c = [np.ascontiguousarray(x[:, k]) for k in range(6)]
        soft = SoftFinger(*(sc[:, k] for k in range(7)), sc_valid)
        with np.errstate(invalid="ignore", divide="ignore"):
            point, stats, _, moved = line_fit_points(t, c, contact, soft, point, relatched, tip, config, noise, corr)
        fill_stats = False
        del c, soft
        latched &= ~moved
        fallback &= ~moved
        joint_fb = contact & ~moved
        has = np.all(np.isfinite(point), axis=-1)
    normal_in = sc[:, 3:6]  # the soft-finger normal (used in track mode)
    if law is None:
        depth_mode, lawp, dparams = DEPTH_OFF, np.zeros(2), np.zeros(1)
    elif config.depth_compensation == "law":
        depth_mode, lawp, dparams = DEPTH_LAW, np.array([law.stiffness, law.max_depth]), np.zeros(1)
    else:
        depth_mode, lawp = DEPTH_ONLINE, np.array([law.stiffness, law.max_depth])
        dparams = depth_params(config, noise, corr)
    capacity = int(ring_rows.compiled()(t, max(config.evidence_window, config.significance_window)))
    estate, counts, ring, wconst = new_evidence_state(capacity, corr)
    normal, h, direction = new("normal", (n, 3)), new("h", (n, 3)), new("direction", (n, 3))
    sigma, h_norm, h_std, depth, depth_std = (new(k, n) for k in ("sigma", "h_norm", "h_std", "depth", "depth_std"))
    angle, angle_std, angle_noise_std = new("angle", n), new("angle_std", n), new("angle_noise_std", n)
    h_ratio, f_ratio, from_data, pulling = new("h_ratio", n), new("f_ratio", n), new("from_data", n, bool), new("pulling", n, bool)
    state, line_evidence = new("state", n, np.int8), new("line_evidence", n, np.int8)
    tail_run.compiled()(
        t, x, drift, contact, np.ascontiguousarray(taring, dtype=bool), kind, sp, mode == LATCH, point, has, normal_in,
        relatched, depth_mode, lawp, dparams, np.array(noise_variances(noise)),
        evidence_params(config, noise, twist_curvature(tip)), wconst,
        estate, counts, ring, latched, fallback, joint_fb, normal, sigma, h, h_norm, h_std, depth, depth_std, from_data,
        state, line_evidence, direction, angle, angle_std, angle_noise_std, h_ratio, f_ratio, pulling, stats, fill_stats,
    )  # fmt: skip
    return dict(
        wrench=x, point=point, normal=normal, sigma=sigma, h=h, h_norm=h_norm, h_std=h_std, direction=direction,
        angle=angle, angle_std=angle_std, angle_noise_std=angle_noise_std, latched=latched, latch_fallback=fallback,
        pulling=pulling, relatched=relatched, depth=depth, line_fit_conditioning=stats[0],
        line_fit_angle_std=stats[1], line_fit_offset_std=stats[2], line_fit_residual=stats[3],
        line_fit_fallback=joint_fb, line_evidence=line_evidence, h_ratio=h_ratio, excitation_ratio=f_ratio,
        drift=drift, depth_std=depth_std, depth_from_data=from_data, state=state,
        had_latch=bool(lstate[_HAD]) if mode == LATCH else had_latch,
    )
