"""Extra columns of a Parquet or Arrow IPC log carried into a Parquet or Arrow IPC output with their Arrow type.

softtip's tables hold numpy columns: a Parquet extra column of type binary, list, struct,
timestamp, date, decimal or a nullable integer would come out as text or floats (bytes
replaced by U+FFFD, lists as ``[1 2]``, nulls as NaN), and a nullable integer column whose
first nulls come late in a large file would change type between pieces. Such columns go
through the run as a placeholder and :func:`carry_columns` puts the input's own Arrow
columns in their place in the finished output, batch by batch (memory bounded by a batch).
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

__all__ = ["typed_extras", "placeholder", "carry_columns", "extra_names"]

#: Rows per batch while carrying columns.
_BATCH = 1 << 16


def typed_extras(path: str, required: tuple[str, ...]) -> list[str]:
    """Extra columns of the Parquet or Arrow IPC file ``path`` whose Arrow type numpy would not keep.

    Kept as they are: floating point, strings, booleans (the table's own types). Carried:
    every other type (integers too: a null anywhere would make them floats).
    """
    import pyarrow as pa

    from softtip.io.tables import _columnar, _ColumnarFile

    with _ColumnarFile(path, _columnar(path) or "parquet") as pf:
        schema = pf.schema
    names = []
    for field in schema:
        if field.name.strip() in required:
            continue
        t = field.type
        if pa.types.is_floating(t) or pa.types.is_string(t) or pa.types.is_large_string(t) or pa.types.is_boolean(t):
            continue
        names.append(field.name)
    return names


def placeholder(n: int) -> np.ndarray:
    """What stands for a carried column until :func:`carry_columns` (one byte a row)."""
    return np.zeros(n, dtype=np.int8)


def extra_names(output_names: list[str], extra: list[str]) -> dict[str, str]:
    """The output name of each extra column: its own, or ``input_NAME`` (``input_input_NAME``, ...)
    when an output column (or an earlier extra) already has it."""
    taken = set(output_names)
    out = {}
    for name in extra:
        new = name
        while new in taken:
            new = f"input_{new}"
        taken.add(new)
        out[name] = new
    return out


def carry_columns(source: str, dest: str | os.PathLike[str], renamed: Mapping[str, str]) -> None:
    """Replace the placeholder columns of the Parquet or Arrow IPC file ``dest`` by ``source``'s own columns.

    Parameters
    ----------
    source : str
        The input Parquet or Arrow IPC file (same rows, same order, as ``dest``).
    dest : path
        The output file, rewritten in place in its format (a temporary file beside it, then a
        rename), with the writer settings of :func:`softtip.io.tables.write_table`.
    renamed : mapping
        Input column name -> its name in ``dest``.
    """
    import pyarrow as pa

    from softtip.io.tables import _columnar, _columnar_writer, _ColumnarFile

    if not renamed:
        return
    dest = os.fspath(dest)
    fmt = _columnar(source) or "parquet"
    dest_fmt = _columnar(dest) or "parquet"
    tmp = f"{dest}.carry.tmp"
    src_names = list(renamed)
    try:
        with _ColumnarFile(source, fmt) as src, _ColumnarFile(dest, dest_fmt) as out, open(tmp, "wb") as sink:
            src_schema = src.schema
            schema = out.schema
            for name, new in renamed.items():
                i = schema.get_field_index(new)
                schema = schema.set(i, pa.field(new, src_schema.field(name).type))
            writer = _columnar_writer(sink, schema.empty_table(), schema.metadata and {
                k.decode("utf-8"): v.decode("utf-8") for k, v in schema.metadata.items()}, dest_fmt)  # fmt: skip
            try:
                pending: pa.Table | None = None
                src_batches = src.iter_batches(_BATCH, columns=src_names)
                for batch in out.iter_batches(_BATCH):
                    n = batch.num_rows
                    while pending is None or pending.num_rows < n:
                        more = pa.Table.from_batches([next(src_batches)])
                        pending = more if pending is None else pa.concat_tables([pending, more])
                    take, pending = pending.slice(0, n), pending.slice(n)
                    arrays = []
                    for field in schema:
                        src_name = next((k for k, v in renamed.items() if v == field.name), None)
                        if src_name is None:
                            arrays.append(batch.column(batch.schema.get_field_index(field.name)))
                        else:
                            arrays.append(take.column(src_name).combine_chunks())
                    writer.write_table(pa.Table.from_arrays(arrays, schema=schema))
            finally:
                writer.close()
        os.replace(tmp, dest)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
