"""The estimator: tare, filter, contact onset, contact point, measurement.

:func:`estimate` runs it over a whole log, vectorised (:mod:`.batch`); :class:`Estimator`
runs it one sample at a time for live use (:mod:`.stream`). Each stage has its batch and its
stream form side by side in one module: :mod:`.tare`, :mod:`.latch`, :mod:`.line_fit`,
:mod:`.depth`, :mod:`.measure`; settings are in :mod:`.config`, results in :mod:`.results`. Both forms call
the same kernels (:mod:`softtip.core.location`, :mod:`softtip.core.spin`, :mod:`softtip.core.noise`) and
agree to rounding.

Per sample (manual §3):

1. **Tare** (:mod:`.tare`). Unless a bias is given, the samples in the first
   ``tare_duration`` seconds make the bias (``tare_method``: by default their mean without
   spikes); those samples are reported as ``none`` (``taring``). The fingertip must not be
   touched then: the tare is checked against the noise model (spikes, force and moment
   noise) and a first contact that pulls from its onset (the release of a tare taken in
   contact) is flagged; :attr:`Estimates.tare` / :attr:`Estimator.tare_report` say what
   happened, :attr:`Estimates.warnings` (also issued as :class:`EstimatorWarning`) what is
   wrong. :meth:`Estimator.tare` tares again on demand.
2. **Filter** (optional): causal Butterworth low-pass, steady state at the first sample.
3. **Contact** (:mod:`.contact`): onset at ``|f| ≥ contact_threshold`` (and 4.5 noise standard deviations), release below a
   threshold lower by ``contact_hysteresis`` noise standard deviations, after at least
   ``min_contact_duration``; contacts numbered (``contact_id``). While untouched the bias
   drift is followed (``drift_time_constant``) and, with ``drift_tracking``, subtracted.
4. **Contact point.** ``track``: the soft-finger solution of every sample. ``latch`` (the
   papers'): during the first rise of the force after onset (until ``|f|`` first exceeds the
   light-force window, or sets no new maximum for ``stall_time``), the soft-finger solutions
   of the samples inside the window are averaged; that mean, put back on the skin, is the
   contact point from then on, until contact ends. Before the first window sample the
   current soft-finger solution is used. With no window sample in the whole rise, the mean
   of the first ``fallback_samples`` solutions of the contact is latched and flagged.
5. **Depth** (:mod:`.depth`, softtip's, issue 11): friction acts inside the skin, so the
   moment is taken about ``r − δ n``; with a skin law (the fingertip's ``skin_thickness``,
   or ``skin_law``) ``δ`` is learnt per contact from a window of the data, the law its prior
   (``depth_compensation="online"``, the default then), or the law's as it is (``"law"``);
   ``"off"`` is the papers' undeformed point. ``depth``, ``depth_std`` and
   ``depth_from_data`` report it.
6. **Measurement**: spin torque, its tangential part ``h``, the noise level of ``h`` and
   whether ``|h|`` is significant.
7. **Line evidence** (:mod:`.evidence`): over a sliding window, the state ``point``,
   ``line`` or ``area``, the line's ``line_evidence`` (``confirmed`` once the contact was
   excited about two tangent axes and ``h`` stayed on one, else ``unconfirmed``) and, for
   ``line`` only, the direction (under confirmed evidence the window's) and its angle with a
   standard deviation.

In ``track`` mode ``h`` is zero by construction (the soft-finger model puts all of ``q``
along ``n``), so only ``point`` contacts are reported: use ``latch`` for directions.

softtip's extensions (issue 5), each an :class:`EstimatorConfig` field:

- ``relatch_distance``: once the latch is held, a sample at light force (inside the
  window) whose soft-finger solution lies farther than this from the latched point starts
  a new latch (a new first rise, from that sample); ``relatched`` flags that sample, and
  the first sample of every contact that follows a latched one (contact lost and regained).
- ``skin_law``, ``depth_compensation``: see step 5 (:mod:`softtip.core.depth`, :mod:`.depth`).
- ``contact_point="line-fit"``: the latch of ``latch`` mode, then the contact point moved
  across the line to where a window of the last ``line_fit_window`` seconds fits the line
  contact model (:mod:`softtip.core.line_fit`). A window is accepted when its standard deviations
  of line angle and offset are below ``line_fit_max_angle_std`` and ``line_fit_max_offset_std``
  and its fit residual below ``line_fit_max_residual`` noise standard deviations. The point
  held is the accepted window since contact onset (or the last re-latch) with the
  smallest standard deviation aged by ``line_fit_drift``; before the first one the latched
  point is used and ``line_fit_fallback`` set. The coordinate along the line is the latch's:
  a line contact does not tell it.
"""

from softtip.estimator.batch import estimate
from softtip.estimator.config import CONTACT_POINT_MODES, EstimatorConfig
from softtip.estimator.results import (
    AREA,
    EVIDENCE,
    LINE,
    NONE,
    POINT,
    STATES,
    Estimates,
    EstimatorWarning,
    SampleEstimate,
)
from softtip.estimator.stream import Estimator

__all__ = [
    "STATES", "NONE", "POINT", "LINE", "AREA", "EVIDENCE", "CONTACT_POINT_MODES", "EstimatorConfig", "Estimates",
    "SampleEstimate", "Estimator", "estimate", "EstimatorWarning",
]  # fmt: skip
