"""Calibration of a mesh fingertip's placement on the sensor from plane presses.

The shape is known (the CAD mesh); its pose relative to the sensor is not exactly: a printed
tip sits a little off where the drawing puts it. The probing log is the one of
``softtip calibrate`` for spheres and capsules: presses of the fingertip against a flat,
rigid surface, spread over the skin, with the friction force turning a little during each
press (the surface slides or the finger rocks).

Method
------
1. **Press points.** Per press ``k`` the contact normal ``n_k`` is constant (the table does
   not turn) and ``m_i = (r_k − κ √F_i n_k) × f_i + σ_i n_k``. With ``n_k`` the normal of the
   skin as last fitted (first: against the mean force) the tangential part of that equation
   (two numbers per sample; ``σ_i`` free) is linear in ``r_k``: least squares, with the
   covariance of ``r_k`` from the residual scatter. (Fitting ``n_k`` from the moments too
   turns it toward the noise: the component along ``n_k`` is the one left free.)
2. **Registration.** The press points must lie on the posed mesh, indented by the skin's
   compression ``κ √F_k`` along the normal (``F_k`` the press's mean normal force; for a
   Winkler skin pressed by a plane the depth grows as √F). Gauss–Newton on the
   point-to-surface distances ``(r_k − q_k) · ν_k + κ √F_k`` (``q_k`` the closest point of
   the posed mesh, ``ν_k`` its normal), weighted by each point's variance along ``ν_k``,
   for the translation ``t`` (and with ``rotation=True`` a small rotation ``ω``) and ``κ``.
   Steps 1 and 2 alternate four times (the points depend on ``κ`` and the normals).
3. **Honesty.** Standard deviations are ``(JᵀWJ)⁻¹`` scaled by the reduced χ² when it
   exceeds 1; directions the presses do not constrain (a capsule's roll about its own axis,
   one spot) are refused by the conditioning of ``JᵀWJ``.

The result moves the mesh: ``p_sensor = R(ω) p + t`` applied after the file's transform.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from softtip.calibration.probing import TARGET_STD, find_presses, force_spread, precision_text, tare_probing_log
from softtip.core._vec import tangent_basis as _tangent_basis
from softtip.core.mesh import MeshFingertip
from softtip.core.mounting import rpy_of
from softtip.errors import InputError
from softtip.estimator.tare import TareReport

__all__ = ["MeshCalibration", "calibrate_mesh", "calibrate_mesh_file", "press_points"]

_MIN_SPREAD = math.sin(math.radians(4.0))  # the friction force must turn this much in a press


@dataclass(frozen=True)
class MeshCalibration:
    """The fitted placement of a mesh fingertip.

    Attributes
    ----------
    translation, translation_std : array, shape (3,)
        Shift of the mesh in the sensor frame and its standard deviation, m.
    rotation, rotation_std : array, shape (3,)
        Small rotation (rotation vector, rad) about the mesh's bounding-sphere centre, and its
        standard deviation; zeros when only the translation was fitted.
    compliance, compliance_std : float
        Skin indentation ``κ`` in ``δ = κ √F``, m/√N.
    n_presses, n_skipped : int
        Presses used, and presses left out (too short or without a turning force).
    rms_residual : float
        RMS distance of the press points from the fitted skin (indentation included), m.
    noise_ratio : float
        The residual over what the presses' own scatter explains (about 1 when the mesh fits;
        :attr:`fit_warning` above 2).
    tip : MeshFingertip
        The fingertip moved to the fitted pose.
    tare : TareReport or None
        The bias from the untouched start and its warnings
        (:func:`~softtip.calibration.probing.tare_probing_log`); None for a tared log.
    """

    translation: NDArray[np.float64]
    translation_std: NDArray[np.float64]
    rotation: NDArray[np.float64]
    rotation_std: NDArray[np.float64]
    compliance: float
    compliance_std: float
    n_presses: int
    n_skipped: int
    rms_residual: float
    tip: MeshFingertip
    tare: TareReport | None = field(default=None, repr=False)
    noise_ratio: float = math.nan

    @property
    def fit_warning(self) -> str:
        """``""``, or why the mesh does not fit the presses as placed: the presses lie farther from
        the fitted skin than their own scatter explains (:attr:`noise_ratio` above 2)."""
        if not self.noise_ratio > 2.0:
            return ""
        tilt = "" if np.any(self.rotation_std > 0) else "a tilt of the mesh (--rotation fits it, where the shape fixes it), "
        return (
            f"the presses lie {self.noise_ratio:.1f} times farther from the fitted skin than their own scatter explains "
            f"(rms {self.rms_residual * 1e3:.3f} mm): the mesh does not fit them as placed; look for {tilt}the wrong "
            "mesh or units, or a skin that is not this shape. The standard deviations are scaled by it"
        )

    def precision_warning(self, target: float = TARGET_STD) -> str:
        """``""``, or what it would take to bring the shift's standard deviations to ``target``
        (m): they fall as ``1/√presses`` (as :meth:`Calibration.precision_warning
        <softtip.calibration.probing.Calibration.precision_warning>` says for the closed forms)."""
        stds = {f"shift along {axis}": float(v) for axis, v in zip("xyz", self.translation_std)}
        return precision_text(stds, self.n_presses, target, "it",
                              "press all over the skin, and where its normal points along that axis")  # fmt: skip

    def summary(self) -> str:
        t = ", ".join(f"{v * 1e3:+.3f}" for v in self.translation)
        ts = ", ".join(f"{v * 1e3:.3f}" for v in self.translation_std)
        rotated = bool(np.any(self.rotation_std > 0))
        lines = [
            f"mesh shift ({t}) mm ± ({ts}) mm" + (" (after the rotation below, about the mesh's centre)" if rotated else ""),
            f"skin compliance {self.compliance * 1e3:.3f} ± {self.compliance_std * 1e3:.3f} mm/√N",
            f"{self.n_presses} presses used ({self.n_skipped} skipped), rms residual {self.rms_residual * 1e3:.3f} mm "
            f"({self.noise_ratio:.2f} × the presses' own scatter)",
        ]
        if rotated:
            r = ", ".join(f"{math.degrees(v):+.3f}" for v in self.rotation)
            rs = ", ".join(f"{math.degrees(v):.3f}" for v in self.rotation_std)
            lines.insert(1, f"mesh rotation vector ({r})° ± ({rs})°, about the mesh's bounding-sphere centre")
        # what the fingertip file gets: the file's own mounting composed with the fitted move
        tr = ", ".join(f"{v * 1e3:+.3f}" for v in self.tip.translation)
        rpy = ", ".join(f"{math.degrees(v):+.3f}" for v in self.tip.rpy)
        lines.insert(2 if rotated else 1, f"the fingertip file's mounting: translation ({tr}) mm, rpy ({rpy})°")
        return "\n".join(lines)


def press_points(
    f: NDArray, m: NDArray, normal: ArrayLike | None = None, compliance: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
    """Contact point of one plane press (see the module docstring, step 1).

    Parameters
    ----------
    f, m : array, shape (N, 3)
        Force (N) and moment (N·m) samples of the press, tared.
    normal : array-like (3,), optional
        The contact normal (outward from the skin); default: against the mean force. It is
        not fitted from the moments: the spin leaves the moment's component along ``n``
        free, and a fitted ``n`` would turn toward the noise.
    compliance : float
        Skin indentation ``κ`` (m/√N): the contact point of sample ``i`` is
        ``r − κ √F_i n``, and ``r`` (returned) is the point of the undeformed skin.

    Returns
    -------
    point : array (3,)
        m.
    normal : array (3,)
        The normal used.
    cov : array (3, 3)
        Covariance of ``point``, m² (from the residual scatter).
    force : float
        Mean normal force ``−f · n``, N.
    """
    n = -np.mean(f, axis=0) if normal is None else np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    t1, t2 = _tangent_basis(n)
    f_normal = np.maximum(-(f @ n), 0.0)
    # tangential part of m − (r − δ n) × f = 0, linear in r: (r × f)·t = r · (f × t)
    q = m + compliance * np.sqrt(f_normal)[:, None] * np.cross(n, f)
    a = np.concatenate((np.cross(f, t1), np.cross(f, t2)))
    b = np.concatenate((q @ t1, q @ t2))
    r, *_ = np.linalg.lstsq(a, b, rcond=None)
    res = b - a @ r
    s2 = float(res @ res) / max(len(b) - 3, 1)
    cov = s2 * np.linalg.pinv(a.T @ a)
    return r, n, cov, float(np.mean(f_normal))


def calibrate_mesh(
    t: ArrayLike,
    wrench: ArrayLike,
    tip: MeshFingertip,
    *,
    rotation: bool = False,
    tare_duration: float = 0.2,
    contact_threshold: float = 0.05,
    min_force: float = 0.5,
    iterations: int = 20,
) -> MeshCalibration:
    """Fit the placement of ``tip`` on the sensor from a log of plane presses.

    Parameters
    ----------
    t : array-like, shape (N,)
        Time, s.
    wrench : array-like, shape (N, 6)
        Raw wrench, N and N·m (the first ``tare_duration`` seconds untouched: the bias).
    tip : MeshFingertip
        The fingertip at its nominal placement.
    rotation : bool
        Also fit a small rotation (6 DOF); default: the translation only.
    tare_duration : float
        s, the untouched start whose mean without spikes is the bias
        (:func:`~softtip.calibration.probing.tare_probing_log`); 0 when the log is already tared.
    contact_threshold, min_force : float
        A press lasts while ``|f|`` is at least ``contact_threshold``; only its samples with
        ``|f| ≥ min_force`` are used, N.

    Raises
    ------
    InputError
        Too few usable presses, or presses that leave a direction of the pose undetermined.
    """
    t = np.asarray(t, dtype=float)
    w = np.asarray(wrench, dtype=float)
    w, tare = tare_probing_log(t, w, tare_duration)
    f_norm = np.linalg.norm(w[:, :3], axis=1)
    presses, skipped = [], 0
    for idx in find_presses(f_norm, contact_threshold):
        idx = idx[f_norm[idx] >= min_force]
        if len(idx) < 8 or force_spread(w[idx, :3]) < _MIN_SPREAD:
            skipped += 1
        else:
            presses.append(idx)
    n_par = 7 if rotation else 4
    if len(presses) < n_par + 2:
        raise InputError(
            f"{len(presses)} usable presses ({skipped} skipped: too short or without a turning friction force); "
            f"the mesh placement needs at least {n_par + 2}, spread over the skin"
        )
    centre = tip.bounding_sphere[0]
    x = np.zeros(n_par)
    # press points with the indentation of the current κ, then the registration; twice more
    # with the fitted κ (the points move by the indentation's spread within each press)
    nrm = None  # press normals: against the mean force first, then the fitted skin's
    try:
        for _ in range(4):
            x, a, wgt, pts, cov, sqf, kappa0, nrm = _register(tip, w, presses, x, rotation, centre, iterations, nrm)
    except np.linalg.LinAlgError:
        raise _diverged(tip) from None

    def posed(x):
        rot = Rotation.from_rotvec(x[3:6]) if rotation else Rotation.identity()
        return rot, x[:3]

    # final residuals and covariance
    rot, shift = posed(x)
    local = rot.inv().apply(pts - centre - shift) + centre
    face, b1, b2, _ = tip.closest(local)
    q, nu = tip._interp(face, b1, b2)
    res = np.sum((local - q) * nu, axis=1) + (x[-1] - kappa0) * sqf
    chi2 = float(np.sum(res * res * wgt)) / max(len(pts) - n_par, 1)
    scale = np.sqrt(np.diag(a))
    if not (np.isfinite(a).all() and np.isfinite(x).all() and (scale > 0).all()):
        raise _diverged(tip)  # the registration ran away: the presses lie nowhere near this skin
    cond = np.linalg.cond(a / np.outer(scale, scale))
    if not np.isfinite(cond) or cond > 1e8:
        raise InputError(
            "the presses leave part of the mesh placement undetermined (a direction the skin's shape does not "
            "fix, such as a round tip's roll about its own axis, or presses at one spot): fit the translation "
            "only, or press at more points spread over the skin"
        )
    cov_x = np.linalg.inv(a) * max(chi2, 1.0)
    std = np.sqrt(np.diag(cov_x))
    # the file's transform composed with the fitted move: p = R_c (R_f p_mesh + t_f − c) + c + t_c
    r_file = Rotation.from_euler("xyz", tip.rpy)
    moved = MeshFingertip(
        rot.apply(tip.vertices - centre) + centre + shift,
        tip.faces,
        crease_angle_deg=tip.crease_angle_deg,
        skin_thickness=tip.skin_thickness,
        source=tip.source,
        mesh_units=tip.mesh_units,
        translation=tuple(float(v) for v in rot.apply(np.asarray(tip.translation) - centre) + centre + shift),
        rpy=rpy_of(rot * r_file),
    )
    return MeshCalibration(
        translation=x[:3].copy(),
        translation_std=std[:3],
        rotation=x[3:6].copy() if rotation else np.zeros(3),
        rotation_std=std[3:6] if rotation else np.zeros(3),
        compliance=float(x[-1]),
        compliance_std=float(std[-1]),
        n_presses=len(pts),
        n_skipped=skipped,
        rms_residual=float(np.sqrt(np.mean(res * res))),
        noise_ratio=math.sqrt(chi2),
        tip=moved,
        tare=tare,
    )


def _register(tip, w, presses, x, rotation, centre, iterations, nrm):
    """Press points at the current κ, then Gauss–Newton of the placement and κ (module docstring)."""
    kappa0 = max(float(x[-1]), 0.0)  # the points are of the undeformed skin at this κ
    fits = [press_points(w[idx, :3], w[idx, 3:], None if nrm is None else nrm[k], kappa0) for k, idx in enumerate(presses)]
    pts = np.array([p[0] for p in fits])
    cov = np.array([p[2] for p in fits])
    sqf = np.sqrt(np.array([p[3] for p in fits]))
    n_par = len(x)

    def posed(x):
        rot = Rotation.from_rotvec(x[3:6]) if rotation else Rotation.identity()
        return rot, x[:3]

    for _ in range(iterations):
        rot, shift = posed(x)
        # press points in the mesh's nominal frame: p = R⁻¹ (r − c − t) + c
        local = rot.inv().apply(pts - centre - shift) + centre
        face, b1, b2, _ = tip.closest(local)
        q, nu = tip._interp(face, b1, b2)
        res = np.sum((local - q) * nu, axis=1) + (x[-1] - kappa0) * sqf
        nu_s = rot.apply(nu)  # normals in the sensor frame
        var = np.einsum("ki,kij,kj->k", nu_s, cov, nu_s)
        wgt = 1.0 / np.maximum(var, 1e-18)
        jac = np.zeros((len(pts), n_par))
        jac[:, :3] = -nu_s  # ∂res/∂t
        if rotation:
            arm = rot.apply(q - centre)
            jac[:, 3:6] = -np.cross(arm, nu_s)  # ∂res/∂ω (small rotation of the mesh)
        jac[:, -1] = sqf
        jtw = jac.T * wgt
        a = jtw @ jac
        step = np.linalg.lstsq(a, -jtw @ res, rcond=None)[0]  # minimum norm where undetermined
        x = x + step
        if np.max(np.abs(step[:-1])) < 1e-10:
            break
    return x, a, wgt, pts, cov, sqf, kappa0, nu_s


def _diverged(tip: MeshFingertip) -> InputError:
    """The error of a registration that ran away from the skin."""
    extent = float(np.ptp(tip.vertices, axis=0).max())
    return InputError(
        f"the presses do not fit this mesh (the fit diverged): it is {extent * 1e3:.4g} mm across; wrong mesh units "
        "(--mesh-units, or mesh_units in the fingertip file), the wrong mesh, or a mesh not placed on the sensor?"
    )


def calibrate_mesh_file(
    t: ArrayLike, wrench: ArrayLike, mesh: str, mesh_units: str | None = None, skin_thickness: float | None = None,
    **kwargs,
) -> MeshCalibration:
    """:func:`calibrate_mesh` for a mesh given as a file: a mesh fingertip ``.toml`` or a bare
    ``.stl`` / ``.obj`` / ``.ply`` with ``mesh_units`` (placed as drawn); ``skin_thickness`` (m),
    where given, is the fitted fingertip's (a ``.toml``'s own otherwise)."""
    from dataclasses import replace
    from pathlib import Path

    from softtip.core.mesh import load_mesh_fingertip, mesh_fingertip_from_table

    path = Path(mesh)
    if path.suffix.lower() == ".toml":
        if mesh_units is not None:
            raise InputError("--mesh-units is for a bare mesh file; a fingertip .toml gives mesh_units itself")
        tip = load_mesh_fingertip(path)
        if skin_thickness is not None and skin_thickness != tip.skin_thickness:
            tip = replace(tip, skin_thickness=skin_thickness)
    else:
        if mesh_units is None:
            raise InputError(f"{path}: give --mesh-units (mesh files carry no units)")
        table = {"mesh": str(path.resolve()), "mesh_units": mesh_units}
        if skin_thickness is not None:
            table["skin_thickness"] = skin_thickness
        tip = mesh_fingertip_from_table(table, source=str(path))
    return calibrate_mesh(t, wrench, tip, **kwargs)
