"""A log estimated piece by piece (``softtip estimate --chunk-rows``) gives the one-shot run's bits."""

from __future__ import annotations

import dataclasses
import itertools
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip import EstimatorConfig, estimate
from softtip.apps.chunked import estimate_pieces
from softtip.core.noise import NANO17
from softtip.estimator.contact import track_contacts
from softtip.io.tables import write_table
from softtip.sim.synthetic import sliding_presses

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def _log(seed: int, presses: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Presses on the tip with untouched gaps (100 Hz), sensor noise, and a bias that drifts."""
    rng = np.random.default_rng(seed)
    t, w = sliding_presses(rng, n_presses=presses, center=(0.0, 0.0, 20e-3), radius=10e-3)
    w = w + rng.normal(0.0, 1.0, w.shape) * np.array(NANO17.force_std + NANO17.moment_std)
    ramp = (t - t[0]) / (t[-1] - t[0])
    w = w + np.array([0.05, 0.3, -0.2, 1e-4, -2e-4, 5e-5]) + ramp[:, None] * np.array([0.02, -0.01, 0.015, 2e-5, 0, -1e-5])
    return t, w


CONFIGS = {
    "default": EstimatorConfig(),
    "lowpass": EstimatorConfig(lowpass_hz=20.0),
    "no-drift-tracking": EstimatorConfig(drift_tracking=False, lowpass_hz=15.0),
    "joint": EstimatorConfig(contact_point="line-fit"),
    "noise-from-tare": EstimatorConfig(noise_from_tare=True, tare_duration=0.4),
    "noise-auto-raised": EstimatorConfig(tare_duration=0.4, noise=NANO17.scaled(0.7)),
}


def _one_shot(t, w, config):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return estimate(t, w, "murakami2006", config)


def _blocks(t, w, size):
    return [(t[i : i + size], w[i : i + size], {"row": np.arange(i, min(i + size, len(t)))}) for i in range(0, len(t), size)]


@pytest.mark.parametrize("name", sorted(CONFIGS))
@pytest.mark.parametrize("rows", [30, 130, 100000])
def test_pieces_give_the_bits_of_the_one_shot_run(name: str, rows: int) -> None:
    """Rows per piece smaller than a contact (30: the pieces grow to hold it), about one
    press (130) and more than the log; blocks of 37 rows that end anywhere."""
    config = CONFIGS[name]
    t, w = _log(seed=rows)
    one = _one_shot(t, w, config)
    assert one.n_contacts >= 4
    pieces = list(estimate_pieces(_blocks(t, w, 37), "murakami2006", config, rows))
    ests = [e for e, _ in pieces]
    assert sum(map(len, ests)) == len(t)
    if rows < len(t):
        assert len(ests) > 1
    for field in dataclasses.fields(one):
        whole = getattr(one, field.name)
        if isinstance(whole, np.ndarray) and whole.shape[:1] == (len(t),):
            joined = np.concatenate([getattr(e, field.name) for e in ests])
            assert np.array_equal(whole, joined, equal_nan=True), field.name
    assert np.array_equal(np.concatenate([x["row"] for _, x in pieces]), np.arange(len(t)))
    start = 0
    for e in ests:  # every cut is out of contact, and a piece holds at least `rows` samples but the last
        assert not one.contact_id[start] or start == 0
        start += len(e)
        assert len(e) >= min(rows, len(t) - start + len(e)) or e is ests[-1]
    assert [w for e in ests for w in e.warnings] == list(one.warnings)


def test_a_contact_longer_than_a_piece_makes_the_piece_longer() -> None:
    t, w = _log(seed=3, presses=3)
    one = _one_shot(t, w, EstimatorConfig())
    ests = [e for e, _ in estimate_pieces(_blocks(t, w, 5), "murakami2006", EstimatorConfig(), 5)]
    for k in range(1, one.n_contacts + 1):
        holding = [i for i, e in enumerate(ests) if np.any(e.contact_id == k)]
        assert len(holding) == 1  # one piece holds the whole contact
        assert len(ests[holding[0]]) >= np.count_nonzero(one.contact_id == k) > 5


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), track=st.booleans(), where=st.floats(0.0, 1.0), tau=st.sampled_from([0.05, 2.0, 30.0]))
def test_contact_tracker_cut_at_any_untouched_sample(seed: int, track: bool, where: float, tau: float) -> None:
    """track_contacts on two pieces, cut at an untouched sample, with the first's state: the bits of one run."""
    rng = np.random.default_rng(seed)
    n = 600
    x = rng.normal(0.0, 0.02, (n, 6))
    for _ in range(rng.integers(1, 5)):
        a = int(rng.integers(0, n - 20))
        x[a : a + int(rng.integers(1, 80)), :3] += rng.normal(0.0, 1.0, 3)
    x += np.linspace(0.0, rng.normal(0.0, 0.3), n)[:, None]
    t = np.cumsum(rng.uniform(0.5e-3, 2e-3, n))
    config = EstimatorConfig(drift_tracking=track, drift_time_constant=tau)
    start = int(rng.integers(0, 30))
    whole = track_contacts(t, x, start, config, NANO17)
    free = np.flatnonzero(~whole.busy[start + 1 :]) + start + 1
    if not len(free):
        return
    c = int(free[int(where * (len(free) - 1))])
    first = track_contacts(t[:c], x[:c], start, config, NANO17)
    second = track_contacts(t[c:], x[c:], 0, config, NANO17, first.state)
    for name in ("wrench", "drift", "contact", "contact_id", "busy"):
        joined = np.concatenate([getattr(first, name), getattr(second, name)])
        assert np.array_equal(getattr(whole, name), joined), name
    alarm = first.drift_alarm if first.drift_alarm >= 0 else (c + second.drift_alarm if second.drift_alarm >= 0 else -1)
    assert alarm == whole.drift_alarm


def run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_cli_in_pieces_writes_the_one_shot_output(tmp_path: Path, fmt: str) -> None:
    t, w = _log(seed=11)
    t[300] = t[299]  # a repeated stamp: the reader's warning says the same
    t[len(t) // 2 :] += 0.5  # a recorder that lost half a second: so does its note on the gap
    src = tmp_path / f"in.{fmt}"
    trial = np.full(len(t), "a", dtype=object)
    trial[40] = 'b,"c"'  # a cell that needs quotes, in one piece: the others' cells are written as in the whole
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}, "trial": trial.astype(str)}, src)
    outs = {}
    for label, extra in (("one", []), ("pieces", ["--chunk-rows", 50])):
        dest = tmp_path / f"{label}.{fmt}"
        done = run("estimate", src, "-o", dest, "--lowpass-hz", 20, *extra)
        assert done.returncode == 0, done.stderr
        outs[label] = (dest, done.stderr.replace(str(dest), "OUT"))
    assert outs["one"][1] == outs["pieces"][1]
    assert "repeated time stamp" in outs["one"][1] and "contact 3:" in outs["one"][1]
    assert "t has 1 gap longer than 0.1 s (the largest 0.51 s" in outs["one"][1]
    if fmt == "csv":
        assert outs["one"][0].read_bytes() == outs["pieces"][0].read_bytes()
    else:
        one, pieces = pq.read_table(outs["one"][0]), pq.read_table(outs["pieces"][0])
        assert one.schema.equals(pieces.schema, check_metadata=True)
        for name in one.column_names:
            a, b = one.column(name).to_numpy(), pieces.column(name).to_numpy()
            assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
        assert pq.ParquetFile(outs["pieces"][0]).metadata.num_row_groups > 1


def test_cli_in_pieces_bad_row_gives_the_located_error_and_no_output(tmp_path: Path) -> None:
    t, w = _log(seed=5)
    lines = ["t,fx,fy,fz,mx,my,mz"] + [",".join(repr(float(v)) for v in (t[i], *w[i])) for i in range(len(t))]
    lines[700] = lines[700].replace(",", ",x", 1)  # line 701: a cell that is not a number
    src = tmp_path / "bad.csv"
    src.write_text("\n".join(lines) + "\n")
    dest = tmp_path / "out.csv"
    one = run("estimate", src, "-o", dest)
    pieces = run("estimate", src, "-o", dest, "--chunk-rows", 40)
    assert one.returncode == pieces.returncode == 2
    assert pieces.stderr == one.stderr
    assert f"softtip: error: {src}:701: column 'fx': expected a number" in pieces.stderr
    assert not dest.exists() and os.listdir(tmp_path) == ["bad.csv"]


def test_cli_in_pieces_trailing_blank_lines_fall_back_to_the_one_shot_reader(tmp_path: Path) -> None:
    t, w = _log(seed=6, presses=2)
    src = tmp_path / "in.csv"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    src.write_text(src.read_text() + "\n\n")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert run("estimate", src, "-o", a, "-q").returncode == 0
    done = run("estimate", src, "-o", b, "-q", "--chunk-rows", 30)
    assert done.returncode == 0, done.stderr
    assert a.read_bytes() == b.read_bytes()


def test_cli_chunk_rows_needs_a_table_output_only(tmp_path: Path) -> None:
    t, w = _log(seed=7, presses=1)
    src = tmp_path / "in.csv"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    done = run("estimate", src, "--chunk-rows", 10, "--plot", tmp_path / "x.png", "-o", tmp_path / "o.csv")
    assert done.returncode == 2
    assert "--chunk-rows" in done.stderr and done.stdout == ""
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]


def test_cli_chunk_rows_onto_standard_output_is_the_one_shot_table(tmp_path: Path) -> None:
    # standard output is written piece by piece (memory bounded by the piece), the same text
    t, w = _log(seed=7, presses=1)
    src = tmp_path / "in.csv"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    whole = run("estimate", src, "-q")
    pieces = run("estimate", src, "-q", "--chunk-rows", 10)
    assert whole.returncode == 0 and pieces.returncode == 0, pieces.stderr
    assert pieces.stdout == whole.stdout and len(whole.stdout.splitlines()) == len(t) + 1
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]


@pytest.mark.parametrize("case", ["repeated", "cut", "milliseconds", "quoted", "quoted-repeated", "parquet"])
def test_block_reader_gives_read_log_values_and_warnings(tmp_path: Path, case: str, monkeypatch) -> None:
    import softtip.io.tables as sio
    from softtip.io.tables import iter_log, read_log

    monkeypatch.setattr(sio, "_CSV_BLOCK_BYTES", 20_000)

    n = 3000
    t = np.arange(n) * (1.0 if case == "milliseconds" else 1e-3)
    if case.endswith("repeated"):
        t[1500] = t[1499]
        t[2900] = t[2899]
    w = np.round(np.random.default_rng(1).normal(0.0, 1.0, (n, 6)), 7) + 0.5
    note = np.where(np.arange(n) % 2, "a", "b, c" if case.startswith("quoted") else "d")
    columns = {"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}, **({} if case == "cut" else {"note": note})}
    src = tmp_path / ("in.parquet" if case == "parquet" else "in.csv")
    write_table(columns, src)
    if case == "cut":  # the file ends inside its last line, whose last number lost digits
        src.write_bytes(src.read_bytes() + b"%.3f,0.5,0.5,0.5,0.5,0.5,0.5" % (t[-1] + 1e-3))
    one = read_log(src)
    blocks = iter_log(src, rows=700)
    if case == "milliseconds":  # a time unit to guess: the one-shot run stops naming --time-units (issue 28)
        from softtip.io.tables import NotStreamable

        with pytest.raises(NotStreamable):
            list(blocks)
        assert len(one.warnings) == 1 and one.time_suspect is not None
        return
    got = list(blocks)
    assert len(got) > 1
    assert np.array_equal(np.concatenate([b[0] for b in got]), one.t)
    assert np.array_equal(np.concatenate([b[1] for b in got]), one.wrench)
    if case != "cut":
        assert np.array_equal(np.concatenate([b[2]["note"] for b in got]), np.asarray(one.extra["note"]))
    assert blocks.warnings() == one.warnings
    assert len(one.warnings) == (case in ("repeated", "quoted-repeated", "cut", "milliseconds")), one.warnings


@settings(max_examples=200, deadline=None)
@given(
    values=st.lists(st.sampled_from([0.5, 1.0, 1.5, 2.0, 2.5, 3.0]) | st.floats(0.0, 4.0), max_size=40),
    cuts=st.lists(st.integers(0, 40), max_size=4),
    limit=st.sampled_from([1.0, 1.5, 1.75, 2.0, 2.25]),
)
def test_lever_vote_decides_as_the_median_of_all(values: list[float], cuts: list[int], limit: float) -> None:
    from softtip.core.lever import LeverVote

    d = np.array(values)
    vote = LeverVote(limit)
    edges = sorted({0, len(d), *[min(c, len(d)) for c in cuts]})
    for a, b in itertools.pairwise(edges):
        vote.add(d[a:b])
    assert vote.n == len(d)
    assert vote.median_above() == (len(d) > 0 and bool(np.median(d) > limit))


def test_cli_in_pieces_units_check_as_one_shot(tmp_path: Path) -> None:
    """A log in kgf and kgf·mm read as SI: the one-shot run's message, exit 2, nothing written."""
    t, w = _log(seed=8, presses=3)
    src = tmp_path / "kgf.csv"
    write_table({"t": t, **{k: (w[:, i] / 9.80665) * (1e3 if i >= 3 else 1.0) for i, k in enumerate(WRENCH)}}, src)
    dest = tmp_path / "out.csv"
    one, pieces = run("estimate", src, "-o", dest), run("estimate", src, "-o", dest, "--chunk-rows", 50)
    assert one.returncode == pieces.returncode == 2
    assert "--units kgf-mm" in pieces.stderr and pieces.stderr == one.stderr
    assert not dest.exists()
    good = run("estimate", src, "--units", "kgf-mm", "-o", dest, "--chunk-rows", 50)
    assert good.returncode == 0, good.stderr
