"""``softtip stream``: live estimation from a Net F/T / Axia sensor, or a replayed log."""

from __future__ import annotations

import os
import sys
import warnings
from typing import TYPE_CHECKING

import click

from softtip.cli.options import (
    FRAMES_HELP,
    POSITIVE,
    check_outputs,
    check_units,
    estimator_options,
    full_scale_option,
    full_scale_range,
    is_bag,
    log_format_given,
    log_format_kwargs,
    log_format_names,
    log_format_options,
    make_config,
    optional_extra,
    print_log_notes,
)
from softtip.cli.types import PORT, Number, check_lowpass, option
from softtip.core.fingertip import load_fingertip
from softtip.core.fullscale import COARSE_MARGIN, FullScale, check_full_scale
from softtip.core.units import UNIT_SYSTEMS
from softtip.errors import InputError
from softtip.estimator.results import EstimatorWarning

if TYPE_CHECKING:
    from softtip.apps.live import LiveSummary
    from softtip.estimator import Estimator

__all__ = ["stream"]

#: stream --speed: 0 (as fast as possible) or within these factors of real time
MIN_SPEED, MAX_SPEED = 1e-3, 1e6
#: stream --timeout upper bound, s (a day; longer waits overflow the host's timers)
MAX_TIMEOUT = 86400.0

@click.command(
    "stream",
    help="""Estimate live: from an ATI Net F/T or Axia sensor, or a replayed log.

With --netft HOST softtip reads the calibration (counts per force and torque unit, units)
from the sensor over HTTP (/netftapi2.xml), streams RDT records over UDP, converts them to
SI and runs the streaming estimator on every sample. With --replay
LOG.csv the log is fed through the same path at its recorded rate times --speed (0: as
fast as possible).

Taring: the first --tare-duration seconds (0.2 s) make the sensor bias, so keep
the fingertip untouched when the stream starts (or give --bias FILE); the t key of the
terminal view tares again from the next samples; --device-bias also zeroes the sensor
itself first. The tare is checked (spikes, noise above the noise model, a stream that
starts in contact) and the drift followed while untouched; warnings are shown in the view
and at the end.

The terminal view (standard error, redrawn a few times a second when it is a terminal)
shows the state, contact point, normal, |h|, edge angle ± std, sample rate, and what the
stream went through: packets lost on the network, late and duplicate packets (dropped),
malformed datagrams, samples dropped by softtip's own queue, the device's status word,
restarts and F/T-sequence stalls, and the latest warning; the device's rate (comrdtrate)
is checked against the host clock (a difference over 2 % is warned about). None of these
ends the stream unless named in --strict (then exit 1).

-o FILE.csv (or --record FILE.csv) writes every sample as it comes (flushed every 0.05 s, always whole
lines): t and the raw wrench fx_raw..mz_raw first (the file is a log that `softtip estimate`
and --replay read as it is), then the columns of `softtip estimate` (fx..mz the tared wrench,
as there), then seq (RDT sequence or row), lost and dropped (records missing just
before this one: on the network or still to come late / dropped by this host), late,
duplicates and malformed (discarded since the previous row), status (the device's status
word) and host_time (host receive time, s since the Unix epoch). Ctrl-C, SIGTERM and
SIGHUP stop cleanly (exit 0, every row taken written), also during discovery or a silent
stream; so do --duration and the end of a replayed log. No data for --timeout seconds is
an error (exit 1).

"""
    + FRAMES_HELP
)
@option("--netft", "host", metavar="HOST", help="Address of the Net F/T / Axia.")
@option("--replay", "replay", type=click.Path(dir_okay=False), metavar="LOG", help="Replay a recorded log instead: CSV, or Parquet or Arrow IPC by its name (columns t, fx, fy, fz, mx, my, mz, or a layout the input formats page lists).")
@option("--speed", type=Number("× real time", 0.0, MAX_SPEED), default=1.0, show_default=True, help="Replay speed: 1 real time, 2 twice as fast, 0 as fast as possible.")
@option("--units", type=click.Choice(UNIT_SYSTEMS), default=None, help="Units of the replayed log's wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet or Arrow --replay's own]")
@option("--rdt-port", type=PORT, default=49152, show_default=True, help="UDP port of the sensor's RDT server.")
@option("--http-port", type=PORT, default=80, show_default=True, help="HTTP port of the sensor's web server (calibration).")
@option("--timeout", type=Number("s", 0.0, MAX_TIMEOUT, min_open=True), default=2.0, show_default=True, metavar="S", help="Give up after S seconds without data from the sensor.")
@option("--device-bias", is_flag=True, help="Send the sensor's own bias (zero) command at start, before softtip's tare (the records of the first 0.05 s after it are dropped: the sensor's before it zeroed itself).")
@option("--strict", metavar="FAULTS", default="", help="Comma-separated faults that end the stream (exit 1): status, restart, stall, lost, duplicate, late, malformed, dropped, or all. Default: none (counted, warned).")
@option("--duration", type=POSITIVE("s"), metavar="S", help="Stop after S seconds (default: until Ctrl-C or the end of the replayed log).")
@option("-o", "--output", "--record", "record", type=click.Path(dir_okay=False), metavar="FILE.csv", help="Record raw samples and estimates to FILE.csv as they come (--record is the same option).")
@option("--view/--no-view", default=None, help="Live terminal view (default: when standard error is a terminal, and not with -q).")
@option("-q", "--quiet", is_flag=True, help="Nothing but warnings and errors on standard error (no view unless --view, no tare line, no summary).")
@option("--rerun", "rerun_spawn", is_flag=True, help="Show the 3-D view live in a Rerun viewer (needs the rerun-sdk package; at most 50 samples/s are drawn, by a process at the lowest priority, and the viewer it starts too, so that they never take a core from the estimator: on a busy machine the view lags, the estimates do not).")
@option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save the 3-D view and time series to FILE.rrd.")
@option("--payload", type=click.Path(dir_okay=False), metavar="FILE.toml", help="With --replay: remove the fingertip's weight per sample, using the log's qw, qx, qy, qz columns (recorded raw_* columns are then compensated).")
@full_scale_option
@log_format_options
@estimator_options
@click.pass_context
def stream(
    ctx,
    host,
    replay,
    speed,
    units,
    rdt_port,
    http_port,
    timeout,
    device_bias,
    strict,
    duration,
    record,
    view,
    quiet,
    rerun_spawn,
    rerun_save,
    tip,
    payload=None,
    full_scale=None,
    **estimator_opts,
):

    from softtip.io.netft import FAULTS

    sensor_range = full_scale_range(full_scale, estimator_opts.get("sensor"))  # default: the --sensor's, else a Nano17's

    if (host is None) == (replay is None):
        raise click.UsageError("give either --netft HOST or --replay LOG")
    if payload is not None and replay is None:
        raise click.UsageError("--payload needs the orientation columns of a replayed log (--replay LOG)")
    if 0 < speed < MIN_SPEED:
        raise click.BadParameter(
            f"{speed:g}; expected 0 (as fast as possible) or a number in [{MIN_SPEED:g}, {MAX_SPEED:g}] × real time",
            param_hint="'--speed'",
        )
    faults = {f.strip() for f in strict.split(",") if f.strip()}
    if "all" in faults:
        faults = set(FAULTS)
    if faults - set(FAULTS):
        raise click.UsageError(f"--strict: unknown fault(s) {', '.join(sorted(faults - set(FAULTS)))}; expected some of {', '.join(FAULTS)} or all")
    if faults and host is None:
        raise click.UsageError("--strict applies to a live sensor (--netft HOST)")
    formats = log_format_kwargs(estimator_opts)
    if host is not None and log_format_given(formats):
        raise click.UsageError(f"{log_format_names()} apply to --replay")
    check_outputs(
        [("--replay", replay), ("--payload", payload), ("--tip", tip if os.path.isfile(tip) else None),
         ("--bias", estimator_opts.get("bias_file"))],
        [("-o", record), ("--rerun-save", rerun_save)],
        table_formats=("csv",),  # the recorder writes CSV rows as they come
    )
    from softtip.io.atomic import Outputs

    if quiet and view is None:
        view = False
    outputs = Outputs()  # the Rerun recording, put in place when the session ends (the -o recording is written as it comes)
    rerun_file = outputs.file(rerun_save) if rerun_save else None  # a missing folder: stop before the sensor is opened
    try:
        _stream(
            ctx, host, replay, speed, units, rdt_port, http_port, timeout, device_bias, faults, duration, record, view,
            rerun_spawn, rerun_file, tip, payload, estimator_opts, outputs, sensor_range, formats, quiet,
        )  # fmt: skip
    except BaseException:
        outputs.discard()
        raise
    outputs.commit()


def _stream(
    ctx, host, replay, speed, units, rdt_port, http_port, timeout, device_bias, faults, duration, record, view,
    rerun_spawn, rerun_file, tip, payload, estimator_opts, outputs, sensor_range, formats, quiet=False,
) -> None:
    import signal
    import threading

    from softtip.apps.live import KeyReader, LiveStats, LiveSummary, Recorder, TerminalView, run_live
    from softtip.estimator import Estimator
    from softtip.io.sources import Interrupted, LogSource, SourceError

    rerun_save = None if rerun_file is None else rerun_file.tmp
    fingertip = load_fingertip(tip)
    recorder = Recorder(record) if record is not None else None
    if rerun_spawn:  # before the sensor is opened: without a display the viewer fails late
        from softtip.viz.rerun import check_viewer

        check_viewer()
    viz = optional_extra("softtip.viz.rerun", "viz") if (rerun_spawn or rerun_save) else None
    logger = None  # the Rerun view, once the sensor is open

    stop = threading.Event()
    # Ctrl-C, SIGTERM and SIGHUP end the loop between two samples (or a wait for one): the
    # recording stays complete, on a whole line
    stop_signals = [signal.SIGINT, signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    previous = {sig: signal.signal(sig, lambda *_: stop.set()) for sig in stop_signals}
    source = stats = estimator = None
    try:
        try:
            if replay is not None:
                from softtip.io.tables import read_log

                if is_bag(replay):  # its bytes are not a log's text: say so, not "not valid UTF-8"
                    raise InputError(f"{replay}: a ROS bag; --replay reads a CSV, Parquet or Arrow log (softtip "
                                     "estimate reads a bag: softtip estimate BAG --topic TOPIC)")  # fmt: skip
                log = read_log(replay, units=units, **formats)
                # as `estimate` reads it: far beyond the sensor's range, or a time unit it cannot guess, stops here
                check_full_scale(log.t, log.wrench, sensor_range, replay, units=log.units, margin=COARSE_MARGIN)
                print_log_notes(log, quiet)
                if payload is None:
                    source = LogSource.from_log(log, speed=speed, stop=stop)
                else:
                    from softtip.io.payload import replay_source

                    source = replay_source(log, speed, payload, stop=stop)
                info = f"(replay x{speed:g})" if speed else "(replay, as fast as possible)"
                raw = getattr(source, "source", source)  # the log as read (before any payload compensation)
                if recorder is not None and raw.stamps_ns is not None:
                    recorder.keep_stamps()  # the note above says they go along, as with `estimate`
            else:
                from softtip.io.netft import NetFTSource

                try:
                    source = NetFTSource(host, rdt_port=rdt_port, http_port=http_port, timeout=timeout, device_bias=device_bias, strict=faults, stop=stop)
                except ValueError as exc:
                    raise click.UsageError(str(exc)) from None
                # load the estimator's compiled steps (its warm-up) before the device streams: built
                # after open(), the estimator would start the session behind by that load (about 0.5 s of CPU)
                Estimator(fingertip)
                source.open()
                d = source.info
                rate = f"{d.rate_hz:g} Hz" if d.rate_hz else "rate unknown"
                info = f"({d.product}, {d.force_unit} / {d.torque_unit}, {rate})"
            lowpass = estimator_opts["lowpass_hz"]
            if lowpass is not None and source.rate_hz is not None:
                check_lowpass(lowpass, source.rate_hz)
            config = make_config(
                estimator_opts, sample_rate=source.rate_hz if lowpass is not None else None, tip=fingertip
            )
            if lowpass is not None and source.rate_hz is None:
                raise click.UsageError("--lowpass-hz needs the sample rate, which this source does not report")
            if replay is not None:  # `estimate`'s units check, then its range check, before any sample is used
                _check_replay_units(log, payload, fingertip, config)
                check_full_scale(raw.t, raw.wrench, sensor_range, replay, units=log.units)
            # a short replay runs the steps as Python: loading numba would cost more (the same bits)
            estimator = Estimator(fingertip, config, expected_samples=len(raw.t) if replay is not None else None)
            tare_request = threading.Event()
            stats = LiveStats(
                source_name=source.name,
                info=info,
                dropped=(lambda: source.dropped) if hasattr(type(source), "dropped") else None,
                counters=getattr(source, "counters", None),
                warnings=(lambda: source.warnings) if hasattr(type(source), "warnings") else None,
            )
            show = sys.stderr.isatty() if view is None else view
            tare_key = show and sys.stdin.isatty()
            term = TerminalView(
                stats, interval=0.2, config=config, recorder=recorder, estimator=estimator,
                tare_key=tare_key,
            ) if show else None  # fmt: skip
            on_estimate = _within_range(sensor_range, source.name, stats)  # a live sample beyond it ends the run
            if viz is not None:
                # drawn by a process of its own, which starts while the stream runs
                logger = viz.LiveRerun(fingertip, save=rerun_save, spawn=rerun_spawn, wait=False)
                checked = on_estimate

                def on_estimate(e, r):
                    checked(e, r)
                    logger.log_sample(e)
            keys = KeyReader({"t": tare_request.set}) if tare_key else None
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", EstimatorWarning)  # shown in the view and below
                    summary = run_live(
                        source, estimator, recorder=recorder, view=term, stats=stats, duration=duration, stop=stop,
                        on_estimate=on_estimate, tare_request=tare_request,
                    )  # fmt: skip
            finally:
                if keys is not None:
                    keys.close()
            recorder = None  # closed by run_live
            if viz is not None:
                logger.close()
        except Interrupted:
            click.echo("softtip: interrupted before the first sample; nothing recorded", err=True)
            return
        except SourceError as exc:
            if stats is not None and estimator is not None:  # the session ran: its counters as at any end
                _report(LiveSummary.of(stats, "fault"), source.name, estimator, record, quiet)
            else:
                for w in getattr(source, "warnings", None) or []:
                    click.echo(f"softtip: warning: {source.name}: {w}", err=True)
            click.echo(f"softtip: error: {exc}", err=True)
            if logger is not None:
                logger.close()  # written out before it is put in place
            outputs.commit()  # what was seen up to the fault stays viewable
            ctx.exit(1)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if source is not None and hasattr(source, "close"):
            source.close()
        if recorder is not None:
            recorder.close()
    _report(summary, source.name, estimator, record, quiet)


def _check_replay_units(log, payload, fingertip, config) -> None:
    """Exit 2 when the replayed log's units cannot be right, naming the pair that fits: the
    check of ``softtip estimate`` on the log tared as the estimator tares it (the payload
    removed first). The tare alone, not a whole estimate: a replay starts at once."""
    from types import SimpleNamespace

    import numpy as np

    from softtip.estimator.tare import tare_log

    if payload is not None:
        from softtip.io.payload import compensate_log

        log = compensate_log(log, payload)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)  # the stream says them as they come
        tare = tare_log(log.t, log.wrench, config)
    bias = tare.bias if np.isfinite(tare.bias).all() else np.zeros(6)
    check_units(SimpleNamespace(wrench=log.wrench - bias, taring=tare.taring), fingertip, config, log)


def _report(summary: LiveSummary, name: str, estimator: Estimator, record: str | None, quiet: bool = False) -> None:
    """The end of a session on standard error: the source's warnings, the tare (as `estimate`
    says it, before its summary), the counters and the estimator's warnings (also when a fault
    ended it, before the error); ``quiet``: the warnings only."""
    for w in summary.warnings:
        click.echo(f"softtip: warning: {name}: {w}", err=True)
    if not quiet:
        _summary(summary, estimator, record)
    for msg in dict.fromkeys(estimator.warnings):
        click.echo(f"softtip: warning: {msg}", err=True)


def _summary(summary: LiveSummary, estimator: Estimator, record: str | None) -> None:
    """The tare and the counters of a session."""
    retared_at = summary.retares[-1] if summary.retares else None
    if estimator.tare_report is not None and estimator.tare_report.source != "none":
        click.echo(f"softtip: {estimator.tare_report.summary(retared_at)}", err=True)
    if record and summary.retares:  # the key's tares are not in the file: a re-estimate tares once, at its start
        at = ", ".join(f"{t:g}" for t in summary.retares)
        click.echo(
            f"softtip: warning: {record}: tared again at t = {at} s (the t key), which the recording does not hold: "
            "softtip estimate on it tares once, from its start, so its estimates from there differ from the recorded ones",
            err=True,
        )
    rate = summary.samples / summary.seconds if summary.seconds > 0 else 0.0
    why = {"end": "end of log", "duration": "duration reached", "interrupt": "interrupted", "fault": "ended by the fault below"}[summary.reason]
    c = summary.counters
    more = "".join(f"{c[k]} {k}, " for k in ("late", "duplicates", "malformed") if k in c)
    device = "".join(f", {c[k]} {label}" for k, label in (("restarts", "restarts"), ("stalls", "stalled records"), ("status_records", "with a nonzero status")) if c.get(k))
    click.echo(
        f"softtip: {summary.samples} samples in {summary.seconds:.2f} s ({rate:.1f} Hz), {summary.lost} lost, {more}"
        f"{summary.dropped} dropped by softtip{device}; {estimator.contacts} contact(s); {why}"
        + (f"; recorded -> {record}" if record else ""),
        err=True,
    )


def _within_range(full_scale: FullScale, name: str, stats):
    """A per-sample check of a live source against ``--full-scale``: the first sample beyond it
    ends the session (exit 2, naming the sample; every row before it is recorded). A replayed
    log is checked whole before it starts."""
    bounds = full_scale.bounds.tolist()

    def check(e, r) -> None:
        w = r.wrench
        if any(not abs(v) <= b for v, b in zip(w, bounds)):
            import numpy as np

            check_full_scale([r.t], np.asarray([w], dtype=float), full_scale, name, first_sample=stats.received - 1)

    return check
