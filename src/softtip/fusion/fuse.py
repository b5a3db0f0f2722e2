"""Two fingertips, one object: contacts and edge directions fused in a common frame.

Each fingertip's estimates (its sensor frame) are put into the common frame with the
fingertip's pose, and the pair of contacts is read as a grasp:

``parallel_lines``
    Both contacts are lines whose directions agree within their uncertainty (the axial angle
    between them at most ``agree_sigmas`` times its standard deviation): a plate or a stick
    pinched across. The common direction is the weighted axial mean; the plane through both
    contact lines has the normal ``d × (r₂ − r₁)`` (a plate's face; for a stick, the plane
    through its axis).
``crossing_lines``
    Both are lines that disagree: two different edges (a wedge's two faces meeting the
    fingers, a cube's edges). Both lines are reported, with the angle between them and their
    closest approach.
``line_and_face``
    One line; the other contact is a ``point`` or an ``area``: a face. Its outward normal on
    the object is minus the fingertip's normal.
``faces``
    No line: two faces.
``single`` / ``none``
    One contact, or none.

Flags (``flag``, several joined by ``+``):

``unbalanced``
    The contact forces do not balance the object's weight (``object_mass`` along
    ``gravity``; without a mass any weight along gravity is allowed) beyond the sensors'
    noise and ``balance_tolerance`` of the grasp force: one of the estimates (or a pose) is
    wrong, or a third force acts on the object (the environment, another finger, a load).
``area``
    A contact's evidence says ``area``: it is a face, never fused as a line.

``evidence`` is ``confirmed`` when every line fused was confirmed by excitation about two
axes, ``unconfirmed`` otherwise. A flat face pressed against one finger while the object is
only tilted about one axis reports the same line as the edge on the other finger (its force
turns the same way): no method can tell that grasp from a plate pinched across until the
object is rocked about two axes, and until then the fusion says ``parallel_lines``,
``unconfirmed``.

Standard deviations (first order), with the two sources of error a fingertip's own standard
deviation cannot show:

* **Shared error.** Both fingertips hold one object: what moves it (the joints, gravity,
  rocking) loads both contacts alike, and what the single-finger model leaves out (a line's
  small resistance to rolling about its own edge, the skin's shear) turns both measured
  directions the same way in the common frame. Each finger's ``angle_std`` is split in two:
  the sensor noise's share (``angle_noise_std``), independent between two sensors, and the
  rest, the estimator's model error (``EstimatorConfig.evidence_model_std``, the window's
  across-axis spread, ``window_model_std``, ``unconfirmed_model_std``), taken as shared with correlation
  ``finger_correlation`` (ρ, default 1). The fused direction is the weighted axial mean,
  with weights ``w = 1 / angle_std²`` and the variance
  ``(w_a + w_b + 2 ρ w_a w_b m_a m_b) / (w_a + w_b)²`` (``m`` the model errors): averaging
  two fingers shrinks their noise, never the error they share. On the simulator's grasps
  the two fingers' errors had the same sign in the common frame in most runs.
* **Unconfirmed lines.** Before the object has been rocked about two axes, a line's direction
  comes from load varied about one axis, and its rolling resistance follows the same load:
  the axis is biased by an amount no single-axis window shows (on the simulator's stick and
  cube edge at 45° to the joint axis, 7–9° on both fingers alike while each reported about
  3.7° from the noise alone). Each fingertip's estimator therefore reports a line that is
  ``unconfirmed`` with a model-error term in its standard deviation
  (``EstimatorConfig.unconfirmed_model_std``, 5°, from a held ``h``; ``window_model_std``, 2°,
  from a window that saw one axis), which the correlated fingers carry into
  the fused one undiminished (``unconfirmed_std`` adds a further shared term, for estimates
  made without it); the fused reading stays marked ``unconfirmed``.

The plane normal's standard deviation is the direction's tilt across the plane (the part of
each finger's error about the line between the contacts, which tilts the plane one for one)
and the contact points' error across the line (``point_std`` per axis, m, each finger
independent) over the distance between the contacts.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.noise import NANO17, SensorNoise
from softtip.estimator import Estimates
from softtip.estimator.results import EVIDENCE
from softtip.fusion.columns import FUSED_COLUMNS
from softtip.fusion.poses import PoseSeries

__all__ = ["GRASPS", "Finger", "FusedGrasp", "fuse", "fused_markdown_table"]

#: Grasp readings, indexed by the codes in :attr:`FusedGrasp.grasp`.
GRASPS = ("none", "single", "parallel_lines", "crossing_lines", "line_and_face", "faces")
_NONE, _SINGLE, _PARALLEL, _CROSSING, _LINE_FACE, _FACES = range(6)
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True, eq=False)
class Finger:
    """One fingertip's estimates and where its sensor is.

    Parameters
    ----------
    name : str
    estimates : Estimates
        From :func:`softtip.estimate` on this fingertip's log (sensor frame).
    pose : PoseSeries
        The sensor frame's pose in the common frame over the log's time (``estimates.t``).
    noise : SensorNoise
        The sensor's noise model (for the force balance): the one its estimates used
        (:func:`softtip.estimator.tare.noise_in_use`, which :func:`softtip.fusion.fuse_logs`
        passes; measured with ``noise_from_tare``).
    """

    name: str
    estimates: Estimates
    pose: PoseSeries
    noise: SensorNoise = field(default=NANO17)


@dataclass(frozen=True, eq=False)
class FusedGrasp:
    """Per time step of the first finger's log: the grasp in the common frame (SI; NaN where
    undefined). Angles and their standard deviations in rad."""

    t: NDArray[np.float64]
    grasp: NDArray[np.int8]  #: codes into :data:`GRASPS`
    evidence: NDArray[np.str_]  #: ``confirmed``, ``unconfirmed`` or ``""`` (no line)
    flag: NDArray[np.str_]  #: ``""``, ``unbalanced``, ``area`` or both joined by ``+``
    point_a: NDArray[np.float64]  #: (N, 3) contact points
    point_b: NDArray[np.float64]
    direction: NDArray[np.float64]  #: (N, 3) the (common) line direction, an axis
    direction_std: NDArray[np.float64]  #: (N,)
    direction_b: NDArray[np.float64]  #: (N, 3) the second line (``crossing_lines``)
    line_angle: NDArray[np.float64]  #: (N,) axial angle between the two lines
    line_angle_std: NDArray[np.float64]
    closest_approach: NDArray[np.float64]  #: (N,) m, ``crossing_lines``
    plane_normal: NDArray[np.float64]  #: (N, 3) plane through both lines (``parallel_lines``)
    plane_normal_std: NDArray[np.float64]  #: (N,)
    face_normal: NDArray[np.float64]  #: (N, 3) the face's outward normal on the object (``line_and_face``)
    force_residual: NDArray[np.float64]  #: (N, 3) N, ``f_a + f_b − m g``
    balance_chi2: NDArray[np.float64]  #: (N,) the residual's χ² against the noise and tolerance
    names: tuple[str, str] = ("a", "b")

    def __len__(self) -> int:
        return len(self.t)

    @property
    def grasp_names(self) -> NDArray[np.str_]:
        return np.asarray(GRASPS)[self.grasp]

    def columns(self) -> dict[str, NDArray]:
        """Output columns (SI, angles in degrees), as :data:`softtip.fusion.columns.FUSED_COLUMNS`
        declares them. The contact points are ``r1_*`` and
        ``r2_*``, of the first and the second finger given (:attr:`names` says which is which),
        so the columns are the same whether the fingers came from CSV logs or a bag's topics."""
        out: dict[str, NDArray] = {}
        for c in FUSED_COLUMNS:
            v = getattr(self, c.source)
            if c.unit == "deg":
                v = np.degrees(v)
            if len(c.names) == 1:
                out[c.names[0]] = v
            else:
                for i, name in enumerate(c.names):
                    out[name] = v[:, i]
        return out


def _hold(t_src: NDArray, t: NDArray, max_age: float) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """Index of the latest source sample at or before each ``t``, and whether it is fresh."""
    k = np.searchsorted(t_src, t, side="right") - 1
    ok = k >= 0
    kc = np.clip(k, 0, len(t_src) - 1)
    ok &= (t - t_src[kc]) <= max_age
    return kc, ok


def _in_common(f: Finger, t: NDArray, idx: NDArray, ok: NDArray):
    """The finger's contact quantities at ``idx`` of its log, in the common frame."""
    est = f.estimates
    n = len(t)
    state = np.where(ok, est.state_names[idx], "none")
    evidence = np.where(ok, np.asarray(EVIDENCE)[est.line_evidence[idx]], "")
    rot, tr = f.pose.at(est.t[idx])
    point = rot.apply(np.nan_to_num(est.point[idx])) + tr
    normal = rot.apply(np.nan_to_num(est.normal[idx]))
    direction = rot.apply(np.nan_to_num(est.direction[idx]))
    force = rot.apply(np.nan_to_num(est.wrench[idx, :3]))
    # the force noise of each sensor, rotated: Σ = R diag(s²) Rᵀ
    s2 = np.asarray(f.noise.force_std) ** 2
    m = rot.as_matrix()
    cov = np.einsum("nij,j,nkj->nik", m, s2, m)
    contact = state != "none"
    nan3 = np.full((n, 3), np.nan)
    angle_std = np.where(state == "line", est.angle_std[idx], np.nan)
    # what is not the sensor's noise is the estimator's model error: shared by both fingers
    noise_std = np.where(state == "line", est.angle_noise_std[idx], np.nan)
    model = np.sqrt(np.maximum(angle_std * angle_std - noise_std * noise_std, 0.0))
    return {
        "state": state,
        "evidence": evidence,
        "point": np.where(contact[:, None], point, nan3),
        "normal": np.where(contact[:, None], normal, nan3),
        "direction": np.where((state == "line")[:, None], direction, nan3),
        "angle_std": angle_std,
        "model_std": model,
        "force": np.where(ok[:, None], force, 0.0),
        "force_cov": cov,
    }


def _unit(v: NDArray) -> NDArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def fuse(
    fingers: Sequence[Finger],
    *,
    object_mass: float | None = None,
    gravity: ArrayLike = (0.0, 0.0, -STANDARD_GRAVITY),
    point_std: float = 5e-5,
    finger_correlation: float = 1.0,
    unconfirmed_std: float = 0.0,
    agree_sigmas: float = 3.0,
    balance_tolerance: float = 0.05,
    balance_chi2: float = 16.27,
    max_age: float | None = None,
) -> FusedGrasp:
    """Fuse two fingertips' estimates into the grasped object's local geometry.

    Parameters
    ----------
    fingers : two Finger
        The first finger's samples are the time steps of the result; the second's latest
        sample at or before each (within ``max_age``) is paired with it.
    object_mass : float, optional
        kg; the object's weight enters the force balance. None: unknown (any weight along
        ``gravity`` is allowed).
    gravity : 3 floats
        m/s², in the common frame (default ``−z``, 9.80665).
    point_std : float
        m, standard deviation of a contact point across its line, each finger independently
        (for the plane normal). What is common to both fingers (the skin's compression, a
        depth law's error) shifts the plane without tilting it; on the simulator the
        difference between the two fingers' errors is below 0.02 mm.
    finger_correlation : float
        ρ in [0, 1], correlation of the two fingers' model errors (each ``angle_std`` less its
        ``angle_noise_std``) in the common frame: the object's motion and the contact model's
        errors are shared. 0: independent. The sensors' noise is independent whatever ρ.
    unconfirmed_std : float
        rad, model-error standard deviation of a line direction that is not yet confirmed by
        excitation about two axes (its rolling bias), shared by both fingers, added here
        (default 0: the estimator already carries it in each finger's ``angle_std``,
        ``EstimatorConfig.unconfirmed_model_std``, 5°, for a held ``h`` and
        ``window_model_std``, 2°, for a window that saw one axis, which ``finger_correlation``
        treats as shared; give it here for estimates made without it).
    agree_sigmas : float
        Two lines agree when their axial angle is at most this many standard deviations:
        the two fingers' ``angle_std`` combined as if independent (a shared error cancels in
        the difference, so the test is the wider for it; ``line_angle_std`` is the same).
    balance_tolerance : float
        Fraction of the grasp force allowed as unbalanced (dynamics, friction hysteresis).
    balance_chi2 : float
        χ² (3 degrees of freedom; 16.27 is the 99.9 % point) above which the forces are
        ``unbalanced``.
    max_age : float, optional
        s; default two median sample periods of the second finger.

    Returns
    -------
    FusedGrasp
    """
    if len(fingers) != 2:
        raise ValueError(f"fuse takes two fingers, got {len(fingers)}")
    if not (0.0 <= finger_correlation <= 1.0):
        raise ValueError(f"finger_correlation must be in [0, 1], got {finger_correlation!r}")
    if not (math.isfinite(unconfirmed_std) and unconfirmed_std >= 0.0):
        raise ValueError(f"unconfirmed_std must be 0 or more (rad), got {unconfirmed_std!r}")
    if not (math.isfinite(point_std) and point_std >= 0.0):
        raise ValueError(f"point_std must be 0 or more (m), got {point_std!r}")
    fa, fb = fingers
    t = np.asarray(fa.estimates.t, dtype=float)
    tb = np.asarray(fb.estimates.t, dtype=float)
    if max_age is None:
        dt = np.diff(tb)
        dt = dt[dt > 0]
        max_age = 2.0 * float(np.median(dt)) if len(dt) else 0.0
    n = len(t)
    ia = np.arange(n)
    ib, okb = _hold(tb, t, max_age)
    A = _in_common(fa, t, ia, np.ones(n, dtype=bool))
    B = _in_common(fb, t, ib, okb)
    g = np.asarray(gravity, dtype=float).reshape(3)

    line_a, line_b = A["state"] == "line", B["state"] == "line"
    has_a, has_b = A["state"] != "none", B["state"] != "none"
    area = (A["state"] == "area") | (B["state"] == "area")
    nan3 = np.full((n, 3), np.nan)
    nan1 = np.full(n, np.nan)

    # -- two lines: agreement, the common direction, the plane --------------------------------
    da, db = A["direction"], B["direction"]
    sgn = np.where(np.sum(da * db, axis=-1) < 0, -1.0, 1.0)
    dbs = db * sgn[:, None]
    with np.errstate(invalid="ignore"):
        angle = np.arccos(np.clip(np.abs(np.sum(da * db, axis=-1)), 0.0, 1.0))
        sa2, sb2 = A["angle_std"] ** 2, B["angle_std"] ** 2
        angle_std = np.sqrt(sa2 + sb2)
        both = line_a & line_b
        agree = both & (angle <= agree_sigmas * angle_std)
        wa, wb = 1.0 / sa2, 1.0 / sb2
        w = wa + wb
        u = _unit(wa[:, None] * da + wb[:, None] * dbs)
        rho = float(finger_correlation)
        # the shared part: the model terms' covariance, ρ m_a m_b, weighted
        shared = 2.0 * rho * wa * wb * A["model_std"] * B["model_std"]
        su2 = float(unconfirmed_std) ** 2
        # shares of the weight whose line is unconfirmed: their common rolling bias
        ua = np.where(A["evidence"] == "unconfirmed", wa, 0.0) / w
        ub = np.where(B["evidence"] == "unconfirmed", wb, 0.0) / w
        u_var = (wa + wb + shared) / w**2 + su2 * (ua + ub) ** 2
        base = B["point"] - A["point"]
        length = np.linalg.norm(base, axis=-1)
        bhat = base / length[:, None]
        cross = np.cross(u, bhat)
        sin = np.linalg.norm(cross, axis=-1)
        plane_n = cross / sin[:, None]
        # the plane tilts about the base line with the part of each finger's error (a rotation
        # about its own normal: along n × d) across the plane; ca, cb are those parts per unit
        # rotation about the common axis bhat, so that shared errors add with one sign
        ca = np.sum(A["normal"] * bhat, axis=-1) * np.sum(np.cross(A["normal"], da) * plane_n, axis=-1)
        cb = np.sum(B["normal"] * bhat, axis=-1) * np.sum(np.cross(B["normal"], dbs) * plane_n, axis=-1)
        tilt = (
            (ca**2 * wa + cb**2 * wb + ca * cb * shared) / w**2
            + su2 * (ua * ca + ub * cb) ** 2
        )
        # about the direction with the contact points' errors across it
        plane_std = np.sqrt(tilt + 2.0 * point_std**2 / length**2) / sin
        # closest approach of two lines that disagree
        dxd = np.cross(da, db)
        closest = np.abs(np.sum(base * dxd, axis=-1)) / np.linalg.norm(dxd, axis=-1)

    one_line = (line_a ^ line_b) & has_a & has_b
    grasp = np.full(n, _NONE, dtype=np.int8)
    grasp[has_a ^ has_b] = _SINGLE
    grasp[has_a & has_b] = _FACES
    grasp[one_line] = _LINE_FACE
    grasp[both & ~agree] = _CROSSING
    grasp[agree] = _PARALLEL

    direction = np.where(agree[:, None], u, np.where(line_a[:, None], da, np.where(line_b[:, None], db, nan3)))
    # one line alone: its own standard deviation, with the rolling bias while unconfirmed
    own_a = np.sqrt(A["angle_std"] ** 2 + np.where(A["evidence"] == "unconfirmed", su2, 0.0))
    own_b = np.sqrt(B["angle_std"] ** 2 + np.where(B["evidence"] == "unconfirmed", su2, 0.0))
    direction_std = np.where(agree, np.sqrt(u_var), np.where(line_a, own_a, np.where(line_b, own_b, nan1)))
    direction_b = np.where((both & ~agree)[:, None], db, nan3)
    face_normal = np.where(
        (one_line & line_a)[:, None], -B["normal"], np.where((one_line & line_b)[:, None], -A["normal"], nan3)
    )
    # evidence of the lines fused
    ev_a = np.where(line_a, A["evidence"], "confirmed")
    ev_b = np.where(line_b, B["evidence"], "confirmed")
    any_line = line_a | line_b
    confirmed = (ev_a == "confirmed") & (ev_b == "confirmed")
    evidence = np.where(any_line, np.where(confirmed, "confirmed", "unconfirmed"), "")

    # -- force balance ------------------------------------------------------------------------
    res = A["force"] + B["force"]
    if object_mass is not None:
        res = res - float(object_mass) * g
    fmag = np.maximum(np.linalg.norm(A["force"], axis=-1), np.linalg.norm(B["force"], axis=-1))
    cov = A["force_cov"] + np.where(okb[:, None, None], B["force_cov"], 0.0)
    cov = cov + (balance_tolerance * fmag)[:, None, None] ** 2 * np.eye(3) / 3.0
    if object_mass is None and np.linalg.norm(g) > 0:
        # an unknown weight: allow any residual along gravity (the object's weight pulls down)
        gh = g / np.linalg.norm(g)
        along = res @ gh
        res_t = res - np.maximum(along, 0.0)[:, None] * gh
    else:
        res_t = res
    with np.errstate(invalid="ignore"):
        chi2 = np.einsum("ni,ni->n", res_t, np.linalg.solve(cov, res_t[..., None])[..., 0])
    both_in = has_a & has_b
    unbalanced = both_in & (chi2 > balance_chi2)
    flag = np.where(unbalanced & area, "unbalanced+area", np.where(unbalanced, "unbalanced", np.where(area, "area", "")))

    return FusedGrasp(
        t=t,
        grasp=grasp,
        evidence=evidence,
        flag=flag,
        point_a=A["point"],
        point_b=B["point"],
        direction=direction,
        direction_std=direction_std,
        direction_b=direction_b,
        line_angle=np.where(both, angle, nan1),
        line_angle_std=np.where(both, angle_std, nan1),
        closest_approach=np.where(both & ~agree, closest, nan1),
        plane_normal=np.where(agree[:, None], plane_n, nan3),
        plane_normal_std=np.where(agree, plane_std, nan1),
        face_normal=face_normal,
        force_residual=np.where(both_in[:, None], res, nan3),
        balance_chi2=np.where(both_in, chi2, nan1),
        names=(fa.name, fb.name),
    )


def fused_markdown_table() -> str:
    """The table of manual §8: one row per column or vector, empty cells NaN where a reading
    does not define them."""
    import inspect

    defaults = inspect.signature(fuse).parameters  # the defaults the descriptions quote
    fill = {"tolerance": 100.0 * defaults["balance_tolerance"].default, "chi2": defaults["balance_chi2"].default}
    rows = ["| column | unit | |", "| --- | --- | --- |"]
    for c in FUSED_COLUMNS:
        names = f"`{c.names[0]}`" if len(c.names) == 1 else f"`{c.names[0]}` … `{c.names[-1]}`"
        rows.append(f"| {names} | {c.unit} | {c.description.format(**fill)} |")
    return (
        "<!-- written by scripts/make_column_table.py from softtip.fusion.columns; do not edit -->\n\n"
        + "\n".join(rows)
        + "\n\nA number is NaN (empty in CSV) where the reading does not define it. Where the first log has absolute "
        "stamps (a bag, a log with Unix time) `stamp_ns`, its stamps in ns, is the last column.\n"
    )
