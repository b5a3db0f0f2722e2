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


def test_surface_mesh_of_a_mesh_tip_and_of_a_mounted_tip():
    pytest.importorskip("rerun")
    from scipy.spatial.transform import Rotation

    from softtip.core.mesh import MeshFingertip, capsule_mesh
    from softtip.core.mounting import Mounted
    from softtip.viz.rerun import surface_mesh

    # a mesh fingertip is drawn with its own triangles, not a sphere
    mesh = MeshFingertip(*capsule_mesh(0.016, 0.020, segments=24, nail_height=0.001))
    v, tri, n = surface_mesh(mesh)
    assert np.array_equal(v, mesh.vertices) and np.array_equal(tri, mesh.faces)
    assert np.all(np.sum(n * mesh.normal(v), axis=1) > 0.5)
    # a mounted fingertip: its shape's mesh where the mount puts it, in the sensor frame
    rot = Rotation.from_euler("xyz", [10.0, 30.0, -20.0], degrees=True)
    shift = np.array([0.002, -0.003, 0.004])
    for shape in (Capsule(0.016, 0.02), mesh):
        mounted = Mounted(shape, rot, shift)
        v0, tri0, n0 = surface_mesh(shape)
        v, tri, n = surface_mesh(mounted)
        assert np.array_equal(tri, tri0)
        assert np.allclose(v, rot.apply(v0) + shift, atol=1e-15)
        assert np.allclose(n, rot.apply(n0), atol=1e-15)
        assert np.abs(mounted.surface(v)).max() < 1e-9
        assert np.all(np.sum(n * mounted.normal(v), axis=1) > 0.5)


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


def test_rerun_draws_a_mounted_tip_where_its_mount_puts_it(tmp_path):
    pytest.importorskip("rerun")
    from rerun.chunk import RrdReader

    from softtip import load_fingertip
    from softtip.viz.rerun import surface_mesh

    tip_file = tmp_path / "tip.toml"
    tip_file.write_text(
        '[fingertip]\nshape = "capsule"\nradius = 0.016\nlength = 0.020\n\n'
        "[fingertip.mount]\ntranslation = [0.0, 0.003, 0.002]\nrpy_deg = [0.0, 20.0, 0.0]\n",
        encoding="utf-8",
    )
    rrd = tmp_path / "view.rrd"
    out = subprocess.run(
        [SOFTTIP, "estimate", EXAMPLE_PATH, "--tip", tip_file, "-o", tmp_path / "e.csv", "--rerun-save", rrd, "-q"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    skin = [ch for ch in RrdReader(rrd).store().stream() if ch.entity_path == "/tip/skin"]
    assert len(skin) == 1
    drawn = np.array(skin[0].to_record_batch().column("Mesh3D:vertex_positions").to_pylist()[0])
    tip = load_fingertip(tip_file)
    v, _, _ = surface_mesh(tip)
    assert np.allclose(drawn, v, atol=1e-8)  # stored as float32
    assert np.abs(tip.surface(v)).max() < 1e-12
    # the mount tilts the shape's apex 20° about y, away from the sensor's z axis
    apex = v[np.argmax(v @ np.array([np.sin(np.radians(20.0)), 0.0, np.cos(np.radians(20.0))]))]
    assert np.allclose(apex, [0.036 * np.sin(np.radians(20.0)), 0.003, 0.002 + 0.036 * np.cos(np.radians(20.0))], atol=1e-3)
