"""The transmission through its CAN frames (issue 29 item 3; DESIGN 15): the firmware's frame loop with
config.transmission, in process (wc_replay --gearbox --lockstep through a pipe, the same wc_loop_iterate as
wc_tcu), driven with the frames a vehicle's TCU receives and read back from the frames it sends.

Each period the caller's values go out as ShiftCommand (ShiftRequest, CurrentGear, TargetGear, TurbineTorque,
TargetInertiaTime) and GearboxSensors (turbine and output speed, oil and housing temperature; last: it steps
the loop on the frame clock), each with its E2E CRC and alive counter (wetclutch.util.canlog.Encoder); what
comes back is one ElementXVfsCommand per element, GearboxStatus, EngineTorqueRequest and, when a shift ends,
ShiftReport, decoded with the DBC. So every value crosses its DBC scaling both ways: speeds in 0.25 rpm,
temperatures in 0.1 K (the housing in 1 K), the turbine torque in 0.05 N m, currents in 1/32 mA.

FrameTransmission.step has the signature and the result fields of transmission8.Transmission.step (the
ctypes path, wc_transmission_step alone), so a closed loop can run either: the difference is the frames.
"""
from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from ..calibration import cal_image, shift as shift_calibration
from ..util import canlog
from .matrix8 import CONTROLLER, _element_clutch_values
from .scenarios import SHIFT_TOML, ShiftError
from .tcu import InprocTcu

ELEMENTS = ("A", "B", "C", "D", "E")         # lut/wc_8hp_gearbox.h: element e is bit e
GEARBOX = "8hp"                              # wc_replay --gearbox (the table compiled in)
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


def element_images(gearbox_path) -> list[bytes]:
    """One calibration image per element: its own clutch (pack, piston, spring, VFS of the description), shift
    control off (wc_replay --element-image)."""
    return [cal_image.write_image_bytes({**_element_clutch_values(str(gearbox_path), e),
                                         **cal_image._shift_values(None),          # noqa: SLF001
                                         **cal_image.loop_values(None, False)}) for e in ELEMENTS]


def shift_image(gearbox_path) -> bytes:
    """The image whose shift part is the transmission's shift calibration (the whole shift's controller of
    tools/calibrations/shift_1_2.toml; each shift's driveline model is the table's) and whose loop part gives
    the timeouts; its clutch part is element A's (not used by the transmission)."""
    base = shift_calibration.load(SHIFT_TOML).variants[CONTROLLER]
    return cal_image.write_image_bytes({**_element_clutch_values(str(gearbox_path), ELEMENTS[0]),
                                        **cal_image._shift_values(base),      # noqa: SLF001
                                        **cal_image.loop_values(None, True)})


@dataclass
class FrameStep:
    """One period's outputs, decoded from the frames (fields as transmission8._Step)."""
    current_mA: list = field(default_factory=list)
    theta_degC: list = field(default_factory=list)
    engine_delta_Nm: float = 0.0
    engine_active: int = 0
    gear: int = 0
    phase: int = 0
    type: int = 0
    refusal: int = 0
    ended: int = 0
    report: list = field(default_factory=list)   # inertia s, RMSE rad/s, jerk, energy J, peak theta, flare,
    #                                              tie-up, abort reason, fallback (NaN: not on the bus)
    status: int = 0                              # GearboxStatus's status word (bit n: the n-th Status* signal)
    roles: list = field(default_factory=list)
    frames: list = field(default_factory=list)   # (id, data) as sent, for frame-level checks


class FrameTransmission:
    """wc_replay --gearbox 8hp --lockstep on the gearbox's element images and the shift image."""

    def __init__(self, gearbox_path, gear: int, theta_start_degC: float, holding_margin: float = 1.3,
                 holding_floor_Nm: float = 10.0):
        self._dir = tempfile.TemporaryDirectory(prefix="wc_transmission_frames_")
        d = Path(self._dir.name)
        args = ["--gearbox", GEARBOX]
        for e, image in zip(ELEMENTS, element_images(gearbox_path)):
            (d / f"{e}.img").write_bytes(image)
            args += ["--element-image", str(d / f"{e}.img")]
        (d / "shift.img").write_bytes(shift_image(gearbox_path))
        args += ["--calibration-image", str(d / "shift.img"), "--start-gear", str(int(gear)),
                 "--theta-start", f"{theta_start_degC:.6g}", "--holding-margin", f"{holding_margin:.9g}",
                 "--holding-floor", f"{holding_floor_Nm:.9g}"]
        self.tcu = InprocTcu.with_arguments(args)
        self.enc = canlog.Encoder()
        db = self.enc.db
        self.messages = {m.frame_id: m for m in db.messages}
        self.element_ids = [db.get_message_by_name(n).frame_id for n in canlog.ELEMENT_COMMANDS[:len(ELEMENTS)]]
        self.status_id = db.get_message_by_name(canlog.GEARBOX_STATUS).frame_id
        self.engine_id = db.get_message_by_name(canlog.ENGINE_REQUEST).frame_id
        self.report_id = db.get_message_by_name(canlog.SHIFT_REPORT).frame_id
        self.status_bits = [s.name for s in db.get_message_by_name(canlog.GEARBOX_STATUS).signals
                            if s.name.startswith("Status")]
        self.k = 0

    def step(self, request, current, target, torque_Nm, target_s, w_t, w_o, oil, housing) -> FrameStep:
        frames = [self.enc.frame(canlog.SHIFT_COMMAND, ShiftRequest=int(bool(request)), AdaptationReset=0,
                                 TargetGear=int(target), CurrentGear=int(current),
                                 TurbineTorque=min(max(float(torque_Nm), -1000.0), 1000.0),
                                 TargetInertiaTime=round(float(target_s) * 1e3)),
                  self.enc.frame(canlog.GEARBOX_SENSORS, TurbineSpeed=_clip_rpm(w_t), OutputSpeed=_clip_rpm(w_o),
                                 OilTemp=float(oil), HousingTemp=float(round(housing)))]
        out = self.tcu.exchange(1.0e6 + self.k * 1e-3, frames)
        self.k += 1
        return self._decode(out)

    def _decode(self, out) -> FrameStep:
        o = FrameStep(current_mA=[math.nan] * len(ELEMENTS), theta_degC=[math.nan] * len(ELEMENTS),
                      roles=[0] * len(ELEMENTS), frames=out)
        for fid, data in out:
            sig = self.messages[fid].decode(data, decode_choices=False)
            if fid in self.element_ids:
                e = self.element_ids.index(fid)
                o.current_mA[e], o.theta_degC[e], o.roles[e] = sig["VfsCurrent"], sig["EstimatedTemp"], sig["Role"]
            elif fid == self.status_id:
                o.gear, o.phase, o.type, o.refusal = (int(sig["Gear"]), int(sig["ShiftPhase"]), int(sig["ShiftType"]),
                                                      int(sig["Refusal"]))
                o.status = sum(int(sig[b]) << n for n, b in enumerate(self.status_bits))
            elif fid == self.engine_id:
                o.engine_active, o.engine_delta_Nm = int(sig["InterventionActive"]), float(sig["TorqueDelta"])
            elif fid == self.report_id:
                o.ended = 1
                o.report = [sig["InertiaPhaseTime"] * 1e-3, sig["SlipRmse"] / RPM_PER_RAD_S, sig["PeakJerk"],
                            sig["FrictionEnergy"] * 1e3, sig["PeakClutchTemp"], sig["Flare"], sig["TieUp"],
                            sig["AbortReason"], math.nan]
        if any(math.isnan(c) for c in o.current_mA):
            raise ShiftError(f"wc_replay --gearbox: a period without every element's VFS command: {out}")
        return o

    def close(self) -> None:
        self.tcu.close()
        self._dir.cleanup()


def _clip_rpm(w_rad_s: float) -> float:
    return min(max(float(w_rad_s) * RPM_PER_RAD_S, -8000.0), 8000.0)
