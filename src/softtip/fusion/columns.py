"""The output columns of two fused fingertips (:meth:`softtip.fusion.fuse.FusedGrasp.columns`,
``softtip fuse``), each declared once: :data:`FUSED_COLUMNS`. The table of manual §8
(``docs/guide/fused-columns.md``, written by ``scripts/make_column_table.py``) is made from it."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["FusedColumn", "FUSED_COLUMNS", "fused_column_names", "fused_markdown_table"]


class FusedColumn(NamedTuple):
    """One output column, or a vector's three (``names``: x, y, z)."""

    names: tuple[str, ...]
    unit: str  #: SI, or deg; "" for a text column or a unit vector
    description: str


FUSED_COLUMNS: tuple[FusedColumn, ...] = (
    FusedColumn(("t",), "s", "time of the first log's sample (the second finger's latest sample within two of its "
                "periods is paired with it)"),
    FusedColumn(("grasp",), "", "the reading: `parallel_lines`, `crossing_lines`, `line_and_face`, `faces`, `single` or "
                "`none` (the table above)"),
    FusedColumn(("evidence",), "", "`confirmed` once every fused line is confirmed, `unconfirmed` before, empty without "
                "a line"),
    FusedColumn(("flag",), "", "empty, `unbalanced`, `area`, or both joined by `+` (the flags above)"),
    FusedColumn(("r1_x", "r1_y", "r1_z"), "m", "the first finger's contact point, common frame"),
    FusedColumn(("r2_x", "r2_y", "r2_z"), "m", "the second finger's contact point, common frame"),
    FusedColumn(("dx", "dy", "dz"), "", "the line's direction (an axis: its sign means nothing), common frame; the common "
                "direction of `parallel_lines`"),
    FusedColumn(("d2x", "d2y", "d2z"), "", "the second line's direction (`crossing_lines`)"),
    FusedColumn(("plane_nx", "plane_ny", "plane_nz"), "", "the normal of the plane through both lines (`parallel_lines`)"),
    FusedColumn(("face_nx", "face_ny", "face_nz"), "", "the face's outward normal on the object (`line_and_face`)"),
    FusedColumn(("direction_std_deg",), "deg", "standard deviation of the direction, shared error counted (below)"),
    FusedColumn(("line_angle_deg",), "deg", "the axial angle between the two lines"),
    FusedColumn(("line_angle_std_deg",), "deg", "its standard deviation"),
    FusedColumn(("closest_approach",), "m", "the distance between the two lines (`crossing_lines`)"),
    FusedColumn(("plane_normal_std_deg",), "deg", "standard deviation of the plane's normal (`parallel_lines`)"),
    FusedColumn(("residual_fx", "residual_fy", "residual_fz"), "N", "the force balance's residual, `f₁ + f₂ − m g` "
                "(without `--object-mass` any weight along gravity is allowed)"),
    FusedColumn(("balance_chi2",), "", "the residual's χ² against the sensors' noise and 5 % of the grasp force; "
                "`unbalanced` beyond 16.27 (3 degrees of freedom, p = 0.001)"),
)  # fmt: skip


def fused_column_names() -> list[str]:
    """Every column's name, in the output's order (absolute stamps add ``stamp_ns`` last)."""
    return [name for c in FUSED_COLUMNS for name in c.names]


def fused_markdown_table() -> str:
    """The table of manual §8: one row per column or vector, empty cells NaN where a reading
    does not define them."""
    rows = ["| column | unit | |", "| --- | --- | --- |"]
    for c in FUSED_COLUMNS:
        names = f"`{c.names[0]}`" if len(c.names) == 1 else f"`{c.names[0]}` … `{c.names[-1]}`"
        rows.append(f"| {names} | {c.unit} | {c.description} |")
    return (
        "<!-- written by scripts/make_column_table.py from softtip.fusion.columns; do not edit -->\n\n"
        + "\n".join(rows)
        + "\n\nA number is NaN (empty in CSV) where the reading does not define it. Where the first log has absolute "
        "stamps (a bag, a log with Unix time) `stamp_ns`, its stamps in ns, is the last column.\n"
    )
