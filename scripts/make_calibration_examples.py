"""Regenerate the calibration examples in src/softtip/data/ (for `softtip calibrate --example`
and `softtip calibrate-payload --example`).

    python scripts/make_calibration_examples.py

* example_probing.csv: 30 plane presses (1.5 s each: the surface pushes along the skin
  normal to 1.5–4 N, then slides about half a millimetre one way and then across, which
  turns the friction force) on a sphere fingertip of radius 16 mm whose centre is at
  (0.3, −0.2, 20.0) mm, simulated by softtip.sim at 100 Hz with Nano17-class noise
  (3 mN, 0.02 N·mm per axis, plus quantisation: 1/160 N and 1/32 N·mm).
* example_still.csv: the same fingertip (20 g, centre of mass at (1, −0.5, 20) mm) held
  still, untouched, in 12 orientations (±60° about x and y), 1 s each at 100 Hz, with a
  sensor bias and the same noise; columns t, fx..mz and the orientation qw, qx, qy, qz.
"""

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from softtip.calibration.payload import Payload, payload_wrench
from softtip.core.fingertip import Sphere
from softtip.io.tables import write_table
from softtip.sim import SensorModel
from softtip.sim.probing import simulate_probing

DATA = Path(__file__).resolve().parents[1] / "src" / "softtip" / "data"
AXES = ("fx", "fy", "fz", "mx", "my", "mz")
TIP = Sphere(0.016, (0.0003, -0.0002, 0.020))
PAYLOAD = Payload(0.020, (0.001, -0.0005, 0.020))
SENSOR = SensorModel(rate=100.0)


def probing() -> None:
    t, w = simulate_probing(TIP, 45.0, sensor=SENSOR, rng=2026)
    out = DATA / "example_probing.csv"
    write_table({"t": t, **{a: w[:, i] for i, a in enumerate(AXES)}}, out, float_format="%.6g")
    print(f"wrote {out} ({len(t)} samples)")


def still() -> None:
    rng = np.random.default_rng(2027)
    angles = np.radians(np.column_stack((rng.uniform(-60, 60, 12), rng.uniform(-60, 60, 12), rng.uniform(-180, 180, 12))))
    per = int(SENSOR.rate)
    q = Rotation.from_euler("xyz", np.repeat(angles, per, axis=0)).as_quat(scalar_first=True)
    bias = SensorModel(rate=SENSOR.rate, bias=(0.12, -0.05, 0.2, 1e-3, -2e-3, 5e-4))
    w = bias.measure(payload_wrench(q, PAYLOAD), rng)
    t = np.arange(len(q)) / SENSOR.rate
    cols = {"t": t, **{a: w[:, i] for i, a in enumerate(AXES)}, **{c: q[:, i] for i, c in enumerate(("qw", "qx", "qy", "qz"))}}
    out = DATA / "example_still.csv"
    write_table(cols, out, float_format="%.7g")
    print(f"wrote {out} ({len(t)} samples)")


if __name__ == "__main__":
    probing()
    still()
