"""Writing a calibration file (``wetclutch identify``): the base file with some values and sources replaced."""
from __future__ import annotations

import re
from pathlib import Path

from .parameters import PARAMETERS, Calibration


# ---------------------------------------------------------------------------
# Writing a calibration file

_LINE = re.compile(r'^(\s*)([A-Za-z_][A-Za-z0-9_]*)(\s*=\s*)\{.*\}\s*(#.*)?$')


def _fmt(x: float) -> str:
    return repr(float(f"{x:.7g}"))


def render_calibration(base_path: Path, cal: Calibration, changes: dict[str, float], sources: dict[str, str],
                       header: str) -> str:
    """The base file with the changed values and their sources replaced (comments kept)."""
    units = {name: (section, unit) for section, name, unit, *_ in PARAMETERS}
    text = Path(base_path).read_text(encoding="utf-8")
    section = None
    done = set()
    lines = []
    for line in text.splitlines():
        m_sec = re.match(r'^\s*\[([^\]]+)\]\s*(#.*)?$', line)
        if m_sec:
            section = m_sec.group(1).strip()
        m = _LINE.match(line)
        if m and m.group(2) in changes and units[m.group(2)][0] == section:
            name = m.group(2)
            src = sources[name].replace("\\", "/").replace('"', "'")
            line = f'{m.group(1)}{name}{m.group(3)}{{ value = {_fmt(changes[name])}, unit = "{units[name][1]}",' \
                   f' source = "{src}" }}'
            done.add(name)
        lines.append(line)
    if done != set(changes):
        # the base is not in the one-line-per-parameter form: write every parameter out instead
        return _render_full(cal.with_values(**changes), {**cal.sources, **sources}, header)
    return header + "\n".join(lines) + "\n"


def _render_full(cal: Calibration, sources: dict[str, str], header: str) -> str:
    out = [header.rstrip("\n")]
    section = None
    for sec, name, unit, constraint, _ in PARAMETERS:
        if sec != section:
            out.append(f"\n[{sec}]")
            section = sec
        value = cal.values[name]
        text = str(int(value)) if constraint == "count" else _fmt(value)
        src = sources[name].replace("\\", "/").replace('"', "'")
        out.append(f'{name} = {{ value = {text}, unit = "{unit}", source = "{src}" }}')
    return "\n".join(out) + "\n"
