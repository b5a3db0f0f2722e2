"""The output-column registry (softtip.estimator.columns) is the one list: the estimates, the
files, the live recording, ``--help``, the manual's table and the ROS topics all follow it."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip.estimator import Estimates, SampleEstimate, estimate
from softtip.estimator.columns import COLUMNS, NOT_COLUMNS, STAGES, TOPICS, column_names, help_text, markdown_table
from softtip.io.examples import load_example

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "docs" / "guide" / "columns.md"


@pytest.fixture(scope="module")
def example() -> Estimates:
    log = load_example()
    return estimate(log.t, log.wrench, "murakami2006")


def test_every_column_is_declared_once_with_a_known_type_and_stage():
    names = column_names()
    assert len(names) == len(set(names))
    for c in COLUMNS:
        assert c.dtype in ("float64", "bool", "int64", "str"), c
        assert c.stage in STAGES, c
        assert c.description and "\n" not in c.description, c
        assert (c.codes is not None) == (c.dtype == "str"), c
        assert not c.degrees or c.name.endswith("_deg"), c
        assert (c.topic is None) == (c.field is None), c
    assert {c.topic for c in COLUMNS} - {None} == {t.key for t in TOPICS}


def test_every_output_attribute_is_in_the_registry_and_no_other():
    attrs = {c.attr for c in COLUMNS}
    for cls_fields in ({f.name for f in dataclasses.fields(Estimates)}, set(SampleEstimate._fields)):
        outputs = cls_fields - set(NOT_COLUMNS)
        assert outputs == attrs, (outputs ^ attrs)
    assert set(SampleEstimate._fields) - attrs <= set(NOT_COLUMNS)  # the sample's non-columns are named too


def test_a_vector_attribute_is_its_columns_in_order(example):
    """Each vector attribute's components are all columns, in order and together (the live
    recording unpacks such an attribute whole)."""
    by_attr: dict[str, list[int]] = {}
    positions: dict[str, list[int]] = {}
    for k, c in enumerate(COLUMNS):
        if c.index is not None:
            by_attr.setdefault(c.attr, []).append(c.index)
            positions.setdefault(c.attr, []).append(k)
    assert by_attr
    for attr, indices in by_attr.items():
        width = np.asarray(getattr(example, attr)).shape[1]
        assert indices == list(range(width)), attr
        assert positions[attr] == list(range(positions[attr][0], positions[attr][0] + width)), attr


def test_the_estimates_columns_follow_the_registry(example):
    cols = example.columns()
    assert list(cols) == column_names()
    kinds = {"float64": "f", "bool": "b", "int64": "i", "str": "U"}
    for c in COLUMNS:
        v = np.asarray(cols[c.name])
        assert v.shape == (len(example),) and v.dtype.kind == kinds[c.dtype], c.name
        source = getattr(example, c.attr)
        source = source if c.index is None else source[:, c.index]
        if c.codes is not None:
            np.testing.assert_array_equal(v, np.asarray(c.codes)[source])
        elif c.degrees:
            np.testing.assert_array_equal(v, np.degrees(source))
        else:
            np.testing.assert_array_equal(v, source)
    table = example.to_arrow()
    assert table.column_names == column_names()
    types = {"float64": "double", "bool": "bool", "int64": "int64", "str": "string"}
    assert [str(f.type) for f in table.schema] == [types[c.dtype] for c in COLUMNS]


def test_an_optional_attribute_left_empty_leaves_its_columns_out(example):
    cols = dataclasses.replace(example, drift=None, contact_id=None).columns()
    assert list(cols) == [c.name for c in COLUMNS if c.attr not in ("drift", "contact_id")]


def test_the_live_recording_has_the_registry_columns_in_order():
    from softtip.apps.live import RECORD_COLUMNS

    estimates = [n for n in RECORD_COLUMNS if n in set(column_names())]
    assert estimates == column_names()
    start = RECORD_COLUMNS.index("state")
    assert list(RECORD_COLUMNS[start:start + len(COLUMNS) - 1]) == column_names()[1:]


def test_the_live_row_is_the_sample_estimate_by_the_registry():
    """A recorded row holds each column's value of the SampleEstimate, as the registry maps it."""
    import softtip
    from softtip.apps.live import RECORD_COLUMNS, estimate_row
    from softtip.io.sources import Reading

    log = load_example()
    est = softtip.Estimator("murakami2006")
    checked = 0
    for k in range(len(log.t)):
        r = Reading(float(log.t[k]), tuple(log.wrench[k].tolist()), k)
        e = est.update(r.t, r.wrench)
        row = dict(zip(RECORD_COLUMNS, estimate_row(e, r), strict=True))
        for c in COLUMNS[1:]:
            v = getattr(e, c.attr)
            v = v if c.index is None else v[c.index]
            v = v * (180.0 / np.pi) if c.degrees else v
            assert row[c.name] == v or (v != v and row[c.name] != row[c.name]), (k, c.name)
        checked += e.state == "line"
    assert checked > 100


def test_the_manual_table_is_the_registry():
    """docs/guide/columns.md (included by manual §4) is the registry's table: regenerate it
    with ``python scripts/make_column_table.py``. The README lists no columns; it points to the manual."""
    assert TABLE.read_text(encoding="utf-8") == markdown_table()
    listed = []
    for line in TABLE.read_text(encoding="utf-8").splitlines():
        if line.startswith("| `"):
            cell = line.split("|")[1]
            names = re.findall(r"`([^`]+)`", cell)
            if len(names) == 2:  # a vector: first … last
                first = column_names().index(names[0])
                names = column_names()[first:column_names().index(names[1]) + 1]
            listed += names
    assert listed == column_names()
    manual = (ROOT / "docs" / "guide" / "04-data-and-command-line.md").read_text(encoding="utf-8")
    assert "```{include} columns.md" in manual
    assert not re.search(r"\|\s*`(rx|h_norm|joint_\w+)", (ROOT / "README.md").read_text(encoding="utf-8"))


def test_the_help_lists_the_registry():
    import click

    from softtip.cli.estimate import estimate as command

    wide = click.Context(command, info_name="estimate", terminal_width=100_000, max_content_width=100_000)
    text = " ".join(command.get_help(wide).split())  # unwrapped: click breaks lines at hyphens
    assert help_text() in text
    for name in ("line_fit_conditioning", "angle_noise_std_deg", "drift_fx..drift_fz", "excitation_ratio"):
        assert name in text
    out = subprocess.run([sys.executable, "-m", "softtip.cli", "estimate", "--help"], capture_output=True, text=True, check=True)
    assert "line_fit_residual" in out.stdout


def test_the_ros_topics_are_the_registry_topics():
    from softtip.ros import TOPICS as ROS_TOPICS

    assert ROS_TOPICS == {t.key: f"/softtip/{t.key}" for t in TOPICS}
    assert set(ROS_TOPICS) >= {"wrench", "state", "contact_point", "normal", "edge_direction", "line_evidence"}


def test_a_bag_carries_each_column_in_its_topic_and_field(tmp_path, example):
    """Every column with a topic that bags hold is in that topic's messages, at the field the
    registry names, in SI (rad), one message per sample it is published for."""
    import operator

    pytest.importorskip("rosbags")
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    from softtip.io.bag import write_estimates_bag

    write_estimates_bag(tmp_path / "bag", example, example.wrench, markers=False)
    stamps = {int(s): k for k, s in enumerate(np.rint(example.t * 1e9).astype(np.int64))}
    in_bag = {t.key: t.name for t in TOPICS if t.in_bag}
    messages: dict[str, list] = {}
    with AnyReader([tmp_path / "bag"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        for conn, ts, raw in reader.messages():
            messages.setdefault(conn.topic, []).append((stamps[ts], reader.deserialize(raw, conn.msgtype)))
    checked = 0
    for c in COLUMNS:
        if c.topic not in in_bag:
            continue
        got = messages[in_bag[c.topic]]
        assert got, c.name
        for k, msg in got:
            want = getattr(example, c.attr)[k]
            want = c.codes[want] if c.codes is not None else want if c.index is None else want[c.index]
            assert operator.attrgetter(c.field)(msg) == want, (c.name, k)
            checked += 1
    assert checked > 1000


def test_the_fused_columns_are_the_registry_and_the_manual_table_is_it():
    """`softtip fuse`'s columns (FusedGrasp.columns) in the registry's order, and manual §8's table
    (docs/guide/fused-columns.md) the registry's: regenerate it with scripts/make_column_table.py."""
    import dataclasses

    from softtip.fusion.columns import fused_column_names
    from softtip.fusion.fuse import FusedGrasp, fused_markdown_table

    n = 2
    shapes = {"t": (n,), "grasp": (n,), "evidence": (n,), "flag": (n,)}
    kw = {}
    for f in dataclasses.fields(FusedGrasp):
        if f.name == "names":
            continue
        vector = f.name in ("point_a", "point_b", "direction", "direction_b", "plane_normal", "face_normal", "force_residual")
        kind = np.int8 if f.name == "grasp" else (str if f.name in ("evidence", "flag") else float)
        kw[f.name] = np.zeros((n, 3) if vector else shapes.get(f.name, (n,)), dtype=kind)
    assert list(FusedGrasp(**kw).columns()) == fused_column_names()
    table = ROOT / "docs" / "guide" / "fused-columns.md"
    assert table.read_text(encoding="utf-8") == fused_markdown_table()
    assert "```{include} fused-columns.md" in (ROOT / "docs" / "guide" / "08-two-fingertips-the-grasped-object.md").read_text(encoding="utf-8")
