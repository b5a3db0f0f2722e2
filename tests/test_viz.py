"""The Rerun 3-D view (softtip[viz]), checked from saved .rrd files without a display;
and the messages when an optional extra is missing."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip import EXAMPLE_PATH, Capsule, Ellipsoid, Sphere

SOFTTIP = str(Path(sys.executable).with_name("softtip"))


def entity_rows(path):
    """{entity path: rows} of a saved recording, read back with rerun's own reader."""
    from rerun.chunk import RrdReader

    store = RrdReader(path).store()
    rows = {}
    for line in str(store.summary()).splitlines():
        name, _, rest = line.partition(" rows=")
        rows[name] = rows.get(name, 0) + int(rest.split()[0])
    return rows


@pytest.mark.parametrize(
    "tip",
    [
        Capsule(0.016, 0.02),
        Sphere(0.01, (0, 0, 0.02)),
        Ellipsoid((0.01, 0.012, 0.02), (0, 0, 0.01)),
    ],
)
def test_surface_mesh_lies_on_the_skin(tip):
    pytest.importorskip("rerun")
    from softtip.viz.rerun import surface_mesh

    v, tri, n = surface_mesh(tip)
    assert np.abs(tip.surface(v)).max() < 1e-12
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert tri.min() == 0 and tri.max() == len(v) - 1


def test_estimate_rerun_save(tmp_path):
    pytest.importorskip("rerun")
    rrd = tmp_path / "view.rrd"
    out = subprocess.run(
        [
            SOFTTIP,
            "estimate",
            EXAMPLE_PATH,
            "-o",
            tmp_path / "e.csv",
            "--rerun-save",
            rrd,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert rrd.stat().st_size > 50_000
    rows = entity_rows(rrd)
    assert rows["/tip/skin"] == 1
    for series in ("fx", "fy", "fz"):
        assert rows[f"/series/force/{series}"] == 500
    assert rows["/series/angle_deg"] == rows["/series/h_norm"] == 500
    for entity in ("/tip/contact", "/tip/normal", "/tip/force", "/tip/edge"):
        assert rows[entity] == 500  # a value or a clear for every sample
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e.csv", "view.rrd"]


def test_stream_replay_rerun_save(tmp_path):
    pytest.importorskip("rerun")
    rrd = tmp_path / "live.rrd"
    out = subprocess.run(
        [
            SOFTTIP,
            "stream",
            "--replay",
            EXAMPLE_PATH,
            "--speed",
            "0",
            "--rerun-save",
            rrd,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    rows = entity_rows(rrd)
    assert (
        rows["/tip/skin"] == 1
        and rows["/tip/edge"] > 100
        and rows["/series/force/fz"] > 100
    )


MISSING = """
import sys
sys.modules[{module!r}] = None  # as if the extra were not installed: import raises ImportError
from softtip.cli import main
main({args!r})
"""


@pytest.mark.parametrize(
    "module, args, package",
    [
        ("rosbags", ["estimate", "--example", "--to-bag", "{tmp}/b"], "rosbags"),
        ("rerun", ["estimate", "--example", "--rerun-save", "{tmp}/v.rrd"], "rerun-sdk"),
    ],
)
def test_missing_extra_names_the_package_to_install(tmp_path, module, args, package):
    args = [a.format(tmp=tmp_path) for a in args]
    out = subprocess.run(
        [sys.executable, "-c", MISSING.format(module=module, args=args)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2
    # softtip is not on PyPI: the message names the package itself
    assert f"pip install '{package}" in out.stderr and "softtip[" not in out.stderr
    assert "Traceback" not in out.stderr
    assert list(tmp_path.iterdir()) == []
