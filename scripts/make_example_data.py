"""Regenerate src/softtip/data/example_grasp.csv (the README quick start's input).

    python scripts/make_example_data.py
"""

from pathlib import Path

from softtip.io.tables import write_table
from softtip.sim.synthetic import synthetic_grasp

OUT = Path(__file__).resolve().parents[1] / "src" / "softtip" / "data" / "example_grasp.csv"


def main() -> None:
    g = synthetic_grasp("murakami2006", angle_deg=45.0, seed=2006)
    cols = {"t": g.t}
    for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz")):
        cols[name] = g.wrench[:, i]
    write_table(cols, OUT, float_format="%.9g")
    print(f"wrote {OUT} ({len(g.t)} samples)")


if __name__ == "__main__":
    main()
