"""The reference model's constants: unit conversion, the status bits shared with the firmware, the thermal
envelope, the firmware's input ranges, the clutch modes."""
from __future__ import annotations

import math


RAD_S_PER_RPM = 2.0 * math.pi / 60.0

# Status bits shared with the firmware (include/wetclutch/wc_status.h).
STATUS_BELOW_DRAG = 1 << 0        # request below the drag at zero force: force 0
STATUS_SATURATED = 1 << 1         # request above the capacity at maximum current
STATUS_CURRENT_CLAMPED = 1 << 2   # current clamped to the solenoid range
STATUS_SLIP_INVALID = 1 << 3      # slip speed NaN, infinite or out of range
STATUS_THETA_INVALID = 1 << 4     # a temperature NaN, infinite or out of range
STATUS_FORCE_INVALID = 1 << 5     # contact force NaN, infinite, negative or too large
STATUS_TORQUE_INVALID = 1 << 6    # torque request NaN, infinite, negative or too large
STATUS_POWER_INVALID = 1 << 7     # heat input NaN, infinite or negative
STATUS_OVER_TEMPERATURE = 1 << 8  # estimate above THETA_OVER_DEGC (hysteresis THETA_OVER_HYSTERESIS_K)
STATUS_NOT_INITIALISED = 1 << 9   # NULL or uninitialised instance (C only)
STATUS_LOCKED = 1 << 10           # clutch locked: static friction holds it (DESIGN 9); not an error
# Thermal envelope (include/wetclutch/wc_config.h, DESIGN section 8).
THETA_MIN_DEGC, THETA_MAX_DEGC = -40.0, 250.0
THETA_OVER_DEGC, THETA_OVER_HYSTERESIS_K = 200.0, 10.0
STATUS_INPUT_INVALID = (STATUS_SLIP_INVALID | STATUS_THETA_INVALID | STATUS_FORCE_INVALID | STATUS_TORQUE_INVALID
                        | STATUS_POWER_INVALID)

# The firmware's input ranges (include/wetclutch/wc_config.h; temperatures: THETA_MIN_DEGC, THETA_MAX_DEGC above),
# checked in float32 as the firmware does (reference/evaluate.py).
SLIP_MAX_RAD_S = 1047.2           # WC_SLIP_MAX_rad_s: 10000 rpm
FORCE_MAX_N = 1.0e5
TORQUE_MAX_NM = 1.0e5


# The clutch modes, numbered as the DBC's TorqueRequest.Mode and the C enum wc_clutch_mode_t.
MODE_OPEN, MODE_TORQUE, MODE_LOCKED = 0, 1, 2
