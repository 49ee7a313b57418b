"""CAN frames decoded by the DBC (hil/wetclutch.dbc) -> an ASAM MDF 4 file (asammdf): the one MDF writer
of the package (`wetclutch convert --to mdf4`, the HIL replay report, the shift report); and a simulation's
channels on one time base (``write_channels``: the drive cycle, `wetclutch cycle`).

What the file holds:
  groups    one channel group per CAN frame (message) of the DBC that occurs, in frame-id order; its
            acquisition name is the message's name, its comment the DBC's message comment with the id and
            the sender, its source a CAN bus (the sending node, hil/wetclutch.dbc). Messages that do not
            occur get no group.
  time      each group's master channel "time" [s]: the frame's timestamp minus t0, the earliest
            timestamp of the frames written; the header's start time is t0 (UTC). Exact where t0 and the
            timestamps are within a factor 2 (Sterbenz: any real log, the bundled ones at 1e6 s). Frames
            out of time order are put in order (stable) within their group.
  channels  one per signal: the DBC's signal name, unit and comment (Crc and AliveCounter occur in several
            groups: asammdf's get() wants their group). The
            samples are the raw bus values (the smallest integer type of the signal's bits, signedness as
            in the DBC) with the DBC's conversion, so asammdf's physical values equal cantools' decode
            (raw * factor + offset in float64, the same operations) and raw=True gives the bus value:
              - factor 1, offset 0, no value names: none (counters, status bits, ms): integers;
              - value names for every raw value of the valid range [min|max] (enumerations: Mode,
                LockState, AbortReason): value to text, "undefined" for a raw value without a name;
              - other value names (SNA: raw values outside the valid range): an MDF 4.1 status-string
                table, the names as text and the linear conversion for the rest (asammdf reads SNA as NaN);
              - otherwise the linear conversion phys = factor * raw + offset.
  left out  frames of an id not in the DBC (or an extended id) and frames of a known id with the wrong
            length, counted per id in the returned summary (the caller reports them).
"""
from __future__ import annotations

import io
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from . import atomic, canlog
from .errors import LogError

UNDEFINED_TEXT = "undefined"   # an enumeration's raw value without a name in the DBC


def _raw_dtype(signal) -> np.dtype:
    bits = next(b for b in (8, 16, 32, 64) if signal.length <= b)
    return np.dtype(f"{'int' if signal.is_signed else 'uint'}{bits}")


def _conversion(signal) -> dict | None:
    """The MDF conversion of the signal's raw value to its physical value (asammdf's dict form)."""
    scale, offset = float(signal.scale), float(signal.offset)
    identity = scale == 1.0 and offset == 0.0
    linear = None if identity else {"a": scale, "b": offset}
    names = {int(raw): str(name) for raw, name in (signal.choices or {}).items()}
    if not names:
        return linear
    table: dict = {}
    for i, (raw, name) in enumerate(sorted(names.items())):
        table[f"val_{i}"], table[f"text_{i}"] = raw, name
    valid = range(int(signal.minimum), int(signal.maximum) + 1) if signal.minimum is not None else range(0)
    if identity and valid and all(raw in names for raw in valid):
        table["default_addr"] = UNDEFINED_TEXT                      # an enumeration
    else:
        table["default_addr"] = linear or {"a": 1.0, "b": 0.0}      # a status-string table (SNA)
    return table


def _header(mdf, t0_s: float, subject: str) -> None:
    mdf.header.start_time = datetime.fromtimestamp(t0_s, timezone.utc)
    mdf.header.description = (f"{subject}: CAN frames decoded by hil/wetclutch.dbc (wetclutch);"
                              " time = timestamp - the earliest frame's (the start time)")
    mdf.header.project = "wetclutch"
    mdf.header.subject = subject


def build(messages, subject: str, db=None):
    """The MDF (asammdf.MDF, version 4.10) of the frames (python-can Messages with their timestamps in s)
    and a summary {"groups": {message: frames}, "unknown": {id: frames}, "malformed": {id: frames},
    "t0_s", "span_s"}. Raises LogError (naming subject) when no frame is of the DBC."""
    from asammdf import MDF

    db = db or canlog.database()
    raw = canlog.decode(messages, db, scaling=False)
    unknown, malformed = raw.pop("_unknown")["ids"], raw.pop("_malformed")["ids"]
    summary = {"groups": {}, "unknown": unknown, "malformed": malformed, "t0_s": None, "span_s": 0.0}
    if not raw:
        skipped = sum(unknown.values()) + sum(malformed.values())
        raise LogError(f"{subject}: no frame of hil/wetclutch.dbc"
                       + (f" ({skipped} frame(s) with other ids or lengths)" if skipped else " (no frames)"))
    t0 = min(float(cols["_t"].min()) for cols in raw.values())
    summary["t0_s"] = t0
    summary["span_s"] = max(float(cols["_t"].max()) for cols in raw.values()) - t0
    mdf = MDF(version="4.10")
    try:
        _groups(mdf, raw, t0, subject, db, summary)
    except BaseException:
        mdf.close()
        raise
    return mdf, summary


def _groups(mdf, raw: dict, t0: float, subject: str, db, summary: dict) -> None:
    from asammdf import Signal
    from asammdf.blocks.source_utils import Source

    _header(mdf, t0, subject)
    for spec in sorted((db.get_message_by_name(name) for name in raw), key=lambda m: m.frame_id):
        cols = raw[spec.name]
        order = np.argsort(cols["_t"], kind="stable")
        t = cols["_t"][order] - t0
        signals = [Signal(cols[sig.name][order].astype(_raw_dtype(sig)), t, name=sig.name, unit=sig.unit or "",
                          comment=sig.comment or "", conversion=_conversion(sig))
                   for sig in spec.signals]
        sender = ", ".join(spec.senders) or "?"
        comment = f"{spec.comment or spec.name} (CAN id 0x{spec.frame_id:03X}, sent by {sender}; hil/wetclutch.dbc)"
        mdf.append(signals, acq_name=spec.name, comment=comment, common_timebase=True,
                   acq_source=Source(sender, "hil/wetclutch.dbc", f"CAN id 0x{spec.frame_id:03X}",
                                     Source.SOURCE_BUS, Source.BUS_TYPE_CAN))
        summary["groups"][spec.name] = int(t.size)


def write(path: Path | str, messages, subject: str, db=None) -> dict:
    """build() written to path atomically (util/atomic: a temporary renamed over path; joins an active
    atomic.Staged block). Returns build()'s summary with "path"."""
    mdf, summary = build(messages, subject, db)
    summary["path"] = _save(mdf, path)
    return summary


def _save(mdf, path: Path | str) -> str:
    """mdf saved to path atomically and closed (also when saving fails); the path."""
    try:
        buffer = io.BytesIO()
        mdf.save(buffer, overwrite=True)
    finally:
        mdf.close()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic.open_atomic(path, "wb") as f:
        f.write(buffer.getvalue())
    return str(path)


def write_channels(path: Path | str, time_s, channels: dict, subject: str) -> str:
    """A simulation's channels ({name: (samples, unit)}, each as long as time_s) as one channel group of an
    MDF 4.10 file, float64 physical values, written atomically as write(). Returns the path."""
    from asammdf import MDF, Signal

    t = np.asarray(time_s, dtype=float)
    mdf = MDF(version="4.10")
    try:
        _header(mdf, 0.0, subject)
        mdf.header.description = f"{subject}: simulated channels (wetclutch); time from the cycle's start"
        mdf.append([Signal(np.asarray(x, dtype=float), t, name=name, unit=unit) for name, (x, unit) in
                    channels.items()], acq_name=subject, comment=subject)
    except BaseException:
        mdf.close()
        raise
    return _save(mdf, path)


def skipped_text(summary: dict) -> str:
    """One line on the frames left out ("" if none): how many, per id."""
    parts = []
    for key, what in (("unknown", "with an id not in hil/wetclutch.dbc"), ("malformed", "of a wrong length")):
        ids = summary[key]
        if ids:
            per_id = ", ".join(f"0x{ident:03X}: {count}" for ident, count in sorted(ids.items())[:8])
            more = f", {len(ids) - 8} more ids" if len(ids) > 8 else ""
            parts.append(f"{sum(ids.values())} frame(s) {what} ({per_id}{more})")
    return ("left out " + "; ".join(parts)) if parts else ""
