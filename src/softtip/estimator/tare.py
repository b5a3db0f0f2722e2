"""Tare: the sensor bias from the first samples, while the fingertip is untouched, checked.

Unless a bias is given, the samples in the first ``tare_duration`` seconds make the bias
(``tare_method``: ``robust``, the default, the mean of those that are not spikes;
``median``, per component; ``mean``, of all); those samples are reported as ``none``
(``taring``). :func:`tare_log` does it for a whole log,
:class:`StreamTare` one sample at a time; both take a sample by the same
comparison, :func:`in_tare` (``t − t₀`` short of ``tare_duration`` by more than
:data:`~softtip.core._blocks.TIME_EDGE`), so they agree on the boundary sample, and the same
:func:`tare_from_samples`, which also checks the samples against the noise model
(:class:`TareReport`):

- **spikes**: a sample farther than :data:`SPIKE_SIGMAS` standard deviations from the median
  (the larger of the noise model and the samples' own robust spread) in any component; the
  robust and median tares ignore it, the mean does not (one −20 N spike among ten samples
  moves a mean bias by 2 N);
- **touched while taring**: the standard deviation of the other samples above
  :data:`TOUCHED_RATIO` times the noise model, in force or in moment, unless the samples
  change from one to the next as much as independent ones do (:data:`WHITE_RATIO`): a touch
  moves the wrench slowly next to the sample period, a sensor noisier than its model does
  not, and is reported as that;
- in ``line-fit`` mode, force noise above the noise model by more than the margin line-fit mode
  allows for (it would take the excess for excitation).

The tare also measures the noise model (``noise_from_tare``, ``"auto"`` by default;
:attr:`TareReport.noise`, :func:`noise_in_use`): each axis's standard deviation over the
samples without spikes, which ``"auto"`` uses where it is larger than the configured model's.

:meth:`softtip.Estimator.tare` re-tares on demand from the next samples;
:func:`load_bias` reads a bias file (``--bias FILE``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._blocks import TIME_EDGE
from softtip.core.line_fit import MODEL_MARGIN
from softtip.core.noise import MAD_TO_STD, SensorNoise
from softtip.errors import InputError
from softtip.estimator.config import EstimatorConfig
from softtip.tomlfile import read_toml_table

__all__ = [
    "SPIKE_SIGMAS",
    "TOUCHED_RATIO",
    "TOUCHED_REMEDY",
    "WHITE_RATIO",
    "NOISE_MIN_SAMPLES",
    "in_tare",
    "TareReport",
    "noise_in_use",
    "tare_from_samples",
    "successive_ratio",
    "tare_log",
    "LogTare",
    "StreamTare",
    "load_bias",
    "bias_to_toml",
]

#: A tare sample this many standard deviations from the median (in any component) is a spike.
SPIKE_SIGMAS = 8.0
#: The tare's noise this many times the noise model: the fingertip was touched while taring.
TOUCHED_RATIO = 5.0
#: A tare's spread beyond :data:`TOUCHED_RATIO` is the sensor's own noise, not a touch, when
#: successive samples differ as much as independent ones: the mean square of their differences
#: over twice the variance (von Neumann's ratio, :func:`successive_ratio`), over the axes
#: beyond, at least this. White noise gives about 1 (below 0.5 on 12 % of 10-sample tares on
#: one axis, 1.4 % over three, 5 % and 0.2 % from 30 samples, none from 200); a press five
#: times the noise spanning the tare 0.3 over 10 samples (at most 0.46 over 1000 draws), 0.1
#: over 200, the noise's own share (a change slow next to the sample period moves neighbours
#: alike). Noise that the sensor's own filter correlates from sample to sample reads as a
#: touch: the cautious side; so does white noise below the bar (the model kept, as before).
WHITE_RATIO = 0.5
#: What a fingertip touched while taring leaves the user to do, for the estimator's inputs
TOUCHED_REMEDY = (
    "tare again untouched, give a bias (bias, --bias), or tare_duration 0 (--tare-duration 0) for an input that is "
    "already tared"
)
#: The tare's noise below this share of the noise model on every axis, over at least
#: :data:`OVERSTATED_MIN_SAMPLES` samples (its standard deviation then known to about 13 %):
#: the model overstates the sensor's noise, and the summary says so.
OVERSTATED_RATIO = 0.6
OVERSTATED_MIN_SAMPLES = 30
#: ``noise_from_tare`` measures the noise from at least this many tare samples (spikes left
#: out): a standard deviation from k samples is known to about ``1 / sqrt(2 (k - 1))``, 13 % here.
NOISE_MIN_SAMPLES = OVERSTATED_MIN_SAMPLES
#: ``noise_from_tare="auto"`` raises the model from at least this many (the default 0.2 s tare
#: at 50 Hz): it only raises, so a standard deviation known to about 24 % errs on the safe
#: side (about 10 % above a model that was right, on average), where one too small from a
#: short tare would be lowered by ``"on"``
RAISE_MIN_SAMPLES = 10
_AXES = ("fx", "fy", "fz", "mx", "my", "mz")
_CHI2_1_MEDIAN = 0.454936423119572  # the median of a χ²₁: of (x/σ)² for a normal x


_LABELS = {"robust": "mean without spikes", "median": "median", "mean": "mean"}


def in_tare(elapsed: float | NDArray[np.float64], duration: float) -> bool | NDArray[np.bool_]:
    """Whether a sample ``elapsed`` s after the tare's first (s; float or array) is one of the
    tare's ``duration`` s: ``elapsed < duration − TIME_EDGE`` (a sample at the end is not), for
    the batch and the stream. Time stamps are not exact in binary: at 10 Hz from ``t₀ = 1.3`` s
    the sample at 2.3 s is ``0.9999999999999998`` s after ``t₀``, so a bare ``t − t₀ < 1`` took 11
    samples into a 1 s tare there and 10 from 0 s."""
    return elapsed < duration - TIME_EDGE


@dataclass(frozen=True)
class TareReport:
    """What the tare did, and whether it can have been right. SI units.

    Attributes
    ----------
    bias : (6,) N and N·m; NaN when a log never leaves the tare period
    source : {"tare", "given", "none"}
        ``tare``: from the samples; ``given``: ``config.bias`` (or a bias file); ``none``:
        ``tare_duration`` 0, the input is taken as tared.
    method : {"robust", "median", "mean"}
    n_samples : int
        Samples the bias was made of (0 unless ``source == "tare"``).
    duration : float
        s, ``tare_duration`` asked for.
    force_std, moment_std : (3,) N and N·m
        Standard deviation of each component over the tare samples, spikes left out (NaN
        with fewer than two samples).
    noise_ratio : float
        Largest ratio of ``force_std`` / ``moment_std`` to the noise model (NaN without a
        model or samples).
    spikes : int
        Tare samples more than :data:`SPIKE_SIGMAS` standard deviations from the median.
    spike_shift : float
        N; how far the spikes moved the force of a ``mean`` bias (0 for the others, which
        ignore them).
    warnings : tuple of str
        Plain-language warnings (also in :attr:`softtip.Estimates.warnings`).
    noise : SensorNoise or None
        The noise model the tare measured and the estimate uses from then on
        (``noise_from_tare``: ``"on"`` the measured standard deviations, ``"auto"`` the
        configured ones raised to them); ``None`` where the configured model is used: not
        asked for, not measurable (under ``"on"`` a warning says why) or, under ``"auto"``,
        no axis noisier than the model.
    noise_raised : bool
        ``noise`` is the configured model raised to the measured one where that is larger
        (``noise_from_tare="auto"``), not the measured one on every axis.
    """

    bias: NDArray[np.float64]
    source: str = "tare"
    method: str = "robust"
    n_samples: int = 0
    duration: float = 0.0
    force_std: NDArray[np.float64] = field(default_factory=lambda: np.full(3, np.nan))
    moment_std: NDArray[np.float64] = field(default_factory=lambda: np.full(3, np.nan))
    noise_ratio: float = math.nan
    spikes: int = 0
    spike_shift: float = 0.0
    warnings: tuple[str, ...] = ()
    noise: SensorNoise | None = None
    noise_raised: bool = False

    def summary(self, retared_at: float | None = None) -> str:
        """One line: where the bias came from and its value (N, N·mm); for a tare, the noise of
        its samples against the noise model (and whether the model overstates it).
        ``retared_at``: t (s) of a tare asked for again (:meth:`Estimator.tare`), where it began."""
        f, m = self.bias[:3], self.bias[3:] * 1e3
        span = f"{self.duration:g} s" if retared_at is None else f"{self.duration:g} s of the re-tare at t = {retared_at:g} s"
        what = {
            "tare": f"from the first {span} ({self.n_samples} samples, {_LABELS[self.method]})",
            "given": "given",
            "none": "none (input already tared)",
        }[self.source]
        line = (
            f"bias {what}: force ({f[0]:+.4f}, {f[1]:+.4f}, {f[2]:+.4f}) N, "
            f"moment ({m[0]:+.4f}, {m[1]:+.4f}, {m[2]:+.4f}) N·mm"
        )
        if self.source == "tare" and math.isfinite(self.noise_ratio):
            line += (
                f"; their noise up to {np.nanmax(self.force_std) * 1e3:.2g} mN and "
                f"{np.nanmax(self.moment_std) * 1e3:.2g} N·mm, {self.noise_ratio:.2g} times the noise model"
            )
            if self.noise is None and self.n_samples >= OVERSTATED_MIN_SAMPLES and self.noise_ratio < OVERSTATED_RATIO:
                line += (
                    " (which overstates this sensor's noise: the reported standard deviations are conservative; "
                    "give its noise model, --force-noise and --moment-noise, or measure it, --noise-from-tare on)"
                )
        if self.noise is not None:
            fn, mn = np.asarray(self.noise.force_std) * 1e3, np.asarray(self.noise.moment_std) * 1e3
            how = "raised to theirs where larger" if self.noise_raised else "measured from them"
            line += (
                f"; noise model {how}: force ({fn[0]:.3g}, {fn[1]:.3g}, {fn[2]:.3g}) mN, "
                f"moment ({mn[0]:.3g}, {mn[1]:.3g}, {mn[2]:.3g}) N·mm"
            )
        return line


def noise_in_use(config: EstimatorConfig, report: TareReport | None) -> SensorNoise:
    """The unfiltered noise model of the estimates after a tare.

    Parameters
    ----------
    config : EstimatorConfig
    report : TareReport or None
        The tare's report (``None``: no tare yet).

    Returns
    -------
    SensorNoise
        The model the tare measured (``noise_from_tare``), else ``config.noise``.
    """
    if report is not None and report.noise is not None:
        return report.noise
    return config.noise


def successive_ratio(samples: NDArray) -> float:
    """Von Neumann's ratio of ``samples`` (k, a), pooled over the ``a`` axes (of one unit): the
    mean square of successive differences over twice the variance, each summed over the axes,
    so an axis moves it by its share of the spread (1 for white noise, near 0 for a change slow
    next to the sample period; :data:`WHITE_RATIO`). The smaller of that and the same ratio
    from medians (of the squared differences, over the median of a χ²₁, and of the absolute
    deviations, times 1.4826), which one sample off the others cannot raise: a glitch below the
    spike bar inside a press makes two large differences. NaN from fewer than 3 samples or
    samples that never change."""
    x = np.asarray(samples, dtype=float)
    if len(x) < 3:
        return math.nan
    d2 = np.diff(x, axis=0) ** 2
    var = float(np.sum(np.var(x, axis=0, ddof=1)))
    if not var > 0.0:
        return math.nan
    ratio = float(np.sum(np.mean(d2, axis=0))) / (2.0 * var)
    spread = float(np.sum((MAD_TO_STD * np.median(np.abs(x - np.median(x, axis=0)), axis=0)) ** 2))
    if spread > 0.0:  # (more than half the samples alike on every axis: the mean form alone)
        ratio = min(ratio, float(np.sum(np.median(d2, axis=0))) / _CHI2_1_MEDIAN / (2.0 * spread))
    return ratio


def _measured_noise(clean: NDArray, std: NDArray, model: NDArray, touched: bool) -> tuple[SensorNoise | None, str]:
    """The noise model of ``noise_from_tare`` and why it is not (or only partly) used.

    ``clean`` (k, 6): the tare's samples without spikes; ``std`` (6,) their per-axis standard
    deviations; ``model`` (6,) the configured model's; ``touched``: the tare looked touched.
    An axis read on a grid of step ``q`` (a quantised sensor) has at least ``q / √12`` of
    rounding error whatever the samples' spread, so its measured standard deviation is not
    taken below that; an axis that never changed keeps the configured value.
    """
    keep = "the configured noise model is used"
    n_clean = len(clean)
    if n_clean < NOISE_MIN_SAMPLES:
        return None, (
            f"noise_from_tare: {n_clean} tare samples (spikes left out), fewer than the {NOISE_MIN_SAMPLES} a "
            f"measurement of the noise needs; {keep} (tare longer: tare_duration, --tare-duration)"
        )
    if touched:
        return None, (
            f"noise_from_tare: the tare's samples varied more than {TOUCHED_RATIO:g} times the configured noise "
            f"model, as if touched; {keep} (if the fingertip was untouched, the sensor is that much noisier: give "
            "a larger model, --force-noise and --moment-noise)"
        )
    still = np.ptp(clean, axis=0) == 0.0  # (its std need not come out exactly 0)
    if np.all(still):
        return None, f"noise_from_tare: no axis changed over the {n_clean} tare samples; {keep}"
    steps = np.diff(np.sort(clean, axis=0), axis=0)
    step = np.min(np.where(steps > 0.0, steps, np.inf), axis=0)  # inf where still
    std = np.where(still, model, np.maximum(std, step / math.sqrt(12.0)))
    measured = SensorNoise(tuple(std[:3]), tuple(std[3:]))
    if np.any(still):
        axes = ", ".join(a for a, s in zip(_AXES, still) if s)
        return measured, (
            f"noise_from_tare: {axes} did not change over the {n_clean} tare samples (below the sensor's "
            "resolution?); the configured noise is kept for them"
        )
    return measured, ""


def _given(config: EstimatorConfig) -> TareReport:
    if config.bias is not None:
        return TareReport(np.asarray(config.bias, dtype=float), "given", config.tare_method, 0, config.tare_duration)
    return TareReport(np.zeros(6), "none", config.tare_method, 0, 0.0)


def tare_from_samples(
    samples: NDArray, config: EstimatorConfig, duration: float | None = None, *, touched_remedy: str = TOUCHED_REMEDY
) -> TareReport:
    """The bias of the tare samples ``samples`` (k, 6), with its checks.

    Parameters
    ----------
    samples : ndarray, shape (k, 6)
        Raw wrench while taring, N and N·m.
    config : EstimatorConfig
        ``tare_method``, the noise model and, for the joint-mode check, ``contact_point``.
    duration : float, optional
        s of the tare (default ``config.tare_duration``), for the messages.
    touched_remedy : str
        What to do when the samples vary beyond the noise model (a fingertip touched while
        taring), in that warning's parentheses: the caller's own options (default the
        estimator's, :data:`TOUCHED_REMEDY`).
    """
    s = np.asarray(samples, dtype=float).reshape(-1, 6)
    duration = config.tare_duration if duration is None else float(duration)
    k = len(s)
    if not k:
        return TareReport(np.full(6, np.nan), "tare", config.tare_method, 0, duration)
    med = np.median(s, axis=0)
    model = np.array(config.noise.force_std + config.noise.moment_std)
    dev = np.abs(s - med)
    spread = MAD_TO_STD * np.median(dev, axis=0)
    scale = np.maximum(np.maximum(model, spread), 1e-12 * (1.0 + np.abs(med)))
    spike = np.any(dev > SPIKE_SIGMAS * scale, axis=1)
    clean = s[~spike]
    robust = np.mean(clean, axis=0) if len(clean) else med
    bias = {"robust": robust, "median": med, "mean": np.mean(s, axis=0)}[config.tare_method]
    std = np.std(clean, axis=0, ddof=1) if len(clean) > 1 else np.full(6, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(model > 0, std / np.where(model > 0, model, 1.0), np.nan)
    noise_ratio = float(np.nanmax(ratio)) if np.any(np.isfinite(ratio)) else math.nan
    shift = float(np.linalg.norm(bias[:3] - robust[:3])) if config.tare_method == "mean" else 0.0
    n_spikes = int(np.count_nonzero(spike))

    warn = []
    if n_spikes:
        largest = float(np.max(dev[spike, :3])) if np.any(dev[spike, :3] > SPIKE_SIGMAS * scale[:3]) else 0.0
        what = f"{n_spikes} spike(s) among the {k} tare samples" + (f" (up to {largest:.3g} N off the median)" if largest else "")
        if config.tare_method == "mean":
            warn.append(
                f"{what}: the mean bias is {shift:.3g} N off in force (from the mean without them), and every "
                "estimate with it; use the robust tare (tare_method='robust', --tare-method robust) or re-tare"
            )
        else:
            warn.append(f"{what}, left out of the {config.tare_method} tare")
    touched = False
    noisy = []  # (what varied, how much): beyond the model as white noise, not as a touch
    for name, sl, unit, fmt in (("force", slice(0, 3), "N", 1.0), ("moment", slice(3, 6), "N·mm", 1e3)):
        r = ratio[sl]
        over = r > TOUCHED_RATIO
        if not np.any(over):
            continue
        varied = (
            f"the {name} varied by {np.nanmax(std[sl]) * fmt:.3g} {unit} (standard deviation) while taring, "
            f"{np.nanmax(r):.3g} times the noise model ({np.max(model[sl]) * fmt:g} {unit})"
        )
        eta = successive_ratio(clean[:, sl][:, over])
        if eta >= WHITE_RATIO:
            noisy.append(varied)
            continue
        touched = True  # (also where too few samples tell: NaN)
        how = ", slowly as a touch moves it" if eta < WHITE_RATIO else ""
        warn.append(
            f"{varied}{how}: was the fingertip touched in the first {duration:g} s? The "
            f"bias, and every estimate, would then be wrong ({touched_remedy}); if it was not, the sensor is that "
            "much noisier than the model, which is then kept as given: give its noise model (--force-noise, "
            "--moment-noise)"
        )
    measured = None
    if config.noise_from_tare == "on":
        measured, why = _measured_noise(clean, std, model, touched)
        if why:
            warn.append(why)
    elif (
        config.noise_from_tare == "auto"
        and len(clean) >= (NOISE_MIN_SAMPLES if noisy else RAISE_MIN_SAMPLES)
        and not touched
        and np.isfinite(std).all()
    ):
        # raised to what the tare shows, never lowered: a model given larger is kept; an axis
        # that did not change at all (a quantised or noise-free one) raises nothing (its std
        # need not come out exactly 0). Beyond TOUCHED_RATIO the measurement all but replaces
        # the model, so it takes as many samples as "on": from 10 a standard deviation 24 %
        # low on some axis makes the evidence window read noise as a varying h (rocked planes
        # on Drake's contact at 50 Hz, 3 times the benchmarks' noise, raised from 10 samples:
        # `line` on 15 % of the samples over four noise seeds; none with the preset kept)
        raised = np.where(np.ptp(clean, axis=0) > 0.0, np.maximum(std, model), model)
        if np.any(raised > model):
            measured = SensorNoise(tuple(raised[:3]), tuple(raised[3:]))
    for varied in noisy:
        if measured is not None:
            use = "which the estimate uses from now on (noise_from_tare, --noise-from-tare)"
        elif config.noise_from_tare == "off":
            use = "which is kept as given"
        elif touched:
            use = "which is kept while the tare also looks touched"
        elif not np.isfinite(std).all():
            use = "which is kept: a tare sample is not a number"
        elif config.noise_from_tare == "on":
            use = "which is kept (the noise_from_tare warning says why)"
        else:
            use = (
                f"which is kept: {len(clean)} tare samples (spikes left out) are too few to measure a noise this far "
                f"above the model ({NOISE_MIN_SAMPLES} needed: tare longer, tare_duration, --tare-duration)"
            )
        warn.append(
            f"{varied}, from one sample to the next as independent noise does, not slowly as a touch: the sensor "
            f"is that much noisier than the model, {use}; give its noise model (--force-noise, --moment-noise)"
        )
    fstd = float(np.nanmax(std[:3])) if k > 1 else math.nan
    fmodel = float(np.max(model[:3]))
    if (
        measured is None
        and config.contact_point == "line-fit"
        and k > 2
        and fmodel > 0
        and fstd <= TOUCHED_RATIO * fmodel
        and fstd > fmodel * math.sqrt(1.0 + MODEL_MARGIN) * (1.0 + 2.0 / math.sqrt(2.0 * (len(clean) - 1)))
    ):
        # two standard errors of the tare's own estimate of the noise on top of the margin
        warn.append(
            f"the force noise while taring ({fstd:.3g} N standard deviation) exceeds the noise model "
            f"({fmodel:g} N); contact_point='line-fit' would take the excess noise for excitation at high sample "
            "rates: give this sensor's noise model (--force-noise, --moment-noise)"
        )
    return TareReport(
        bias, "tare", config.tare_method, k, duration, std[:3], std[3:], noise_ratio, n_spikes, shift, tuple(warn),
        noise=measured, noise_raised=config.noise_from_tare == "auto",
    )


def tare_log(t: NDArray, w: NDArray, config: EstimatorConfig) -> LogTare:
    """The bias of a whole log ``w`` (N, 6) sampled at ``t`` (N,).

    Returns :class:`LogTare`; the bias is NaN when the log never
    leaves the tare period (as in the stream).
    """
    n = len(t)
    taring = np.zeros(n, dtype=bool)
    if config.bias is not None or config.tare_duration <= 0 or not n:
        rep = _given(config)
        return LogTare(rep.bias, taring, rep)
    n_tare = int(np.count_nonzero(in_tare(t - t[0], config.tare_duration)))
    taring[:n_tare] = True
    rep = tare_from_samples(w[:n_tare], config)
    if n_tare == n:
        msg = (
            f"the whole log lies within the first {config.tare_duration:g} s used to tare the sensor; nothing was "
            "estimated (tare_duration 0, --tare-duration 0, for a log that is already tared)"
        )
        rep = TareReport(np.full(6, np.nan), **{**_fields(rep), "warnings": rep.warnings + (msg,)})
    return LogTare(rep.bias, taring, rep)


class LogTare(NamedTuple):
    """What :func:`tare_log` gives for a whole log (N samples)."""

    bias: NDArray  #: (6,) N and N·m, the sensor bias (NaN when the log never leaves the tare period)
    taring: NDArray  #: (N,) bool, the samples the tare used
    report: TareReport  #: how the bias was found, and its warnings


def _fields(rep: TareReport) -> dict:
    return {k: getattr(rep, k) for k in TareReport.__dataclass_fields__ if k != "bias"}


class StreamTare:
    """The tare of :func:`tare_log`, one sample at a time.

    :meth:`update` returns ``None`` while taring, then the bias; the samples it was made of
    are in :attr:`samples` until :meth:`release` (the stream primes its filter with them, as
    the batch filters the whole log). :attr:`report` is the :class:`TareReport` once the
    bias is known.
    """

    def __init__(self, config: EstimatorConfig):
        self.config = config
        self.reset()

    def reset(self, duration: float | None = None) -> None:
        """Forget the bias and start taring again: from the next ``duration`` s of samples
        when given (tare on demand, even with a given bias), else as the config says."""
        cfg = self.config
        self.samples: list[tuple[float, ...]] = []
        self._t0: float | None = None
        self._duration = cfg.tare_duration if duration is None else float(duration)
        self.bias: tuple[float, ...] | None = None
        self.report: TareReport | None = None
        if duration is None and (cfg.bias is not None or cfg.tare_duration <= 0):
            self.report = _given(cfg)
            self.bias = tuple(float(v) for v in self.report.bias)

    def update(self, t: float, w: list[float]) -> tuple[float, ...] | None:
        """The bias, or ``None`` while sample ``w`` at ``t`` is one of the tare's."""
        if self.bias is not None:
            return self.bias
        if self._t0 is None:
            self._t0 = t
        if in_tare(t - self._t0, self._duration):
            self.samples.append(tuple(w))
            return None
        self.report = tare_from_samples(np.array(self.samples), self.config, self._duration)
        self.bias = tuple(self.report.bias.tolist())
        return self.bias

    def release(self) -> list[tuple[float, ...]]:
        """The tare's samples (once; the buffer is emptied)."""
        s, self.samples = self.samples, []
        return s


def load_bias(path: str | os.PathLike[str]) -> tuple[float, ...]:
    """Read a sensor bias file: TOML with a ``[bias]`` table, ``force = [fx, fy, fz]`` (N) and
    ``moment = [mx, my, mz]`` (N·m), as written by :func:`bias_to_toml`,
    ``softtip estimate --save-bias`` or ``softtip calibrate-payload``.

    Raises
    ------
    InputError
        Missing or unreadable file, malformed TOML, missing or invalid keys; the message
        names the file and the key.
    """
    name = os.fspath(path)
    table = read_toml_table(name, "bias", ("force", "moment"), "force = [fx, fy, fz] (N) and moment = [mx, my, mz] (N·m)")
    out: list[float] = []
    for key, unit in (("force", "N"), ("moment", "N·m")):
        v = table.get(key)
        ok = isinstance(v, list) and len(v) == 3
        ok = ok and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v)
        if not ok:
            raise InputError(f"{name}: [bias] {key} = {v!r}: expected a list of 3 finite numbers in {unit}")
        out.extend(float(x) for x in v)
    return tuple(out)


def bias_to_toml(bias, comment: str = "") -> str:
    """A sensor bias (6,) (N, N·m) as the TOML of :func:`load_bias`."""
    b = [float(v) for v in bias]
    head = f"# {comment}\n" if comment else ""
    return (
        f"{head}[bias]\nforce = [{', '.join(repr(v) for v in b[:3])}]  # N, sensor frame\n"
        f"moment = [{', '.join(repr(v) for v in b[3:])}]  # N·m, sensor frame\n"
    )
