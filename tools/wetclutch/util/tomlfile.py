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
