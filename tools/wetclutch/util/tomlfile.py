"""Reading a TOML file (calibrations, shift calibrations, plants) with one-line errors."""
from __future__ import annotations

import tomllib
from pathlib import Path


def read_toml(path: str | Path, error: type[Exception], what: str) -> dict:
    """The parsed document of path; a missing or unreadable file, bad TOML or text that is not UTF-8
    raises error(message) naming the file and what it should have been (no traceback)."""
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as e:
        raise error(f"{path}: cannot read {what}: {e.strerror or e}") from None
    except tomllib.TOMLDecodeError as e:
        raise error(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:
        raise error(f"{path}: not UTF-8 text (byte {e.start}): not a {what}") from None


def extends_path(path: Path, doc: dict, chain: tuple, error: type[Exception]) -> Path | None:
    """The base file a plant or vehicle file names in its 'extends' entry (popped from doc), resolved against the
    file's folder; None without one. Raises error naming the file for a bad entry, a loop through chain (the
    files already read) or a missing base."""
    entry = doc.pop("extends", None)
    if entry is None:
        return None
    if not isinstance(entry, str) or not entry.strip():
        raise error(f"{path}: 'extends' must be the path of a base plant file (relative to this file)")
    base = (path.parent / entry).resolve()
    if base in chain:
        raise error(f"{path}: 'extends' loop: {' -> '.join(str(c) for c in chain + (base,))}")
    if not base.is_file():
        raise error(f"{path}: 'extends': base plant file {base} not found")
    return base
