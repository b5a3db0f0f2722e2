"""The output columns of two fused fingertips (``softtip fuse``), each declared once:
:data:`FUSED_COLUMNS`. :meth:`softtip.fusion.fuse.FusedGrasp.columns` makes them from it, and
so does the table of manual §8 (:func:`softtip.fusion.fuse.fused_markdown_table`,
``docs/guide/fused-columns.md``, written by ``scripts/make_column_table.py``)."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["FusedColumn", "FUSED_COLUMNS", "fused_column_names"]


class FusedColumn(NamedTuple):
    """One output column, or a vector's three (``names``: x, y, z), made from the attribute
    ``source`` of :class:`~softtip.fusion.fuse.FusedGrasp` (rad turned to degrees where the unit
    is deg)."""

    names: tuple[str, ...]
    source: str
    unit: str  #: SI, or deg; "" for a text column or a unit vector
    description: str


FUSED_COLUMNS: tuple[FusedColumn, ...] = (
    FusedColumn(("t",), "t", "s", "time of the first log's sample (the second finger's latest sample within two of its "
                "periods is paired with it)"),
    FusedColumn(("grasp",), "grasp_names", "", "the reading: `parallel_lines`, `crossing_lines`, `line_and_face`, `faces`, `single` or "
                "`none` (the table above)"),
    FusedColumn(("evidence",), "evidence", "", "`confirmed` once every fused line is confirmed, `unconfirmed` before, empty without "
                "a line"),
    FusedColumn(("flag",), "flag", "", "empty, `unbalanced`, `area`, or both joined by `+` (the flags above)"),
    FusedColumn(("r1_x", "r1_y", "r1_z"), "point_a", "m", "the first finger's contact point, common frame"),
    FusedColumn(("r2_x", "r2_y", "r2_z"), "point_b", "m", "the second finger's contact point, common frame"),
    FusedColumn(("dx", "dy", "dz"), "direction", "", "the line's direction (an axis: its sign means nothing), common frame; the common "
                "direction of `parallel_lines`"),
    FusedColumn(("d2x", "d2y", "d2z"), "direction_b", "", "the second line's direction (`crossing_lines`)"),
    FusedColumn(("plane_nx", "plane_ny", "plane_nz"), "plane_normal", "", "the normal of the plane through both lines (`parallel_lines`)"),
    FusedColumn(("face_nx", "face_ny", "face_nz"), "face_normal", "", "the face's outward normal on the object (`line_and_face`)"),
    FusedColumn(("direction_std_deg",), "direction_std", "deg", "standard deviation of the direction, shared error counted (below)"),
    FusedColumn(("line_angle_deg",), "line_angle", "deg", "the axial angle between the two lines"),
    FusedColumn(("line_angle_std_deg",), "line_angle_std", "deg", "its standard deviation"),
    FusedColumn(("closest_approach",), "closest_approach", "m", "the distance between the two lines (`crossing_lines`)"),
    FusedColumn(("plane_normal_std_deg",), "plane_normal_std", "deg", "standard deviation of the plane's normal (`parallel_lines`)"),
    FusedColumn(("residual_fx", "residual_fy", "residual_fz"), "force_residual", "N", "the force balance's residual, `f₁ + f₂ − m g` "
                "(without `--object-mass` any weight along gravity is allowed)"),
    FusedColumn(("balance_chi2",), "balance_chi2", "", "the residual's χ² against the sensors' noise and {tolerance:g} % of the "
                "grasp force; `unbalanced` beyond {chi2:g} (3 degrees of freedom)"),
)  # fmt: skip


def fused_column_names() -> list[str]:
    """Every column's name, in the output's order (absolute stamps add ``stamp_ns`` last)."""
    return [name for c in FUSED_COLUMNS for name in c.names]

