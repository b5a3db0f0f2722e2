"""Make the shipped example mesh: the papers' fingertip (capsule r = 16 mm, length 20 mm) with a nail.

Writes ``src/softtip/data/murakami2006_nail.stl`` (binary STL, millimetres, like a CAD export)
and ``src/softtip/data/murakami2006_nail.toml`` (the fingertip file that loads it). The nail is
a 1 mm plate on the back of the finger (−x side), 50° to either side of it, from z = 8 mm up
to 10 mm past the cap's equator along the skin, with 1.5 mm smooth edges. Run from the
repository root::

    python scripts/make_mesh_example.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from softtip.core.mesh import capsule_mesh, load_mesh_fingertip

DATA = Path(__file__).resolve().parents[1] / "src" / "softtip" / "data"
RADIUS, LENGTH = 0.016, 0.020

TOML = """\
# The papers' fingertip (capsule of radius 16 mm, cylinder length 20 mm; the length is
# softtip's choice) with a 1 mm nail on its back (-x side): a triangle mesh in millimetres,
# made by scripts/make_mesh_example.py.
[fingertip]
shape = "mesh"
mesh = "murakami2006_nail.stl"   # relative to this file
mesh_units = "mm"
skin_thickness = 0.005           # m: 5 mm silicone over the 11 mm shell

[fingertip.mount]            # mesh frame -> sensor frame (identity here)
translation = [0.0, 0.0, 0.0]    # m
rpy_deg = [0.0, 0.0, 0.0]
"""


def write_binary_stl(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Binary STL: 80-byte header, triangle count, then per triangle normal, 3 vertices, attribute."""
    tri = vertices[faces].astype(np.float32)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    rec = np.zeros(len(faces), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = normal, tri
    header = b"softtip example: murakami2006 fingertip with a nail, mm".ljust(80, b" ")
    with open(path, "wb") as fh:
        fh.write(header)
        fh.write(np.uint32(len(faces)).tobytes())
        fh.write(rec.tobytes())


def main() -> None:
    vertices, faces = capsule_mesh(
        RADIUS, LENGTH, segments=144, nail_height=0.001, nail_half_width_deg=50.0, nail_z=(0.008, 0.010),
        nail_edge=0.0015,
    )  # fmt: skip
    stl = DATA / "murakami2006_nail.stl"
    write_binary_stl(stl, vertices * 1e3, faces)
    toml = DATA / "murakami2006_nail.toml"
    toml.write_text(TOML, encoding="utf-8")
    tip = load_mesh_fingertip(toml)  # checks the file as a user's would be checked
    print(f"{stl}: {len(faces)} triangles, {stl.stat().st_size / 1e6:.2f} MB, volume {tip.volume * 1e6:.2f} cm³")


if __name__ == "__main__":
    main()
