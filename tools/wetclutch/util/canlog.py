"""CAN logs in candump -L format, encoded and decoded with the DBC (hil/wetclutch.dbc).

Encoding and decoding use cantools (the DBC is the single source of truth);
log files are read and written with python-can's candump-log classes. The
E2E CRC (SAE J1850 over the data id then bytes 1..7) and the alive counter
are computed here independently of the firmware's C code, so a mismatch
between the two shows up as rejected frames.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import can
import cantools
import numpy as np

from .errors import LogError

ROOT = Path(__file__).resolve().parents[3]
DBC_PATH = ROOT / "hil" / "wetclutch.dbc"

SENSORS, REQUEST, COMMAND, ESTIMATE, BENCH = (
    "ClutchSensors", "TorqueRequest", "VfsCommand", "ClutchEstimate", "BenchMeasurement")
SHIFT_COMMAND, SHIFT_REPORT = "ShiftCommand", "ShiftReport"
# the whole shift (DESIGN 14)
OFFGOING_SENSORS, OFFGOING_COMMAND, ENGINE_REQUEST = "OffgoingSensors", "OffgoingVfsCommand", "EngineTorqueRequest"
# the transmission (DESIGN 15): the gearbox's inputs, its status and one VFS command per element (A..F)
GEARBOX_SENSORS, GEARBOX_STATUS = "GearboxSensors", "GearboxStatus"
ELEMENT_COMMANDS = tuple(f"Element{letter}VfsCommand" for letter in "ABCDEF")
E2E_FRAMES = (SENSORS, REQUEST, SHIFT_COMMAND, COMMAND, OFFGOING_SENSORS, OFFGOING_COMMAND, ENGINE_REQUEST,
              GEARBOX_SENSORS, GEARBOX_STATUS, *ELEMENT_COMMANDS)
MODE_OPEN, MODE_TORQUE_CONTROL, MODE_LOCKED, MODE_SHIFT = 0, 1, 2, 3




def database(path: Path = DBC_PATH) -> cantools.database.Database:
    return cantools.database.load_file(str(path), strict=True)


def _crc8_j1850_byte(crc: int) -> int:
    """SAE J1850 CRC-8 (polynomial 0x1D) of one byte, bit by bit."""
    for _ in range(8):
        crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


_CRC8_J1850_TABLE = bytes(_crc8_j1850_byte(b) for b in range(256))   # a byte at a time: every frame of a closed loop


def crc8_j1850(data: bytes) -> int:
    """SAE J1850 CRC-8 (AUTOSAR E2E profile 1's): init 0xFF, final XOR 0xFF."""
    crc = 0xFF
    for byte in data:
        crc = _CRC8_J1850_TABLE[crc ^ byte]
    return crc ^ 0xFF


def protect(frame_id: int, payload: bytearray) -> bytearray:
    payload[0] = crc8_j1850(bytes([frame_id & 0xFF]) + bytes(payload[1:8]))
    return payload


@dataclass
class Encoder:
    """Encodes physical values to frames, keeping one alive counter per E2E frame."""

    db: cantools.database.Database = field(default_factory=database)
    counters: dict = field(default_factory=dict)

    def frame(self, name: str, **signals) -> can.Message:
        msg = self.db.get_message_by_name(name)
        if name in E2E_FRAMES:
            count = self.counters.get(name, 0)
            self.counters[name] = (count + 1) % 16
            signals = {"Crc": 0, "AliveCounter": count, **signals}
        data = bytearray(msg.encode(signals, scaling=True, strict=True))
        if name in E2E_FRAMES:
            protect(msg.frame_id, data)
        return can.Message(arbitration_id=msg.frame_id, is_extended_id=False, data=bytes(data))


def write_log(path: Path, messages: list[tuple[float, can.Message]], channel: str = "vcan0") -> None:
    """Write (timestamp_s, message) pairs as a candump -L log.

    Written by hand rather than with python-can's writer, which appends a
    direction field (' R') that can-utils 2020.11 canplayer does not expect."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="\n") as f:
        for stamp, msg in messages:
            ident = f"{msg.arbitration_id:08X}" if msg.is_extended_id else f"{msg.arbitration_id:03X}"
            f.write(f"({stamp:.6f}) {channel} {ident}#{bytes(msg.data).hex().upper()}\n")


def input_log(t_s, slip_rpm, oil_degC, housing_degC, request_Nm, mode=MODE_TORQUE_CONTROL,
              bench=None, start_s: float = 1.0e6):
    """Frames the TCU receives, one period per row: TorqueRequest, BenchMeasurement
    if given (dict of arrays load_cell_N, torque_Nm, thermistor_degC), then
    ClutchSensors last, so that the step it triggers (frame clock) sees that
    period's request and measurement."""
    enc = Encoder()
    n = len(t_s)
    modes = np.broadcast_to(np.asarray(mode), (n,))
    out = []
    for k in range(n):
        stamp = start_s + float(t_s[k])
        out.append((stamp, enc.frame(REQUEST, TorqueRequest=float(request_Nm[k]), Mode=int(modes[k]))))
        if bench is not None:
            out.append((stamp + 2e-6, enc.frame(BENCH, LoadCellForce=float(bench["load_cell_N"][k]),
                                                MeasuredTorque=float(bench["torque_Nm"][k]),
                                                ClutchThermistorTemp=float(bench["thermistor_degC"][k]))))
        out.append((stamp + 4e-6, enc.frame(SENSORS, SlipSpeed=float(slip_rpm[k]), OilTemp=float(oil_degC[k]),
                                            HousingTemp=float(housing_degC[k]))))
    return out


def read_log(path: Path) -> list[can.Message]:
    """Read a candump -L log; a malformed line is an error naming the line."""
    path = Path(path)
    if not path.is_file():
        raise LogError(f"{path}: {'not a file' if path.exists() else 'no such log file'}")
    try:
        with open(path, encoding="utf-8") as f:
            return read_log_lines(f, str(path))
    except UnicodeDecodeError:
        raise LogError(f"{path}: not UTF-8 text: not a candump -L log") from None
    except OSError as e:
        raise LogError(f"{path}: cannot read: {e.strerror}") from None


def read_log_lines(lines, what: str) -> list[can.Message]:
    """The messages of candump -L lines (a file, or a program's output split into lines); what names them
    in the error of a malformed line."""
    messages = []
    for line_no, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            msg = next(iter(can.CanutilsLogReader([line])))
        except (StopIteration, ValueError, IndexError) as e:
            raise LogError(f"{what}: line {line_no}: not a candump -L line: {line.strip()[:80]!r} ({e})") \
                from None
        if not np.isfinite(msg.timestamp):
            raise LogError(f"{what}: line {line_no}: timestamp {msg.timestamp} is not finite")
        messages.append(msg)
    return messages


def decode(messages, db=None, scaling: bool = True) -> dict[str, dict[str, np.ndarray]]:
    """Decode every known frame into arrays of physical values per frame name (raw values with
    scaling=False, exact as floats: no signal is wider than 53 bits), plus '_t' (timestamps). Frames of
    an id not in the DBC (or of an extended id: the DBC's are standard) are counted under '_unknown',
    frames of a known id with the wrong length (a remote frame, a short one) under '_malformed': counted,
    not used; each also counts them per id under 'ids' ({id: count})."""
    db = db or database()
    rows: dict[str, list] = {}
    unknown: dict[int, int] = {}
    malformed: dict[int, int] = {}
    for msg in messages:
        try:
            spec = db.get_message_by_frame_id(msg.arbitration_id)
        except KeyError:
            spec = None
        if spec is None or bool(msg.is_extended_id) != spec.is_extended_frame:
            unknown[msg.arbitration_id] = unknown.get(msg.arbitration_id, 0) + 1
            continue
        if len(msg.data) != spec.length:
            malformed[msg.arbitration_id] = malformed.get(msg.arbitration_id, 0) + 1
            continue
        values = spec.decode(bytes(msg.data), decode_choices=False, scaling=scaling)
        rows.setdefault(spec.name, []).append((msg.timestamp, values))
    out = {}
    for name, items in rows.items():
        cols = {"_t": np.array([t for t, _ in items])}
        for key in items[0][1]:
            cols[key] = np.array([float(v[key]) for _, v in items])
        out[name] = cols
    out["_unknown"] = {"count": sum(unknown.values()), "ids": unknown}
    out["_malformed"] = {"count": sum(malformed.values()), "ids": malformed}
    return out
