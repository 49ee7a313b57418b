"""``wetclutch convert``: a real bench's Vector ASC or BLF log to candump -L, for the replay (canplayer);
a candump -L (or Vector) log to MDF4 (util/mdf.py), for the calibration engineers' tools."""
from __future__ import annotations

import math
import re
from pathlib import Path

from ..util import atomic, canlog, mdf
from ..util.errors import LogError


# --------------------------------------------------------------------------- log conversion

# Lines of a Vector ASC log that are not events: the header, comments, the trigger block's bounds.
_ASC_HEADER = re.compile(r"(date\s|base\s|(no\s+)?internal\s+events\s+logged|begin\s+triggerblock|end\s+triggerblock"
                         r"|//)", re.IGNORECASE)
# what python-can's ASCReader parses as a frame (anything else it skips without a word)
_ASC_PARSED = re.compile(r"\d+\.\d+\s+(\d+\s+(\w+\s+(Tx|Rx)|ErrorFrame)|CANFD)", re.ASCII | re.IGNORECASE)
# events other than frames, skipped and counted: a channel's keyword event ("1 Statistic: ..."), another bus's
# or the logger's event in capitals ("CAN 1 Status:...", "SV: ...", "J1939TP ...", "LIN ..."), markers
_ASC_OTHER_EVENT = re.compile(r"\d+\.\d+\s+(\d+\s+[A-Za-z]\w*:|[A-Z][A-Z0-9]+:?(\s|$)|[Ll]og trigger event"
                              r"|[Pp]retrigger)", re.ASCII)
_ASC_START = re.compile(r"\d+\.\d+\s+start of measurement", re.IGNORECASE)


class _CountingLines:
    """A text file iterated line by line for python-can's ASCReader, remembering the line number and
    checking each line: python-can skips a line it does not understand without a word, so the first line
    that is not a header line, a comment, a frame (parsed by python-can: a broken one is its ValueError)
    or a known kind of other event (_ASC_OTHER_EVENT, counted in .events) is kept in .bad as
    (line, reason), for convert_log to raise once it knows whether the file held any frame at all."""

    def __init__(self, f):
        self.f = f
        self.line = 0
        self.events = 0
        self.bad = None

    def __iter__(self):
        return self

    def __next__(self):
        line = next(self.f)
        self.line += 1
        text = line.strip()
        if not text or _ASC_HEADER.match(text) or _ASC_PARSED.match(text) or _ASC_START.match(text):
            return line
        if _ASC_OTHER_EVENT.match(text):
            self.events += 1
            return line
        if self.bad is None:
            binary = any(ch < " " and ch != "\t" for ch in text) or "\x7f" in text
            self.bad = (self.line, "binary data" if binary else
                        f"not a Vector ASC line (header, comment, frame or event): {text[:60]!r}")
        return line

    def close(self):
        self.f.close()


VECTOR_SUFFIXES = (".asc", ".blf")


def convert_log(in_path, out_path, channel: str = "vcan0") -> dict:
    """Vector ASC or BLF (python-can readers) -> candump -L (canlog.write_log), written atomically.

    Classic CAN data frames are written with the file's timestamps, in the file's order. Error
    frames, remote frames and CAN FD frames (the DBC is classic CAN) are skipped and counted, and so
    are an ASC file's other events (statistics, chip status, ...). A malformed file raises LogError
    naming the file (and for ASC the line: a broken frame, or a line that is neither header,
    comment, frame nor a known kind of event, see _CountingLines); nothing is written then. A frame
    earlier than the one before it is copied as is and listed in 'out_of_order' as (where,
    timestamp, previous timestamp), where being 'line N' (ASC) or 'frame N' (BLF), for the caller
    to warn about.
    """
    messages, stats = read_vector_log(in_path)
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with atomic.atomic_path(out_path) as tmp:
        canlog.write_log(tmp, messages, channel=channel)
    return stats


def read_vector_log(in_path) -> tuple[list, dict]:
    """The classic CAN data frames of a Vector ASC or BLF log as (timestamp, message) pairs, and
    convert_log's figures ("frames", "skipped", "span_s", "out_of_order"); its errors (LogError)."""
    import can
    import struct
    import zlib as _zlib

    in_path = Path(in_path)
    suffix = in_path.suffix.lower()
    if suffix not in VECTOR_SUFFIXES:
        raise LogError(f"{in_path}: unsupported log format {in_path.suffix or '(no suffix)'!r}:"
                       " expected a Vector .asc or .blf file")
    if not in_path.is_file():
        raise LogError(f"{in_path}: {'not a file' if in_path.exists() else 'no such log file'}")
    messages: list = []
    skipped = {"error": 0, "remote": 0, "fd": 0, "event": 0}
    out_of_order: list = []
    lines = None
    try:
        if suffix == ".asc":
            f = open(in_path, encoding="latin-1", newline=None)
            lines = _CountingLines(f)
            reader = can.ASCReader(lines)
        else:
            reader = can.BLFReader(str(in_path))
        with reader:
            for k, msg in enumerate(reader, start=1):
                where = f"line {lines.line}" if lines is not None else f"frame {k}"
                if msg.is_error_frame:
                    skipped["error"] += 1
                elif msg.is_remote_frame:
                    skipped["remote"] += 1
                elif msg.is_fd or len(msg.data) > 8:
                    skipped["fd"] += 1
                elif len(msg.data) != msg.dlc:
                    raise LogError(f"{in_path}: {where}: {len(msg.data)} data bytes, DLC says {msg.dlc}")
                else:
                    stamp = float(msg.timestamp)
                    if not math.isfinite(stamp):
                        raise LogError(f"{in_path}: {where}: timestamp {stamp} is not finite")
                    if messages and stamp < messages[-1][0]:
                        out_of_order.append((where, stamp, messages[-1][0]))
                    messages.append((stamp, msg))
    except LogError:
        if lines is not None and lines.bad:   # an earlier line python-can skipped is the first problem
            raise LogError(f"{in_path}: line {lines.bad[0]}: {lines.bad[1]}") from None
        raise
    except OSError as e:
        raise LogError(f"{in_path}: cannot read: {e.strerror or e}") from None
    except (ValueError, IndexError, KeyError, struct.error, _zlib.error, EOFError, can.CanError,
            can.io.blf.BLFParseError) as e:
        if lines is not None and lines.bad:
            raise LogError(f"{in_path}: line {lines.bad[0]}: {lines.bad[1]}") from None
        where = f": line {lines.line}" if lines is not None else ""
        raise LogError(f"{in_path}{where}: not a valid Vector {suffix[1:].upper()} log ({type(e).__name__}: {e})") from None
    bad = lines.bad if lines is not None else None
    if not messages:
        raise LogError(f"{in_path}: no CAN data frames found (not a Vector {suffix[1:].upper()} log?"
                       + (f" line {bad[0]}: {bad[1]}" if bad else "") + ")")
    if bad:
        raise LogError(f"{in_path}: line {bad[0]}: {bad[1]}")
    if lines is not None:
        skipped["event"] = lines.events
    return messages, {"frames": len(messages), "skipped": skipped, "span_s": messages[-1][0] - messages[0][0],
                      "out_of_order": out_of_order}


def to_mdf4(in_path, out_path) -> dict:
    """A candump -L log (or a Vector .asc/.blf log, read as convert_log reads it) -> MDF4 (util/mdf.py:
    one channel group per DBC frame, physical values and units from hil/wetclutch.dbc), written
    atomically. Frames not in the DBC are left out and counted (mdf.write's summary, "unknown" and
    "malformed" per id); a malformed line, an empty log or a log without any DBC frame raises LogError
    naming the file (and the line); nothing is written then. Returns the summary with "frames" (the
    log's) and, for a Vector log, convert_log's "skipped" and "out_of_order"."""
    in_path = Path(in_path)
    stats: dict = {"skipped": {}, "out_of_order": []}
    if in_path.suffix.lower() in VECTOR_SUFFIXES:
        pairs, stats = read_vector_log(in_path)
        messages = [msg for _, msg in pairs]
    else:
        messages = canlog.read_log(in_path)
        if not messages:
            raise LogError(f"{in_path}: empty log (no candump -L line)")
    summary = mdf.write(out_path, messages, str(in_path))
    return {**summary, "frames": len(messages), "skipped": stats["skipped"], "out_of_order": stats["out_of_order"]}
