"""Settings as data: what each field of :class:`~softtip.estimator.EstimatorConfig` is.

Every field of the estimator's configuration carries a :class:`Setting` in its dataclass
metadata (:func:`setting`): its unit, its valid range or choices, a one-line help and its
group. From these the configuration checks its values (:func:`check_value`), the ``softtip``
commands build their estimator options (``--`` + the field name, ``_`` → ``-``:
:func:`softtip.cli.options.estimator_options`) and the ROS 2 node declares its parameters
(the field name: :mod:`softtip.ros.node`). One name per setting everywhere.

Inside, every value is in SI (angles in rad, lengths in m). On the command line a setting may
be typed in a handier unit (:attr:`Setting.cli_unit`: angles in degrees, small lengths in mm
with any unit suffix, small moments in N·mm, forces in N or kgf); ROS parameters are the
field's SI value as it is.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Setting", "setting", "settings_of", "check_value", "range_text"]

#: How a setting is given: a number, an integer, a flag, a choice, a fixed tuple of numbers
#: (:attr:`Setting.parts`), a list of such tuples, or a composite value made from other
#: options (:attr:`Setting.options`).
KINDS = ("float", "int", "bool", "choice", "tuple", "tuples", "composite")


@dataclass(frozen=True)
class Setting:
    """What one estimator setting is: the metadata of a config field.

    Attributes
    ----------
    help : str
        One line (or two) for ``--help`` and the ROS parameter's description.
    kind : str
        One of :data:`KINDS`.
    unit : str
        The field's unit in SI (``"s"``, ``"N"``, ``"m"``, ``"rad"``; free text for a
        dimensionless one, e.g. ``"noise standard deviations"``; ``""`` for none).
    low, high : float or None
        Valid range in ``unit``; ``low_open``/``high_open`` exclude the bound itself.
    optional : bool
        ``None`` is a value (the setting is off or decided elsewhere); on a ROS parameter it
        is written 0 (a number) or left unset (a tuple).
    choices : tuple of str
        The values of a ``choice``.
    parts : tuple of Setting
        The elements of a ``tuple`` / ``tuples`` setting, each with its own unit and range;
        their ``name`` is the metavar (``LOW``, ``HIGH``).
    make : callable or None
        Builds the field's value from the tuple of its parts (e.g. a
        :class:`~softtip.core.depth.DepthLaw`); ``None``: the tuple is the value.
    cli_unit : str or None
        The unit a person types on the command line when not ``unit``: ``"deg"`` (the field
        in rad), ``"mm"`` (a length with an optional unit suffix, bare in mm; the field in
        m), ``"N·mm"`` (the field in N·m), ``"mm/√s"`` (the field in m/√s), ``"force"`` (N
        or kgf; the field in N).
    cli_default : str or None
        The default as ``--help`` shows it, when not the field's default in ``cli_unit``.
    metavar : str or None
        Of the command-line option.
    group : str
        Which stage the setting belongs to (``contact``, ``latch``, ``line-fit``, ...).
    cli, ros : bool
        Whether the setting is a ``softtip`` option / a ROS parameter (``sample_rate`` is no
        option: the commands take it from the data).
    options : tuple of str
        A ``composite`` setting's command-line options (declared by hand where they are
        used), e.g. ``--sensor``, ``--force-noise``, ``--moment-noise`` for ``noise``.
    name : str
        The field's name (set by :func:`settings_of`; a part's metavar).
    """

    help: str
    kind: str = "float"
    unit: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    optional: bool = False
    choices: tuple[str, ...] = ()
    parts: tuple[Setting, ...] = ()
    make: Callable[..., Any] | None = None
    cli_unit: str | None = None
    cli_default: str | None = None
    metavar: str | None = None
    group: str = ""
    cli: bool = True
    ros: bool = True
    options: tuple[str, ...] = ()
    name: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {self.kind!r}")

    @property
    def option(self) -> str:
        """The command-line option: ``--`` + the field name with ``_`` → ``-``."""
        return "--" + self.name.replace("_", "-")

    def inside(self, v: float) -> bool:
        """Whether the number ``v`` (in :attr:`unit`) is finite and in the range."""
        if not math.isfinite(v):
            return False
        if self.low is not None and (v < self.low or (self.low_open and v == self.low)):
            return False
        return not (self.high is not None and (v > self.high or (self.high_open and v == self.high)))


def range_text(s: Setting, scale: float = 1.0, unit: str | None = None) -> str:
    """What a number setting accepts, e.g. ``"a number > 0 s"`` (bounds divided by ``scale``,
    in ``unit``; default the setting's own)."""
    unit = s.unit if unit is None else unit
    tail = f" {unit}" if unit else ""
    lo = None if s.low is None else s.low / scale
    hi = None if s.high is None else s.high / scale
    if lo is not None and hi is not None:
        lb, rb = "(" if s.low_open else "[", ")" if s.high_open else "]"
        return f"a number in {lb}{lo:g}, {hi:g}{rb}{tail}"
    if lo is not None:
        return f"a number {'>' if s.low_open else '≥'} {lo:g}{tail}"
    if hi is not None:
        return f"a number {'<' if s.high_open else '≤'} {hi:g}{tail}"
    return f"a finite number{tail}"


def setting(default: Any, help: str, **kwargs: Any) -> Any:  # noqa: A002 - the metadata's own word
    """A dataclass field with its :class:`Setting` in ``metadata["setting"]``.

    ``kind`` is inferred when not given: ``bool`` for a bool default, ``int`` for an int,
    ``choice`` with ``choices``, ``tuple`` with ``parts``, else ``float``; ``optional`` when
    the default is ``None``.
    """
    if "kind" not in kwargs:
        if isinstance(default, bool):
            kwargs["kind"] = "bool"
        elif isinstance(default, int):
            kwargs["kind"] = "int"
        elif kwargs.get("choices"):
            kwargs["kind"] = "choice"
        elif kwargs.get("parts"):
            kwargs["kind"] = "tuple"
    kwargs.setdefault("optional", default is None)
    parts = tuple(dataclasses.replace(p, name=p.name or p.metavar or "") for p in kwargs.pop("parts", ()))
    meta = Setting(help, parts=parts, **kwargs)
    return field(default=default, metadata={"setting": meta})


def settings_of(cls) -> Iterator[Setting]:
    """The :class:`Setting` of every field of the dataclass ``cls``, in field order, each with its
    field's :attr:`~Setting.name` (a ``TypeError`` for a field without one)."""
    for f in dataclasses.fields(cls):
        s = f.metadata.get("setting")
        if s is None:
            raise TypeError(f"{cls.__name__}.{f.name} has no Setting in its metadata")
        yield dataclasses.replace(s, name=f.name)


def check_value(s: Setting, value: Any) -> Any:
    """``value`` of setting ``s`` checked against its kind and range, normalised (floats, ints,
    bools, tuples of floats).

    Raises
    ------
    ValueError
        Naming the setting, what it got and what it expects.
    """
    if value is None and s.optional:
        return None
    if s.kind == "float":
        try:
            v = float(value)
        except (TypeError, ValueError):
            v = math.nan
        if not s.inside(v):
            none = " or None" if s.optional else ""
            raise ValueError(f"{s.name} must be {range_text(s)}{none}, got {value!r}")
        return v
    if s.kind == "int":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or int(value) != value or not s.inside(value):
            raise ValueError(f"{s.name} must be an integer {range_text(s).removeprefix('a number ')}, got {value!r}")
        return int(value)
    if s.kind == "bool":
        # a string is refused: bool("false") is True (a setting read from text)
        if isinstance(value, (bool, np.bool_)) or (isinstance(value, (int, np.integer)) and value in (0, 1)):
            return bool(value)
        raise ValueError(f"{s.name} must be True or False, got {value!r}")
    if s.kind == "choice":
        if value not in s.choices:
            raise ValueError(f"{s.name} must be one of {', '.join(s.choices)}, got {value!r}")
        return value
    return value  # a tuple, a list of tuples, a composite: checked by the config itself
