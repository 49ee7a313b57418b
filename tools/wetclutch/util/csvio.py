"""CSV in/out, the one reader of the package: a header row, then numbers.

Numbers come in two ways through one row parser: ``read_columns`` (a stream,
e.g. stdin, for the reference model: every cell a finite number) and
``read_table`` (a file, for bench data: an empty or nan/na/null cell is NaN,
a fast path for clean files). ``read_records`` reads a table of text cells
(an index of experiments). Errors name the file, the line (1 is the header)
and the column.
"""
from __future__ import annotations

import csv
import math
import warnings
from pathlib import Path
from typing import IO, Iterable, Mapping, Sequence

import numpy as np

MISSING_CELLS = ("nan", "na", "null")    # read_table: these (and an empty cell) are NaN


class CsvError(Exception):
    pass


def _not_text(source, e: UnicodeDecodeError) -> CsvError:
    return CsvError(f"{source}: not UTF-8 text ({e.reason}): not a CSV file")


def _rows(reader: Iterable[list[str]], source: str, first_line: int) -> Iterable[tuple[int, list[str]]]:
    """(line number, row) of the rows; the number is the csv.reader's own count where it has one.
    Undecodable bytes and CSV syntax errors become CsvError naming the source (and the line)."""
    line_no = first_line - 1
    try:
        for row in reader:
            line_no = reader.line_num if hasattr(reader, "line_num") else line_no + 1
            yield line_no, row
    except UnicodeDecodeError as e:
        raise _not_text(source, e) from None
    except csv.Error as e:
        raise CsvError(f"{source}: line {line_no + 1}: not valid CSV ({e})") from None


def _parse_rows(rows: Iterable[list[str]], header: list[str], columns: Sequence[str], source: str,
                missing_as_nan: bool, finite: bool = True, lines: list[int] | None = None) -> np.ndarray:
    """Data rows (line 2 on) to an array of the columns; blank rows are skipped.

    missing_as_nan False: every cell must be a number, and finite unless finite is False (then nan/inf
    cells are NaN/infinite values). True: an empty or nan/na/null cell is NaN. lines, if given, receives the
    line number of each data row returned."""
    index = [header.index(c) for c in columns]
    values_by_row = []
    for line_no, row in _rows(rows, source, 2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise CsvError(f"{source}: line {line_no}: {len(row)} fields, header has {len(header)}")
        values = []
        for c, i in zip(columns, index):
            cell = row[i].strip()
            if missing_as_nan and (cell == "" or cell.lower() in MISSING_CELLS):
                values.append(math.nan)
                continue
            try:
                v = float(cell)
            except ValueError:
                raise CsvError(f"{source}: line {line_no}: column {c}: {row[i]!r} is not a number") from None
            if not missing_as_nan and finite and not math.isfinite(v):
                raise CsvError(f"{source}: line {line_no}: column {c}: {row[i]!r} is not finite")
            values.append(v)
        values_by_row.append(values)
        if lines is not None:
            lines.append(line_no)
    return np.array(values_by_row, dtype=float).reshape(-1, len(columns))


def read_columns(stream: IO[str], columns: Sequence[str], source: str = "<stdin>", finite: bool = True,
                 lines: list[int] | None = None) -> dict[str, np.ndarray]:
    """The columns of a CSV stream; every cell must be a number, a finite one unless finite is False.
    lines, if given, receives the line number of each data row (blank lines are skipped)."""
    reader = csv.reader(stream)
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise CsvError(f"{source}: empty input, expected a header: {','.join(columns)}") from None
    except UnicodeDecodeError as e:
        raise _not_text(source, e) from None
    except csv.Error as e:
        raise CsvError(f"{source}: line 1: not valid CSV ({e})") from None
    missing = [c for c in columns if c not in header]
    if missing:
        raise CsvError(f"{source}: line 1: missing column(s) {', '.join(missing)}; expected {','.join(columns)}")
    data = _parse_rows(reader, header, columns, source, missing_as_nan=False, finite=finite, lines=lines)
    return {c: data[:, k] for k, c in enumerate(columns)}


def read_header(path: Path) -> list[str]:
    """The column names of a CSV file (its first line)."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            first = f.readline()
    except OSError as e:
        raise CsvError(f"{path}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError:
        raise CsvError(f"{path}: not UTF-8 text: not a CSV file") from None
    if not first.strip():
        raise CsvError(f"{path}: empty file, expected a CSV header")
    return [h.strip() for h in next(csv.reader([first]))]


def check_header(header: list[str], required: Sequence[str], source: str,
                 units: Mapping[str, tuple[str, str]]) -> None:
    """Duplicate and missing columns. units maps a column to (quantity, unit), e.g. force_N -> (force, N), so
    that a column in other units (force_kPa) is named as such rather than reported missing."""
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise CsvError(f"{source}: line 1: duplicate column(s) {', '.join(dup)}")
    problems = []
    known = set(units)
    for c in required:
        if c in header:
            continue
        quantity, unit = units.get(c, (c, ""))
        other = [h for h in header if h not in known and h.startswith(quantity + "_")] if c in units else []
        if other:
            problems.append(f"column '{other[0]}' is in {other[0][len(quantity) + 1:]} where '{c}' ({unit}) is"
                            f" expected: convert the column to {unit} and name it {c}")
        else:
            problems.append(f"missing column '{c}'")
    if problems:
        raise CsvError(f"{source}: line 1: " + "; ".join(problems) + f" (expected columns: {','.join(required)})")


def _parse_file(path: Path, header: list[str], columns: Sequence[str]) -> np.ndarray:
    """Row by row, for files numpy refuses: names the line and column of a bad cell."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        return _parse_rows(reader, header, columns, str(path), missing_as_nan=True)


def read_table(path: Path, required: Sequence[str], optional: Sequence[str] = (),
               units: Mapping[str, tuple[str, str]] | None = None) -> dict[str, np.ndarray]:
    """The required columns and those optional ones present of a CSV file; empty/nan cells are NaN.

    units: see check_header."""
    header = read_header(path)
    check_header(header, required, str(path), units or {})
    columns = list(required) + [c for c in optional if c in header]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # "input contained no data": reported below
            data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[header.index(c) for c in columns],
                              dtype=float, ndmin=2, encoding="utf-8")
    except ValueError:   # also UnicodeDecodeError: _parse_file names the file
        data = _parse_file(path, header, columns)
    if data.shape[0] == 0:
        raise CsvError(f"{path}: no data rows")
    return {c: data[:, k] for k, c in enumerate(columns)}


def read_records(path: Path) -> list[tuple[int, dict]]:
    """The rows of a CSV file with text cells (an index), as (line number, {column: cell}); blank rows skipped."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            return [(line_no, row) for line_no, row in enumerate(csv.DictReader(f), start=2)
                    if row and not all(not (v or "").strip() for v in row.values())]
    except OSError as e:
        raise CsvError(f"{path}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise _not_text(path, e) from None
    except csv.Error as e:
        raise CsvError(f"{path}: not valid CSV ({e})") from None


def write_columns(stream: IO[str], columns: dict[str, np.ndarray], fmt: str = "{:.9g}") -> None:
    names = list(columns)
    arrays = [np.asarray(columns[n]) for n in names]
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(names)
    for k in range(arrays[0].size if arrays else 0):
        writer.writerow([str(int(a[k])) if np.issubdtype(a.dtype, np.integer) else fmt.format(float(a[k]))
                         for a in arrays])
