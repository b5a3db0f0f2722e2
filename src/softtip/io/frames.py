"""Estimates as an Arrow table or a pandas DataFrame, for Python users (pandas stays optional).

``softtip.estimate`` returns :class:`~softtip.estimator.results.Estimates`; these give its
output columns (the CLI's table, :meth:`Estimates.columns`) to the data-frame world without
writing a file. pyarrow is a dependency; pandas is imported only by :func:`to_pandas`.
"""

from __future__ import annotations

from typing import Any

__all__ = ["to_arrow", "to_pandas"]


def to_arrow(est: Any, units: str = "si") -> Any:
    """The estimates' output columns as a ``pyarrow.Table``.

    Parameters
    ----------
    est : Estimates
        From :func:`softtip.estimate`.
    units : {"si", "kgf-mm"}
        Units of the force (N or kgf) and moment (N·m or kgf·mm) columns; lengths in m,
        angles in degrees (as :meth:`Estimates.columns`).

    Returns
    -------
    pyarrow.Table
        One column per output column, in the CLI's order; ``state`` and ``line_evidence`` as strings.
    """
    import numpy as np
    import pyarrow as pa

    columns = est.columns(units=units)
    return pa.table({name: pa.array(np.asarray(values).tolist() if np.asarray(values).dtype.kind == "U" else values)
                     for name, values in columns.items()})  # fmt: skip


def to_pandas(est: Any, units: str = "si") -> Any:
    """The estimates' output columns as a ``pandas.DataFrame`` (needs pandas; see :func:`to_arrow`).

    Raises
    ------
    ImportError
        pandas is not installed; the message says how to get it.
    """
    try:
        import pandas  # noqa: F401
    except ImportError:
        raise ImportError("to_pandas needs pandas (pip install pandas); to_arrow gives a pyarrow.Table without it") from None
    return to_arrow(est, units).to_pandas()
