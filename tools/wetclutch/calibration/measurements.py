"""What a calibration tool may measure in the running TCU over XCP (DESIGN 13): the single source of the
measured signals. From this table come the C table of their places (``src/port/wc_xcp_signals.c``, generated
by ``python -m wetclutch.generate.xcp_signals``: ``offsetof`` in the linked program, printed by
``wc_tcu --xcp-layout``) and the A2L's MEASUREMENTs (``wetclutch a2l``). Each signal lives in one of the
slave's read-only regions (src/can/wc_xcp.h): ``loop`` (the ``wc_loop_t``) or ``xcp`` (the slave's own
``wc_xcp_status_t``). Units are the ones the C field names carry; the limits are the physical range a tool
shows (the DBC's range where the signal is also on CAN)."""
from __future__ import annotations

from dataclasses import dataclass

# A2L data type and byte size of each C type a signal may have.
TYPES = {"f32": ("FLOAT32_IEEE", 4), "u32": ("ULONG", 4)}
REGIONS = {"loop": "wc_loop_t", "xcp": "wc_xcp_status_t"}


@dataclass(frozen=True)
class Signal:
    name: str          # A2L identifier
    region: str        # key of REGIONS
    member: str        # C member path inside the region's struct
    ctype: str         # key of TYPES
    unit: str
    lower: float
    upper: float
    description: str

    @property
    def size(self) -> int:
        return TYPES[self.ctype][1]


_S = Signal
SIGNALS: tuple[Signal, ...] = (
    # the clutch step's inputs as the loop used them (held values while a frame is missing)
    _S("slip_rad_s", "loop", "input.slip_rad_s", "f32", "rad/s", -838.0, 838.0,
       "Clutch slip speed of the step (ClutchSensors.SlipSpeed, +-8000 rpm)"),
    _S("theta_oil_degC", "loop", "input.theta_oil_degC", "f32", "degC", -40.0, 200.0, "Oil temperature of the step"),
    _S("torque_request_Nm", "loop", "input.torque_request_Nm", "f32", "Nm", 0.0, 5000.0,
       "Clutch torque request of the step (in Shift mode the shift controller's)"),
    # the clutch step's outputs
    _S("current_mA", "loop", "last.current_mA", "f32", "mA", 0.0, 10000.0, "VFS current command (VfsCommand)"),
    _S("pressure_command_Pa", "loop", "last.pressure_command_Pa", "f32", "Pa", 0.0, 2.0e7,
       "Pressure the led current drives the VFS towards"),
    _S("pressure_model_Pa", "loop", "last.pressure_model_Pa", "f32", "Pa", 0.0, 2.0e7,
       "Pressure of the VFS lag model (eq. DESIGN 9)"),
    _S("force_command_N", "loop", "last.force_command_N", "f32", "N", 0.0, 1.0e5, "Contact force the inverse asked for"),
    _S("contact_force_N", "loop", "last.contact_force_N", "f32", "N", 0.0, 1.0e5, "Contact force of the torque model"),
    _S("theta_degC", "loop", "clutch.theta_degC", "f32", "degC", -40.0, 250.0,
       "Friction-surface temperature, thermal observer state (eq. 1)"),
    _S("model_torque_Nm", "loop", "last.model.torque_Nm", "f32", "Nm", -5000.0, 5000.0,
       "Clutch torque of the model (eq. 5/8; while locked the held torque)"),
    _S("mu_f", "loop", "last.model.mu_f", "f32", "1", 0.0, 1.0, "Coulomb friction coefficient (eq. 18)"),
    _S("hbar_m", "loop", "last.model.hbar_m", "f32", "m", 0.0, 1.0e-3, "Average film thickness (eq. 9)"),
    _S("film_hbar_m", "loop", "clutch.film_hbar_m", "f32", "m", 0.0, 1.0e-3, "Squeeze-film state (DESIGN 9)"),
    _S("static_capacity_Nm", "loop", "last.static_capacity_Nm", "f32", "Nm", 0.0, 1.0e4,
       "Static capacity at the contact force (DESIGN 9)"),
    _S("step_status", "loop", "last.status", "u32", "1", 0.0, 4294967295.0, "Clutch step status bits (wc_status.h)"),
    # the shift controller
    _S("shift_phase", "loop", "shift.phase", "u32", "1", 0.0, 6.0, "Shift phase (wc_shift_phase_t)"),
    _S("shift_request_Nm", "loop", "shift.request_Nm", "f32", "Nm", 0.0, 5000.0, "Shift controller's torque request"),
    _S("shift_integral_Nm", "loop", "shift.integral_Nm", "f32", "Nm", -5000.0, 5000.0, "PI integral term"),
    # the loop's counters
    _S("loop_steps", "loop", "counters.steps", "u32", "1", 0.0, 4294967295.0, "Control steps since start"),
    _S("loop_safe_steps", "loop", "counters.safe_steps", "u32", "1", 0.0, 4294967295.0, "Steps in the safe state"),
    _S("loop_deadline_misses", "loop", "counters.deadline_misses", "u32", "1", 0.0, 4294967295.0,
       "Step deadlines the port missed"),
    _S("loop_frames_used", "loop", "counters.frames_used", "u32", "1", 0.0, 4294967295.0,
       "Received frames that passed every check"),
    # the XCP slave's own status (wc_xcp_status_t)
    _S("xcp_page_result", "xcp", "page_result", "u32", "1", 0.0, 255.0,
       "Last calibration page check: 0 accepted, else wc_cal_image_result_t or 10 (not an online change)"),
    _S("xcp_page_error", "xcp", "page_error", "u32", "1", 0.0, 255.0, "Its failing field's code"),
    _S("xcp_pages_accepted", "xcp", "pages_accepted", "u32", "1", 0.0, 4294967295.0, "Pages given to the loop"),
    _S("xcp_pages_rejected", "xcp", "pages_rejected", "u32", "1", 0.0, 4294967295.0, "Pages refused"),
    _S("xcp_ecu_page", "xcp", "ecu_page", "u32", "1", 0.0, 1.0, "Page the controller uses: 0 working, 1 reference"),
    _S("xcp_daq_overloads", "xcp", "daq_overloads", "u32", "1", 0.0, 4294967295.0,
       "DAQ list samples skipped: the step's frame budget was spent"),
    _S("xcp_errors", "xcp", "errors", "u32", "1", 0.0, 4294967295.0, "XCP error packets sent"),
    _S("xcp_ignored", "xcp", "ignored", "u32", "1", 0.0, 4294967295.0, "XCP frames ignored (malformed, not connected)"),
    _S("xcp_timestamp", "xcp", "timestamp", "u32", "1", 0.0, 4294967295.0, "Control steps since the slave's init"),
)


def by_name() -> dict[str, Signal]:
    return {s.name: s for s in SIGNALS}
