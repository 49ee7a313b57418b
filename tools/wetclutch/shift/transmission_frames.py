"""The transmission through its CAN frames (issue 29 item 3; DESIGN 15): the firmware's frame loop with
config.transmission, in process through ctypes (libwc_transmission_host's frames mode,
src/host/wc_transmission_host.c: the same wc_loop_iterate as wc_tcu and wc_replay --gearbox), driven with the
frames a vehicle's TCU receives and read back from the frames it sends.

Each period the caller's values go out as ShiftCommand (ShiftRequest, CurrentGear, TargetGear, TurbineTorque,
TargetInertiaTime) and GearboxSensors (turbine and output speed, oil and housing temperature; last: it steps
the loop on the frame clock), each with its E2E CRC and alive counter, encoded by the generated codec; what
comes back is one ElementXVfsCommand per element, GearboxStatus, EngineTorqueRequest and, when a shift ends,
ShiftReport, decoded the same way. So every value crosses its DBC scaling both ways: speeds in 0.25 rpm,
temperatures in 0.1 K (the housing in 1 K), the turbine torque in 0.05 N m, currents in 1/32 mA.

FrameTransmission.step has the signature and the result record of transmission8.Transmission.step (which calls
wc_transmission_step alone), so a closed loop can run either: the difference is the frames. With record=True
each step's frames in and out are kept (frames_log: a candump -L log that wc_replay --gearbox replays).
"""
from __future__ import annotations

import ctypes
from pathlib import Path

from ..util import canlog
from .scenarios import ShiftError
from .transmission8 import (ELEMENTS, HOLDING_FLOOR_NM, HOLDING_MARGIN, _library, _Step,  # noqa: F401
                            element_images, shift_image, tcu_images)

GEARBOX = "8hp"                              # wc_replay --gearbox: the compiled-in table of the 8HP description
MAX_FRAMES = 2 + 9                           # a step's frames: ShiftCommand, GearboxSensors, WC_LOOP_TX_FRAMES


class FrameTransmission:
    """The frame loop with the transmission on the gearbox's element images and the shift image, in process."""

    def __init__(self, gearbox_path, gear: int, theta_start_degC: float, holding_margin: float = HOLDING_MARGIN,
                 holding_floor_Nm: float = HOLDING_FLOOR_NM, lib=None, record: bool = False):
        self.lib = lib or _library()
        u, f = ctypes.c_uint32, ctypes.c_float
        self.lib.wc_host_tx_init_frames.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.POINTER(u), u, f, f, f]
        self.lib.wc_host_tx_frames.argtypes = [ctypes.c_void_p, ctypes.POINTER(u), ctypes.c_char_p, u]
        self.lib.wc_host_tx_frames.restype = u
        images = tcu_images(gearbox_path)
        self.state = ctypes.create_string_buffer(self.lib.wc_host_tx_size())
        lengths = (u * len(images))(*[len(b) for b in images])
        rc = self.lib.wc_host_tx_init_frames(self.state, b"".join(images), lengths, gear, theta_start_degC,
                                             holding_margin, holding_floor_Nm)
        if rc != 0:
            raise ShiftError(f"wc_host_tx_init_frames refused the configuration (code {rc})")
        self.out = _Step()
        self.record = record
        self.log: list[tuple[int, int, bytes]] = []      # (period, id, data), inputs first, with record
        self._ids = (u * MAX_FRAMES)()
        self._data = ctypes.create_string_buffer(8 * MAX_FRAMES)
        self.k = 0

    def step(self, request, current, target, torque_Nm, target_s, w_t, w_o, oil, housing, safe=False) -> _Step:
        """Transmission.step's; safe is the frame loop's own (its inputs' freshness): the argument is ignored."""
        rc = self.lib.wc_host_tx_step(self.state, int(request), current, target, torque_Nm, target_s, w_t, w_o, oil,
                                      housing, int(bool(safe)), ctypes.byref(self.out))
        if rc != 0:
            raise ShiftError(f"the frame loop's step {self.k}: its frames did not decode (code {rc})")
        if self.record:
            self.log.extend((self.k, fid, data) for fid, data in self.frames())
        self.k += 1
        return self.out

    def frames(self) -> list[tuple[int, bytes]]:
        """The last step's frames: ShiftCommand, GearboxSensors, then what the loop sent (id, 8 bytes)."""
        n = self.lib.wc_host_tx_frames(self.state, self._ids, self._data, MAX_FRAMES)
        raw = self._data.raw
        return [(int(self._ids[i]), raw[8 * i:8 * i + 8]) for i in range(n)]

    def close(self) -> None:
        """Nothing held outside the process (kept for the closed loops' symmetry with the pipe-driven TCUs)."""


def write_inputs_log(log: list[tuple[int, int, bytes]], path: Path, dt_s: float = 1e-3) -> int:
    """The recorded input frames (ShiftCommand, GearboxSensors of every period) as a candump -L log, the
    period's time stamp; returns the number of frames. wc_replay --gearbox on it sends the recorded outputs."""
    db = canlog.database()
    inputs = {db.get_message_by_name(n).frame_id for n in (canlog.SHIFT_COMMAND, canlog.GEARBOX_SENSORS)}
    lines = [f"({1.0e6 + k * dt_s:.6f}) vcan0 {fid:03X}#{data.hex().upper()}\n" for k, fid, data in log if fid in inputs]
    Path(path).write_text("".join(lines))
    return len(lines)
