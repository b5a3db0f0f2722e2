"""What the estimator returns: :class:`Estimates` (a whole log) and :class:`SampleEstimate`
(one sample); their output columns are those of :mod:`softtip.estimator.columns`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core.units import wrench_to_si
from softtip.estimator.columns import COLUMNS, EVIDENCE, STATES

__all__ = ["STATES", "NONE", "POINT", "LINE", "AREA", "EVIDENCE", "EstimatorWarning", "Estimates", "SampleEstimate"]

NONE, POINT, LINE, AREA = 0, 1, 2, 3  # codes into STATES
#: numpy's type of each column's values (:attr:`Column.dtype <softtip.estimator.columns.Column.dtype>`)
_NUMPY_TYPES = {"float64": np.float64, "bool": np.bool_, "int64": np.int64}


class EstimatorWarning(UserWarning):
    """The estimates may be wrong: a bad tare, a log that starts in contact, a drifting bias.

    The same messages are in :attr:`Estimates.warnings` and :attr:`softtip.Estimator.warnings`.
    """


@dataclass(frozen=True)
class Estimates:
    """Per-sample output of :func:`estimate`. SI units, sensor frame; ``N`` samples.

    Attributes
    ----------
    t : (N,) s
    state : (N,) int8 codes into :data:`STATES` (``none``, ``point``, ``line``, ``area``)
    wrench : (N, 6) the tared (and filtered) wrench the estimates come from, N and N·m;
        NaN while taring
    point, normal : (N, 3) contact point (m) and outward normal; NaN when ``none``
    sigma : (N,) spin torque about the normal, N·m
    h : (N, 3) tangential spin torque, N·m; ``h_norm`` its magnitude
    h_std : (N,) standard deviation of ``h`` (``sqrt(trace Σ_h)``: the sensor noise's and the depth's), N·m
    direction : (N, 3) unit direction of the edge / strip; NaN unless ``line``
    angle, angle_std : (N,) its angle in the tangent frame of the manual (§3.4) and the angle's
        standard deviation, rad; NaN unless ``line``
    angle_noise_std : (N,) the share of ``angle_std`` that is the sensor noise's alone, rad
        (the window's noise term, or the sample's); ``angle_std² − angle_noise_std²`` is the
        model error the estimator counts (``evidence_model_std``, ``window_model_std``,
        ``unconfirmed_model_std``, the window's across-axis spread), which two sensors on one object share and their
        noise is not (:mod:`softtip.fusion`); NaN unless ``line``
    latched : (N,) the contact point is the latched one (not this sample's own solution)
    latch_fallback : (N,) that latch had no light-force sample (manual §3.6)
    pulling : (N,) in contact by force but no pushing contact point (reported ``none``)
    taring : (N,) sample used for the bias (reported ``none``)
    bias : (6,) the bias subtracted, N and N·m
    tare_force_std : float, N: the largest standard deviation of a force component over
        the tare samples (NaN without a tare). Far above the noise model and changing
        slowly, the fingertip was touched while taring and the bias is wrong; changing from
        one sample to the next as white noise, the sensor is that much noisier (the tare's
        warnings say which).
    relatched : (N,) a new latch starts at this sample, replacing an earlier one (drift at
        light force, or contact regained after a latched contact); an event, not masked
    depth : (N,) depth compensation ``δ`` used, m (0 with the papers' method); NaN when ``none``
    depth_std : (N,) its standard deviation, m (online depth; 0 for a fixed law or none)
    depth_from_data : (N,) online depth: the contact's own data, not the skin law (the
        prior), determined it (the data's information on it exceeds the prior's)
    line_fit_conditioning, line_fit_angle_std, line_fit_offset_std, line_fit_residual : (N,) the
        ``line-fit`` window ending at this sample (:mod:`softtip.core.line_fit`): reciprocal condition
        number in [0, 1], standard deviations of its line angle (rad) and of its offset
        across the line (m), and the fit's RMS residual in units of the noise; NaN where no
        window was solved (other modes, ``none``, or no soft-finger solution)
    line_fit_fallback : (N,) ``line-fit`` mode: no window of this contact accepted yet, so the
        point is the latched one
    repeated_stamps : int
        samples whose time equals the previous sample's (accepted; time must not go back)
    contact_id : (N,) 1, 2, … for the first, second, … contact (onset above the contact
        threshold, release below the release threshold); 0 out of contact. A contact may have
        ``none`` samples (pulling, no contact point yet)
    drift : (N, 6) bias drift tracked while untouched since the tare, N and N·m: subtracted
        from this sample's wrench unless ``drift_tracking`` is off
    tare : TareReport or None
        what the tare did and its checks (:class:`~softtip.estimator.tare.TareReport`)
    started_in_contact : bool
        the first contact after the tare pulled for at least 0.1 s: the fingertip was
        probably touched while taring (the release reads as a pull)
    drift_alarm : bool
        the tracked drift of the force exceeded the contact threshold
    warnings : tuple of str
        every warning about these estimates, in plain language (also issued as
        :class:`EstimatorWarning`)
    line_evidence : (N,) int8 codes into :data:`EVIDENCE`: ``confirmed`` when the contact
        was excited about two tangent axes and ``h`` stayed on one, ``unconfirmed`` when the
        excitation so far cannot tell a line from an area; 0 (empty) unless ``line``
    h_ratio : (N,) smaller / larger eigenvalue of ``h``'s covariance over the evidence
        window (noise removed; NaN where ``h`` did not vary beyond the noise or ``none``)
    excitation_ratio : (N,) the same for the tangential load (how far it turned)
    """

    t: NDArray[np.float64]
    state: NDArray[np.int8]
    wrench: NDArray[np.float64]
    point: NDArray[np.float64]
    normal: NDArray[np.float64]
    sigma: NDArray[np.float64]
    h: NDArray[np.float64]
    h_norm: NDArray[np.float64]
    h_std: NDArray[np.float64]
    direction: NDArray[np.float64]
    angle: NDArray[np.float64]
    angle_std: NDArray[np.float64]
    angle_noise_std: NDArray[np.float64]
    latched: NDArray[np.bool_]
    latch_fallback: NDArray[np.bool_]
    pulling: NDArray[np.bool_]
    taring: NDArray[np.bool_]
    bias: NDArray[np.float64]
    relatched: NDArray[np.bool_]
    depth: NDArray[np.float64]
    line_fit_conditioning: NDArray[np.float64]
    line_fit_angle_std: NDArray[np.float64]
    line_fit_offset_std: NDArray[np.float64]
    line_fit_residual: NDArray[np.float64]
    line_fit_fallback: NDArray[np.bool_]
    line_evidence: NDArray[np.int8]
    h_ratio: NDArray[np.float64]
    excitation_ratio: NDArray[np.float64]
    tare_force_std: float = math.nan
    repeated_stamps: int = 0
    contact_id: NDArray[np.int64] | None = None
    drift: NDArray[np.float64] | None = None
    tare: Any = None
    started_in_contact: bool = False
    drift_alarm: bool = False
    warnings: tuple[str, ...] = ()
    depth_std: NDArray[np.float64] | None = None
    depth_from_data: NDArray[np.bool_] | None = None

    def __len__(self) -> int:
        return len(self.t)

    @property
    def state_names(self) -> NDArray[np.str_]:
        """``state`` as strings, shape (N,)."""
        return np.asarray(STATES)[self.state]

    @property
    def n_contacts(self) -> int:
        """Contacts in the log (each onset counted once, however long it lasts)."""
        return int(self.contact_id.max()) if self.contact_id is not None and len(self.contact_id) else 0

    @property
    def n_pulling(self) -> int:
        """Samples in contact by force whose force pulls at every root (reported ``none``)."""
        return int(np.count_nonzero(self.pulling))

    def to_arrow(self, units: str = "si") -> Any:
        """The output columns (:meth:`columns`) as a ``pyarrow.Table``, without writing a file.

        Parameters
        ----------
        units : {"si", "kgf-mm"}
            Units of the force and moment columns, as :meth:`columns`.

        Returns
        -------
        pyarrow.Table
            One column per output column, in order; ``state`` and ``line_evidence`` as strings.
        """
        import pyarrow as pa

        types = {c.name: pa.string() if c.dtype == "str" else pa.from_numpy_dtype(_NUMPY_TYPES[c.dtype]) for c in COLUMNS}
        return pa.table({name: pa.array(v.tolist() if types[name] == pa.string() else v, type=types[name])
                         for name, v in self.columns(units=units).items()})  # fmt: skip

    def to_pandas(self, units: str = "si") -> Any:
        """The output columns as a ``pandas.DataFrame`` (pandas is not a dependency of softtip).

        Raises
        ------
        ImportError
            pandas is not installed; the message says how to get it.
        """
        try:
            import pandas  # noqa: F401
        except ImportError:
            raise ImportError("Estimates.to_pandas needs pandas (pip install pandas); to_arrow gives a pyarrow.Table without it") from None
        return self.to_arrow(units).to_pandas()

    def columns(self, units: str = "si") -> dict[str, NDArray]:
        """The output columns (:data:`softtip.estimator.columns.COLUMNS`, manual §4), in order.

        Parameters
        ----------
        units : {"si", "kgf-mm"}
            Units of the force (N or kgf) and moment (N·m or kgf·mm) columns: the wrench,
            ``sigma``, ``h``, ``h_norm``, ``h_std`` and the drift. Lengths are always in m,
            angles in degrees.
        """
        columns = {}
        for c in COLUMNS:
            values = getattr(self, c.attr)
            if values is None:  # an optional attribute not filled (contact_id, drift, depth_std, depth_from_data)
                continue
            if c.index is not None:
                values = values[:, c.index]
            if c.codes is not None:
                values = np.asarray(c.codes)[values]
            else:  # the registry's type (no copy where the stage made it so already)
                values = np.asarray(values, dtype=_NUMPY_TYPES[c.dtype])
                if c.degrees:
                    values = np.degrees(values)
            columns[c.name] = values
        if units != "si":
            force, moment = wrench_to_si(np.ones(6), units)[[0, 3]]  # one kgf in N, one kgf·mm in N·m
            for c in COLUMNS:
                if c.name in columns and c.unit in ("N", "N·m"):
                    columns[c.name] = columns[c.name] / (force if c.unit == "N" else moment)
        return columns


class SampleEstimate(NamedTuple):
    """One sample of :class:`Estimator` output; fields as in :class:`Estimates` (floats).

    A named tuple: cheap to create at sensor rate, immutable.
    """

    t: float
    state: str
    wrench: tuple[float, ...]
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    sigma: float
    h: tuple[float, float, float]
    h_norm: float
    h_std: float
    direction: tuple[float, float, float]
    angle: float
    angle_std: float
    latched: bool
    latch_fallback: bool
    pulling: bool
    taring: bool
    relatched: bool = False
    depth: float = math.nan
    line_fit_conditioning: float = math.nan
    line_fit_angle_std: float = math.nan
    line_fit_offset_std: float = math.nan
    line_fit_residual: float = math.nan
    line_fit_fallback: bool = False
    contact_id: int = 0
    drift: tuple[float, ...] = (0.0,) * 6
    depth_std: float = math.nan
    depth_from_data: bool = False
    line_evidence: str = ""
    h_ratio: float = math.nan
    excitation_ratio: float = math.nan
    angle_noise_std: float = math.nan

