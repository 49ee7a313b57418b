"""CSV in/out for the reference model: a header row, then numbers.

Errors name the line (1 is the header) and the column.
"""
from __future__ import annotations

import csv
import math
from typing import IO, Sequence

import numpy as np


class CsvError(Exception):
    pass


def read_columns(stream: IO[str], columns: Sequence[str], source: str = "<stdin>") -> dict[str, np.ndarray]:
    reader = csv.reader(stream)
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise CsvError(f"{source}: empty input, expected a header: {','.join(columns)}") from None
    missing = [c for c in columns if c not in header]
    if missing:
        raise CsvError(f"{source}: line 1: missing column(s) {', '.join(missing)}; expected {','.join(columns)}")
    index = [header.index(c) for c in columns]
    rows = []
    for line_no, row in enumerate(reader, start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise CsvError(f"{source}: line {line_no}: {len(row)} fields, header has {len(header)}")
        values = []
        for c, i in zip(columns, index):
            try:
                v = float(row[i])
            except ValueError:
                raise CsvError(f"{source}: line {line_no}: column {c}: {row[i]!r} is not a number") from None
            if not math.isfinite(v):
                raise CsvError(f"{source}: line {line_no}: column {c}: {row[i]!r} is not finite")
            values.append(v)
        rows.append(values)
    data = np.array(rows, dtype=float).reshape(-1, len(columns))
    return {c: data[:, k] for k, c in enumerate(columns)}


def write_columns(stream: IO[str], columns: dict[str, np.ndarray], fmt: str = "{:.9g}") -> None:
    names = list(columns)
    arrays = [np.asarray(columns[n]) for n in names]
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(names)
    for k in range(arrays[0].size if arrays else 0):
        writer.writerow([str(int(a[k])) if np.issubdtype(a.dtype, np.integer) else fmt.format(float(a[k]))
                         for a in arrays])
