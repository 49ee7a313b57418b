"""Loading a calibration file: TOML, units, sources, the firmware's rules (rules.py) and the film table it gives
(film_table.py)."""
from __future__ import annotations

from pathlib import Path

from ..util.tomlfile import read_toml
from . import film_table
from .parameters import OPTIONAL, OPTIONAL_SOURCE, PARAMETERS, Calibration, CalibrationError
from .rules import _check_relations, _check_value


def load(path: str | Path) -> Calibration:
    """Read and validate a calibration file. Raises CalibrationError."""
    path = str(path)
    return from_document(read_toml(path, CalibrationError, "calibration file"), path)


def from_document(doc: dict, path: str) -> Calibration:
    """Validate a parsed calibration document (load's checks; the gearbox description's per-element files with
    their overrides merged in). path names it in every message. Raises CalibrationError."""
    known = {(s, n) for s, n, *_ in PARAMETERS}
    for section, table in doc.items():
        if not isinstance(table, dict):
            raise CalibrationError(f"{path}: '{section}' must be a table of parameters")
        for name in table:
            if (section, name) not in known:
                raise CalibrationError(f"{path}: unknown parameter '{section}.{name}'")

    values: dict[str, float] = {}
    sources: dict[str, str] = {}
    for section, name, unit, constraint, field in PARAMETERS:
        qualified = f"{section}.{name}"
        entry = doc.get(section, {}).get(name)
        if entry is None and name in OPTIONAL:
            values[name], sources[name] = OPTIONAL[name], OPTIONAL_SOURCE
            continue
        if entry is None:
            raise CalibrationError(f"{path}: missing parameter '{qualified}' (unit {unit})")
        if not isinstance(entry, dict) or "value" not in entry:
            raise CalibrationError(
                f"{path}: parameter '{qualified}' must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
        if entry.get("unit") != unit:
            raise CalibrationError(
                f"{path}: parameter '{qualified}': unit {entry.get('unit')!r}, expected {unit!r}")
        source = entry.get("source")
        if not isinstance(source, str) or not source.strip():
            raise CalibrationError(f"{path}: parameter '{qualified}': missing 'source' (paper table or reason)")
        values[name] = _check_value(path, qualified, entry["value"], constraint, field, unit)
        sources[name] = source

    cal = Calibration(values, sources, path)
    _check_relations(cal)
    _check_film(cal)
    return cal


def _check_film(cal: Calibration) -> None:
    """The film table `wetclutch lut` would write from this calibration must pass the firmware's rules."""
    try:
        film_table.build_table(cal)
    except film_table.TableError as e:
        raise CalibrationError(str(e)) from None
