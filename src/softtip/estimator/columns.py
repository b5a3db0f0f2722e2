"""The output columns of the estimator, each declared once: :data:`COLUMNS`.

Everything that lists softtip's per-sample outputs is made from this table: the order, cell
values and types of :meth:`Estimates.columns <softtip.estimator.Estimates.columns>` (so of
``softtip estimate``'s CSV and Parquet files and :meth:`~softtip.estimator.Estimates.to_arrow`),
the rows of a live recording (:mod:`softtip.apps.live`), the columns paragraph of ``softtip
estimate --help``, the table of manual §4 (``docs/guide/columns.md``, written by
:func:`markdown_table` through ``scripts/make_column_table.py``) and the ROS topics that carry
a column (:data:`TOPICS`).

Adding an output column is one :class:`Column` here and the stage that fills its attribute of
:class:`~softtip.estimator.Estimates` and :class:`~softtip.estimator.SampleEstimate`.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["STATES", "EVIDENCE", "STAGES", "Column", "COLUMNS", "NOT_COLUMNS", "TOPICS", "Topic", "column_names", "help_text", "markdown_table"]

#: Contact states, indexed by the integer codes in :attr:`Estimates.state <softtip.estimator.Estimates.state>`.
STATES = ("none", "point", "line", "area")
#: Line evidence, indexed by the codes in :attr:`Estimates.line_evidence <softtip.estimator.Estimates.line_evidence>`
#: (``""`` unless ``line``).
EVIDENCE = ("", "unconfirmed", "confirmed")

#: The stages that fill columns (manual §3), in the order a sample goes through them.
STAGES = {
    "input": "the log itself",
    "tare": "bias removal and the optional low-pass filter (manual §3.1)",
    "contact": "contact onset, release and numbering; the bias drift while untouched",
    "latch": "the latch of the contact point (manual §3.6)",
    "depth": "the depth compensation (manual §3.7)",
    "measure": "contact point, normal and spin torque of the sample (manual §3.2–3.4)",
    "line-fit": "the sliding window of ``--contact-point line-fit``",
    "evidence": "the state, the line's direction and its evidence (manual §3.5)",
}


@dataclass(frozen=True)
class Column:
    """One output column.

    Attributes
    ----------
    name : str
        The name in a CSV header, a Parquet or Arrow schema and a live recording.
    unit : str
        SI unit of the values as written (``"deg"`` for angles, ``""`` for a flag, a count,
        a ratio or a label); force (``"N"``) and moment (``"N·m"``) columns are written in
        kgf and kgf·mm with ``units="kgf-mm"``.
    dtype : {"float64", "bool", "int64", "str"}
        The values' type in a table.
    description : str
        One line, as in ``--help`` and the manual.
    stage : str
        The stage that fills it (a key of :data:`STAGES`).
    attr : str
        The attribute of :class:`~softtip.estimator.Estimates` and
        :class:`~softtip.estimator.SampleEstimate` it comes from (SI, angles in rad).
    index : int or None
        The component of a vector attribute (``point[:, 0]`` is ``rx``), or None.
    codes : tuple of str or None
        The labels of an integer-coded attribute (:data:`STATES`, :data:`EVIDENCE`); a
        :class:`~softtip.estimator.SampleEstimate` holds the label itself.
    topic : str or None
        The key of the :data:`TOPICS` entry whose messages carry it (in the attribute's SI
        unit, rad for angles), in bags (``--to-bag``) and from the ROS 2 node; None: not published.
    field : str or None
        Its field in that topic's message.
    """

    name: str
    unit: str
    dtype: str
    description: str
    stage: str
    attr: str
    index: int | None = None
    codes: tuple[str, ...] | None = None
    topic: str | None = None
    field: str | None = None

    @property
    def degrees(self) -> bool:
        """The attribute is in rad and the column in degrees."""
        return self.unit == "deg"


def _xyz(prefix: str, unit: str, description: str, stage: str, attr: str, topic: str | None = None, field: str | None = None,
         offset: int = 0) -> tuple[Column, ...]:
    """The columns ``<prefix>x``, ``<prefix>y``, ``<prefix>z`` of components ``offset`` … ``offset + 2``
    of a vector attribute, one description for the three."""
    return tuple(
        Column(f"{prefix}{ax}", unit, "float64", description, stage, attr, offset + i, topic=topic,
               field=None if field is None else f"{field}.{ax}")
        for i, ax in enumerate("xyz")
    )  # fmt: skip


#: Every output column, in the order of the files.
COLUMNS: tuple[Column, ...] = (
    Column("t", "s", "float64", "time of the sample", "input", "t"),
    Column("state", "", "str", "none, point, line or area; manual §3.5", "evidence", "state", codes=STATES, topic="state", field="data"),
    *_xyz("f", "N", "force after bias removal and filtering, the one the estimates come from; empty while taring",
          "tare", "wrench", "wrench", "wrench.force"),
    *_xyz("m", "N·m", "moment after bias removal and filtering; empty while taring", "tare", "wrench", "wrench",
          "wrench.torque", offset=3),
    *_xyz("r", "m", "contact point; empty when none", "measure", "point", "contact_point", "point"),
    *_xyz("n", "", "outward unit normal at the contact point", "measure", "normal", "normal", "vector"),
    Column("sigma", "N·m", "float64", "spin torque about the normal", "measure", "sigma"),
    *_xyz("h", "N·m", "tangential spin torque", "measure", "h"),
    Column("h_norm", "N·m", "float64", "magnitude of the tangential spin torque", "measure", "h_norm"),
    *_xyz("d", "", "direction of the touched edge or strip, an axis; only for line", "evidence", "direction",
          "edge_direction", "vector"),
    Column("angle_deg", "deg", "float64", "the direction's angle in the tangent frame, in (-90, 90], at the tip from the sensor x "
           "axis; manual §3.4", "evidence", "angle"),
    Column("h_std", "N·m", "float64", "standard deviation of h: the sensor noise's and the depth's", "measure", "h_std"),
    Column("angle_std_deg", "deg", "float64", "standard deviation of the angle", "evidence", "angle_std", topic="angle_std",
           field="data"),
    Column("angle_noise_std_deg", "deg", "float64", "the sensor noise's share of angle_std_deg; the rest, "
           "√(angle_std² − angle_noise_std²), is model error; manual §3.5", "evidence", "angle_noise_std"),
    Column("latched", "", "bool", "the contact point is the latched one, not this sample's own solution; manual §3.6", "latch",
           "latched"),
    Column("latch_fallback", "", "bool", "that latch had no light-force sample; manual §3.6", "latch", "latch_fallback"),
    Column("relatched", "", "bool", "a new latch starts at this sample", "latch", "relatched"),
    Column("depth", "m", "float64", "depth of the moment's point inside the skin, the depth compensation used (0 without it, "
           "in contact; empty when none); manual §3.7", "depth", "depth"),
    Column("line_fit_conditioning", "", "float64", "the line-fit window's reciprocal condition number, in [0, 1]", "line-fit",
           "line_fit_conditioning"),
    Column("line_fit_angle_std_deg", "deg", "float64", "standard deviation of the line-fit window's line angle", "line-fit",
           "line_fit_angle_std"),
    Column("line_fit_offset_std", "m", "float64", "standard deviation of the line-fit window's offset across the line",
           "line-fit", "line_fit_offset_std"),
    Column("line_fit_residual", "", "float64", "the line-fit window's RMS fit residual, in noise standard deviations",
           "line-fit", "line_fit_residual"),
    Column("line_fit_fallback", "", "bool", "the line-fit mode accepted no window of this contact yet, so the point is the latched one",
           "line-fit", "line_fit_fallback"),
    Column("contact_id", "", "int64", "1, 2, … per contact, 0 out of contact", "contact", "contact_id"),
    *_xyz("drift_f", "N", "bias drift of the force, followed while untouched since the tare; empty while taring", "contact",
          "drift"),
    *_xyz("drift_m", "N·m", "bias drift of the moment, followed while untouched since the tare; empty while taring", "contact",
          "drift", offset=3),
    Column("depth_std", "m", "float64", "standard deviation of the depth", "depth", "depth_std"),
    Column("depth_from_data", "", "bool", "the contact's own data, not the skin law, determined the depth", "depth",
           "depth_from_data"),
    Column("line_evidence", "", "str", "confirmed or unconfirmed on line samples: whether the contact was excited about two "
           "tangent axes with h staying on one; manual §3.5", "evidence", "line_evidence", codes=EVIDENCE, topic="line_evidence",
           field="data"),
    Column("h_ratio", "", "float64", "smaller / larger eigenvalue of the evidence window's covariance of h, noise removed",
           "evidence", "h_ratio"),
    Column("excitation_ratio", "", "float64", "the same for the tangential load: how far it turned", "evidence",
           "excitation_ratio"),
)  # fmt: skip

#: Attributes of :class:`~softtip.estimator.Estimates` and
#: :class:`~softtip.estimator.SampleEstimate` that are not output columns, and why.
NOT_COLUMNS = {
    "pulling": "in contact by force but no pushing contact point; reported as state none",
    "taring": "a tare sample; reported as state none with an empty wrench",
    "bias": "one value per log (the tare's), not per sample",
    "tare_force_std": "one value per log",
    "repeated_stamps": "one value per log",
    "tare": "the tare's report",
    "started_in_contact": "one value per log",
    "drift_alarm": "one value per log",
    "warnings": "the run's warnings",
}


@dataclass(frozen=True)
class Topic:
    """A ROS topic that carries output columns (:attr:`Column.topic`).

    Attributes
    ----------
    key : str
        The name :attr:`Column.topic` uses; the topic is ``/softtip/<key>``.
    msgtype : str
        The ROS 2 message type.
    in_bag : bool
        ``--to-bag`` writes it (the ROS 2 node publishes every topic).
    """

    key: str
    msgtype: str
    in_bag: bool = True

    @property
    def name(self) -> str:
        """The topic's name."""
        return f"/softtip/{self.key}"


#: The topics of the estimates, in the order a bag declares them.
TOPICS: tuple[Topic, ...] = (
    Topic("wrench", "geometry_msgs/msg/WrenchStamped"),
    Topic("state", "std_msgs/msg/String"),
    Topic("contact_point", "geometry_msgs/msg/PointStamped"),
    Topic("normal", "geometry_msgs/msg/Vector3Stamped"),
    Topic("edge_direction", "geometry_msgs/msg/Vector3Stamped"),
    Topic("line_evidence", "std_msgs/msg/String"),
    Topic("angle_std", "std_msgs/msg/Float64", in_bag=False),
)


def column_names() -> list[str]:
    """The names of :data:`COLUMNS`, in order."""
    return [c.name for c in COLUMNS]


def _groups() -> list[list[Column]]:
    """The columns in order, the components of one vector attribute together."""
    groups: list[list[Column]] = []
    for c in COLUMNS:
        last = groups[-1][-1] if groups else None
        if last is not None and c.index is not None and (last.attr, last.description) == (c.attr, c.description):
            groups[-1].append(c)
        else:
            groups.append([c])
    return groups


def _group_name(group: list[Column], separator: str = "..") -> str:
    return group[0].name if len(group) == 1 else f"{group[0].name}{separator}{group[-1].name}"


def _unit_text(c: Column) -> str:
    return {"deg": "degrees", "": ""}.get(c.unit, c.unit)


def help_text() -> str:
    """The columns as ``--help`` text: ``name [unit]: description.`` for each, in order (the
    components of a vector as ``fx..fz``)."""
    parts = []
    for group in _groups():
        c = group[0]
        unit = _unit_text(c)
        parts.append(f"{_group_name(group)}{f' [{unit}]' if unit else ''}: {c.description}.")
    return " ".join(parts)


def markdown_table() -> str:
    """The columns as the Markdown table of manual §4 (``docs/guide/columns.md``)."""
    lines = [
        "<!-- written by scripts/make_column_table.py from softtip.estimator.columns; do not edit -->",
        "",
        "| column | unit | type | stage | meaning | ROS topic (field) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    names = {t.key: t.name for t in TOPICS}
    for group in _groups():
        c = group[0]
        name = f"`{_group_name(group, '` … `')}`"
        field = c.field if len(group) == 1 or c.field is None else c.field.rsplit(".", 1)[0]
        topic = f"`{names[c.topic]}` ({field})" if c.topic is not None else ""
        lines.append(f"| {name} | {_unit_text(c)} | {c.dtype} | {c.stage} | {c.description} | {topic} |")
    return "\n".join(lines) + "\n"

