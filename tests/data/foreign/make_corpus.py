"""Write the foreign-log corpus of tests/test_foreign.py from softtip's example grasp.

Each file holds the example grasp (10 s, 50 Hz) the way another program writes it: its header,
units, separators, stamps, compression. ``python tests/data/foreign/make_corpus.py`` rewrites
them; the values are the example's, rounded to 9 significant digits in the file's units.
"""

from __future__ import annotations

import bz2
import gzip
import lzma
from pathlib import Path

import numpy as np

from softtip.core.units import INCH, KGF, KGF_MM, LBF
from softtip.io.examples import load_example

HERE = Path(__file__).parent
EPOCH_NS = 1_700_000_000_123_456_789  # an absolute stamp (2023-11-14)


def _num(x: float) -> str:
    return f"{x:.9g}"


def _rows(cols: list[np.ndarray | list], sep: str = ",", comma: bool = False) -> str:
    out = []
    for row in zip(*cols):
        cells = [c if isinstance(c, str) else _num(float(c)) for c in row]
        if comma:
            cells = [c.replace(".", ",") for c in cells]
        out.append(sep.join(cells))
    return "\n".join(out) + "\n"


def main() -> None:
    ex = load_example()
    t, w = ex.t, ex.wrench
    f, m = w[:, :3], w[:, 3:]
    n = len(t)
    ns = EPOCH_NS + np.round(t * 1e9).astype(np.int64)
    files: dict[str, str] = {}
    si_cols = [t, *f.T, *m.T]
    files["si_reference.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows(si_cols)
    files["ati_ms_n_nmm.csv"] = "Time (ms),Fx (N),Fy (N),Fz (N),Tx (N-mm),Ty (N-mm),Tz (N-mm)\n" + _rows(
        [t * 1e3, *f.T, *(m * 1e3).T]
    )
    files["ati_lbf_lbfin.csv"] = "Time,Fx (lbf),Fy (lbf),Fz (lbf),Tx (lbf-in),Ty (lbf-in),Tz (lbf-in)\n" + _rows(
        [t, *(f / LBF).T, *(m / (LBF * INCH)).T]
    )
    files["n_nmm_plain_header.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows([t, *f.T, *(m * 1e3).T])
    files["kgf_kgfmm_plain_header.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows([t, *(f / KGF).T, *(m / KGF_MM).T])
    stamp = [str(v) for v in ns.tolist()]
    files["rostopic_echo_p.csv"] = (
        "%time,field.header.seq,field.header.stamp,field.header.frame_id,field.wrench.force.x,field.wrench.force.y,"
        "field.wrench.force.z,field.wrench.torque.x,field.wrench.torque.y,field.wrench.torque.z\n"
        + _rows([[str(v + 1_500_000) for v in ns.tolist()], [str(i) for i in range(n)], stamp, ["ft_sensor"] * n, *f.T, *m.T])
    )
    files["ros2_topic_echo.csv"] = _rows(
        [[str(v // 1_000_000_000) for v in ns.tolist()], [str(v % 1_000_000_000) for v in ns.tolist()], ["ft_sensor"] * n, *f.T, *m.T]
    )
    files["plotjuggler.csv"] = "__time,/ft/wrench/force/x,/ft/wrench/force/y,/ft/wrench/force/z,/ft/wrench/torque/x,/ft/wrench/torque/y,/ft/wrench/torque/z\n" + _rows(
        [[f"{v // 10**9}.{v % 10**9:09d}" for v in ns.tolist()], *f.T, *m.T]
    )
    files["tab_separated.tsv"] = "t\tfx\tfy\tfz\tmx\tmy\tmz\n" + _rows(si_cols, "\t")
    files["semicolon_decimal_comma.csv"] = "t;fx;fy;fz;mx;my;mz\n" + _rows(si_cols, ";", comma=True)
    files["t_in_ms.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows([t * 1e3, *f.T, *m.T])
    files["t_in_us.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows([[str(round(x * 1e6)) for x in t], *f.T, *m.T])
    files["t_absolute_ns.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows([stamp, *f.T, *m.T])
    files["upper_case_preamble.csv"] = (
        "Sensor: FT12345 (Nano17)\nCalibration: SI-25-0.25\nRecorded 2026-11-27 15:00\n"
        "T,FX,FY,FZ,MX,MY,MZ\n" + _rows(si_cols)
    )
    holes = [list(map(_num, c)) for c in si_cols]
    holes[2][120] = ""  # a dropped packet: empty fy
    holes[5][300] = "nan"  # and a nan my
    files["missing_cells.csv"] = "t,fx,fy,fz,mx,my,mz\n" + _rows(holes)
    note = [""] * n
    note[100], note[200] = '"5 mm plate, edge', 'end of note"'
    files["stray_quote.csv"] = "t,fx,fy,fz,mx,my,mz,note\n" + _rows([*si_cols, note])
    note = [""] * n
    note[100] = '"never closed'
    files["unterminated_quote.csv"] = "t,fx,fy,fz,mx,my,mz,note\n" + _rows([*si_cols, note])
    for name, text in files.items():
        (HERE / name).write_text(text, newline="\n")
    data = files["si_reference.csv"].encode()
    (HERE / "si_reference.csv.gz").write_bytes(gzip.compress(data, mtime=0))
    (HERE / "si_reference.csv.bz2").write_bytes(bz2.compress(data))
    (HERE / "si_reference.csv.xz").write_bytes(lzma.compress(data))
    import pyarrow as pa

    (HERE / "si_reference.csv.zst").write_bytes(pa.compress(data, codec="zstd", asbytes=True))


if __name__ == "__main__":
    main()
