"""The calibration image's payload layout (include/wetclutch_can/wc_cal_image.h): the single source.

One ordered table, ``FIELDS``, of everything a calibration image carries: the clutch calibration
(``wc_calibration_t``, its film table as a length and three arrays of ``FILM_NODES`` nodes), the shift
calibration (``wc_shift_calibration_t``) and the frame loop's settings (``wc_loop_config_t``: shift control
on or off, timeouts, E2E, recovery; no pointers, hooks or bench flag). Each field is 4 bytes a value,
little-endian, in this order, without gaps: its ``offset`` follows from the order.

What reads this table:
  - ``generate/cal_image_layout.py`` writes the C codec from it (src/can/generated/wc_cal_image_layout.c,
    ``python -m wetclutch.generate.cal_image_layout``), the loop's limits included;
  - ``calibration/cal_image.py``, the Python codec (``wetclutch cal-image``);
  - the A2L generator: one CHARACTERISTIC a field (``name``, ``offset`` in the calibration page, ``ctype``,
    ``count``, ``unit``, ``lower``/``upper``, ``description``).

The limits restate the firmware's checks, taken from their one home: the clutch's from
calibration/parameters.py (``RANGES``, ``LIMITS``: wc_calibration_check), the shift's from the constants of
calibration/shift.py (wc_shift_calibration_check; tests/python/test_cal_image.py checks each bound against
shift.py's rule), the loop's are defined here (``LOOP_LIMITS``, generated into the C check). ``lower`` and
``upper`` are closed bounds as an A2L wants them: where the firmware's bound is open (``> 0``) or a relation
with another field (``inner_radius_m < outer_radius_m``), ``lower``/``upper`` are the widest physical range
and ``note`` says what the firmware checks besides. A limit that does not exist (mu3: any finite value) is
+-FLT_MAX.
"""
from __future__ import annotations

from dataclasses import dataclass

from . import shift as shift_rules
from .parameters import FORCE_MAX_N, LIMITS, PARAMETERS, RANGES, THETA_MAX_DEGC, THETA_MIN_DEGC

MAGIC = 0x49434357          # WC_CAL_IMAGE_MAGIC, the bytes "WCCI"
VERSION = 1                 # WC_CAL_IMAGE_VERSION
FILM_NODES = 64             # WC_CAL_IMAGE_FILM_NODES: the film table's capacity in the image
ADAPT_NODES = shift_rules.ADAPT_NODES   # WC_ADAPT_NODES
PAYLOAD_MAX_BYTES = 2048    # WC_CAL_IMAGE_PAYLOAD_MAX_BYTES
FLT_MAX = 3.4028234663852886e38
WORD_BYTES = 4


@dataclass(frozen=True)
class Field:
    """One value (count 1) or array (count > 1) of the payload.

    name         A2L-friendly identifier, dotted by group: clutch.*, clutch.film.*, shift.*, loop.*
    member       the C member path in wc_cal_set_t (``clutch.outer_radius_m``, ``film_hbar_m``,
                 ``loop.e2e.sync_counter``)
    ctype        wire type: "f32" (IEEE-754 single) or "u32"
    count        elements (1, FILM_NODES or ADAPT_NODES)
    unit         the unit the name carries ("m", "Pa/mA", "1")
    lower, upper closed limits of each element (see the module's text)
    description  one line
    offset       byte offset in the payload (set by the table's order)
    c_type       the C member's type where it is not the wire type's (bool, uint8_t); else ""
    note         what the firmware checks besides [lower, upper]: an open bound, a relation; else ""
    """
    name: str
    member: str
    ctype: str
    count: int
    unit: str
    lower: float
    upper: float
    description: str
    offset: int = 0
    c_type: str = ""
    note: str = ""

    @property
    def bytes(self) -> int:
        return WORD_BYTES * self.count

    @property
    def group(self) -> str:
        """clutch, shift or loop."""
        return self.name.split(".", 1)[0]


# ---------------------------------------------------------------------------------------------- clutch
# wc_calibration_t in its declaration order (wc_calibration.c asserts that each field sits at its word):
# (C field, description). Unit and limits from parameters.py; heat_capacity_J_per_K is derived there.
_CLUTCH = (
    ("outer_radius_m", "R_o, outer friction radius"),
    ("inner_radius_m", "R_i, inner friction radius"),
    ("friction_area_m2", "A_f, nominal lining contact area"),
    ("piston_area_m2", "A_p, apply piston area"),
    ("friction_pairs", "N_c, friction pairs"),
    ("oil_conductance_W_per_K", "k1, pack-to-oil conductance (eq. 1)"),
    ("housing_conductance_W_per_K", "k2, pack-to-housing conductance (eq. 1)"),
    ("heat_capacity_J_per_K", "C, heat capacity of the pack (eq. 1)"),
    ("viscosity_a1_Pa_s", "mu_v1, first viscosity coefficient (eq. 2)"),
    ("viscosity_b1_per_K", "mu_v2, first viscosity exponent (eq. 2)"),
    ("viscosity_a2_Pa_s", "mu_v3, second viscosity coefficient (eq. 2)"),
    ("viscosity_b2_per_K", "mu_v4, second viscosity exponent (eq. 2)"),
    ("mu1", "mu_f at high speed and theta_1 (eq. 18)"),
    ("mu2", "mu_f at zero speed and theta_1 (eq. 18)"),
    ("mu3", "temperature coefficient of mu_f (eq. 18)"),
    ("stribeck_speed_m_s", "v_s, Stribeck speed (eq. 18)"),
    ("theta1_degC", "theta_1, temperature normalisation offset (eq. 18)"),
    ("theta2_K", "theta_2, temperature normalisation span (eq. 18)"),
    ("vfs_gain_Pa_per_mA", "K, steady pressure per solenoid current"),
    ("vfs_time_constant_s", "tau, VFS/pressure lag time constant"),
    ("return_spring_force_N", "F_s, return spring force"),
    ("vfs_current_min_mA", "solenoid current minimum (the safe state's current)"),
    ("vfs_current_max_mA", "solenoid current maximum"),
    ("control_period_s", "dt of one control step"),
    ("film_squeeze_factor", "phi of the squeeze film; 0: film state off (DESIGN 9)"),
    ("static_friction_factor", "static capacity / kinetic capacity at zero speed"),
    ("lock_slip_rad_s", "|slip| below it for lock_dwell_periods: locked"),
    ("breakaway_slip_rad_s", "|slip| above it while locked: breakaway"),
    ("holding_margin", "a locked clutch is held at (1 + margin) times the request's force"),
    ("lock_dwell_periods", "control periods inside the lock band before locking"),
    ("open_clearance_m", "open element: retracted stroke per gap added to h_bar; 0: off (DESIGN 15)"),
    ("open_aeration_speed_rad_s", "open element: drag / (1 + (slip / this)^2); 0: off (DESIGN 15)"),
)
_TOML_NAME = {c_field: (name, unit, constraint) for _, name, unit, constraint, c_field in PARAMETERS if c_field}
# Upper bounds the firmware sets by a relation only: the widest physical value.
_RELATION = {
    "inner_radius_m": (LIMITS["RADIUS_MAX_m"], "> 0 and < outer_radius_m"),
    "friction_area_m2": (LIMITS["PI"] * LIMITS["RADIUS_MAX_m"] ** 2, "> 0 and <= pi outer_radius_m^2"),
    "mu3": (FLT_MAX, "finite; with theta1, theta2: 1 + mu3 (theta - theta1) / theta2 > 0 and mu_f <= 1 on"
                     f" [{THETA_MIN_DEGC:g}, {THETA_MAX_DEGC:g}] degC"),
    "theta2_K": (FLT_MAX, ">= 1; with mu3 as mu3's note"),
}
_NOTES = {
    "housing_conductance_W_per_K": "oil + housing conductance >= 1e-3 W/K",
    "heat_capacity_J_per_K": "C / (k1 + k2) in [control_period_s, 1e5] s",
    "viscosity_a1_Pa_s": "mu_v in (0, 100] Pa s on the temperature domain",
    "viscosity_a2_Pa_s": "mu_v in (0, 100] Pa s on the temperature domain",
    "vfs_current_max_mA": f"> vfs_current_min_mA; K i_max A_p in (F_s, {FORCE_MAX_N:g}] N",
    "film_squeeze_factor": f"0 or >= {LIMITS['FILM_SQUEEZE_FACTOR_MIN']:g}",
    "breakaway_slip_rad_s": "> lock_slip_rad_s",
    "open_aeration_speed_rad_s": f"0 or >= {LIMITS['OPEN_AERATION_SPEED_MIN_rad_s']:g}",
}


def _clutch_fields() -> list[Field]:
    out = []
    for c_field, description in _CLUTCH:
        if c_field == "heat_capacity_J_per_K":
            unit, low, low_in, high = "J/K", 0.0, False, LIMITS["HEAT_CAPACITY_MAX_J_per_K"]
            constraint = "pos"
        else:
            name, unit, constraint = _TOML_NAME[c_field]
            low, low_in, high = RANGES[name]
        high, relation = _RELATION.get(c_field, (high, ""))
        note = relation or _NOTES.get(c_field, "")
        if not low_in and not relation:
            note = f"> {low:g}" + (f"; {note}" if note else "")
        low = -FLT_MAX if low == float("-inf") else low
        if constraint == "count":
            out.append(Field(f"clutch.{c_field}", f"clutch.{c_field}", "u32", 1, unit, int(low), int(high),
                             description, note=note))
        else:
            out.append(Field(f"clutch.{c_field}", f"clutch.{c_field}", "f32", 1, unit, low, high, description,
                             note=note))
    return out


_FILM = (
    Field("clutch.film.length", "clutch.film.length", "u32", 1, "1", 2, FILM_NODES,
          "film table nodes in use (the rest of the arrays 0)"),
    Field("clutch.film.pressure_Pa", "film_pressure_Pa", "f32", FILM_NODES, "Pa", 0.0, FLT_MAX,
          "film table: contact pressure p_c at each node",
          note="strictly increasing over the nodes in use, the last >= the contact pressure at"
               " vfs_current_max_mA; unused nodes 0"),
    Field("clutch.film.hbar_m", "film_hbar_m", "f32", FILM_NODES, "m", 0.0, LIMITS["FILM_HBAR_MAX_m"],
          "film table: average film thickness h_bar at each node",
          note=f">= {LIMITS['FILM_HBAR_MIN_m']:g} m and strictly decreasing over the nodes in use; unused nodes 0"),
    Field("clutch.film.slope_m_per_Pa", "film_slope_m_per_Pa", "f32", FILM_NODES, "m/Pa", -FLT_MAX, 0.0,
          "film table: d h_bar / d p_c at each node",
          note="Fritsch-Carlson: the cubic Hermite monotone on every interval; unused nodes 0"),
)

# ---------------------------------------------------------------------------------------------- shift
# wc_shift_calibration_t in its declaration order, as calibration/shift.py lists it (FIELDS), the
# adaptation's temperature nodes as one array. (lower, upper, note, description) per C field.
_T = shift_rules.TIME_MAX_S
_SHIFT = {
    "turbine_inertia_kg_m2": (1e-4, 100.0, "", "I_t: turbine + engine inertia (converter locked)"),
    "turbine_ratio": (0.05, 20.0, "", "a in slip = a w_t - b w_o"),
    "output_inertia_kg_m2": (1e-4, 1e5, "", "I_o plus the vehicle referred to the output shaft"),
    "output_ratio": (0.05, 20.0, "", "b in slip = a w_t - b w_o (the target gear's ratio)"),
    "jerk_per_torque_rate": (0.0, 1.0, "", "vehicle jerk per on-coming clutch torque rate"),
    "prepare_time_s": (0.0, _T, "", "prepare (fill) phase time"),
    "torque_phase_time_s": (0.0, _T, "", "torque phase time"),
    "inertia_time_min_s": (shift_rules.INERTIA_TIME_MIN_S, shift_rules.INERTIA_TIME_MAX_S, "",
                           "shortest accepted commanded inertia phase time"),
    "inertia_time_max_s": (shift_rules.INERTIA_TIME_MIN_S, shift_rules.INERTIA_TIME_MAX_S,
                           ">= inertia_time_min_s", "longest accepted commanded inertia phase time"),
    "inertia_timeout_factor": (1.05, 10.0, "", "abort when the inertia phase exceeds target times this"),
    "lockup_ramp_time_s": (0.0, _T, "", "hand-over ramp to the holding torque"),
    "holding_torque_factor": (1.0, 5.0, "", "holding request / (T_t / a)"),
    "min_start_slip_rad_s": (0.0, shift_rules.SLIP_MAX_RAD_S, "", "slip at the inertia phase's start must exceed it"),
    "feedforward_gain": (0.0, 2.0, "", "1: the driveline feed-forward; 0: feedback only"),
    "kp_Nm_per_rad_s": (0.0, shift_rules.GAIN_MAX, "", "PI proportional gain on the slip error"),
    "ki_Nm_per_rad": (0.0, shift_rules.GAIN_MAX, "", "PI integral gain on the slip error"),
    "integral_limit_Nm": (0.0, shift_rules.TORQUE_MAX_NM, "", "|integral term| bound (anti-windup)"),
    "lag_compensation_time_s": (0.0, _T, "0 (off) or >= 0.001", "lag compensation time; 0: off"),
    "theta_source": (0, 1, "", "friction temperature: 0 observer, 1 oil"),
    "flare_slip_rad_s": (0.0, shift_rules.SLIP_MAX_RAD_S, "", "slip above the start slip + this: flare"),
    "tie_up_factor": (1.0, 10.0, "", "request above factor * T_t / a while the slip holds: tie-up"),
    "jerk_filter_time_s": (0.0, _T, "0 (off) or >= 0.001", "filter on the torque before its rate is taken"),
    "adaptation": (0, 1, "", "1: learn and use the learned values (DESIGN 12)"),
    "adapt_theta_node_degC": (THETA_MIN_DEGC, THETA_MAX_DEGC, "strictly increasing",
                              "the friction scale's temperature nodes"),
    "adapt_scale_band": (0.0, shift_rules.CORRECTION_SCALE_MAX, "> 0", "|friction scale - 1| <= band"),
    "adapt_scale_step": (0.0, shift_rules.CORRECTION_SCALE_MAX, "", "|change of a node's scale| per shift"),
    "adapt_scale_gain": (0.0, 1.0, "", "fraction of the measured scale error taken per shift"),
    "adapt_confidence_gain": (0.0, 1.0, "", "confidence gain per update"),
    "adapt_film_factor_min": (0.01, 1.0, "", "the film factor's band: lower end"),
    "adapt_film_factor_max": (1.0, 20.0, "", "the film factor's band: upper end"),
    "adapt_film_step": (0.0, 1.0, "", "|relative change of the film factor| per shift"),
    "adapt_film_gain": (0.0, 1.0, "", "fraction of the film factor error taken per shift"),
    "adapt_kiss_band_Pa": (0.0, shift_rules.KISS_BAND_MAX_PA, "", "|kiss point offset| <= band"),
    "adapt_kiss_step_Pa": (0.0, shift_rules.KISS_BAND_MAX_PA, "", "|change of the kiss offset| per shift"),
    "adapt_kiss_gain": (0.0, 1.0, "", "fraction of the kiss point error taken per shift"),
    "adapt_window_skip_s": (0.0, _T, "", "the learning window starts this long after the inertia phase's start"),
    "adapt_film_window_s": (0.0, _T, "", "the film factor's early part of the window"),
    "adapt_min_slip_drop": (0.0, 1.0, "", "excitation: the slip falls by this fraction of its window start"),
    "adapt_min_conditioning": (0.0, 1.0, "", "the kiss point's least squares: D / (S11 S22) at least this"),
    "coordinator": (0, 1, "", "1: the whole shift (off-going clutch, fill, engine; DESIGN 14)"),
    "offgoing_ratio": (0.0, 20.0, "0 or >= 0.05; with the coordinator at least 1 % away from output_ratio (an upshift above, a downshift below)", "b1 = i1: the off-going clutch's ratio"),
    "fill_pulse_current_mA": (0.0, shift_rules.CURRENT_MAX_MA, "", "fill pulse current"),
    "fill_pulse_time_s": (0.0, _T, "<= prepare_time_s", "fill pulse time"),
    "offgoing_holding_factor": (0.0, 5.0, "", "off-going capacity request before the torque phase / T_t"),
    "offgoing_margin_factor": (0.0, 1.0, "", "torque phase: off-going request = carried + factor * T_t0"),
    "offgoing_lag_compensation_time_s": (0.0, _T, "0 (off) or >= 0.001", "the off-going clutch's lag compensation time"),
    "flare_kp_Nm_per_rad_s": (0.0, shift_rules.GAIN_MAX, "", "flare correction: proportional gain on the off-going slip"),
    "flare_ki_Nm_per_rad": (0.0, shift_rules.GAIN_MAX, "", "flare correction: integral gain"),
    "handover_slip_rad_s": (0.0, shift_rules.SLIP_MAX_RAD_S, "", "off-going slip below -this: released (tie-up)"),
    "engine_intervention": (0, 1, "", "1: request engine torque (EngineTorqueRequest)"),
    "engine_increase_max_Nm": (0.0, shift_rules.ENGINE_DELTA_MAX_NM, "", "torque phase: engine increase limit"),
    "engine_reduction_max_Nm": (0.0, shift_rules.ENGINE_DELTA_MAX_NM, "", "inertia phase: engine reduction limit"),
    "engine_fill_fraction": (0.0, 1.0, "", "torque phase: fraction of the torque hole filled by the engine"),
    "engine_reduction_fraction": (0.0, 2.0, "", "inertia phase: reduction / the turbine's inertia torque I_t |dref/dt| / a"),
    "engine_recovery_time_s": (0.0, _T, "", "the reduction ramps out in this time after the inertia phase"),
    "engine_lead_time_s": (0.0, 1.0, "", "the engine request runs this far ahead of the reference (engine lag and delay)"),
    "fallback_time_s": (0.0, _T, "", "lost input in the inertia phase or later: finish on the model this long at most"),
}


def _shift_fields() -> list[Field]:
    out, seen = [], set()
    for _, unit, c_field, _ in shift_rules.FIELDS:
        base = c_field.split("[", 1)[0]
        if base in seen:
            continue
        seen.add(base)
        lower, upper, note, description = _SHIFT[base]
        count = ADAPT_NODES if "[" in c_field else 1
        ctype = "u32" if c_field in shift_rules.INTEGER_FIELDS else "f32"
        out.append(Field(f"shift.{base}", f"shift.{base}", ctype, count, unit, lower, upper, description,
                         note=note))
    return out


# ---------------------------------------------------------------------------------------------- loop
# The frame loop's settings (wc_loop_config_t; wc_loop.h). Their limits are this table's own: the C
# decode checks them (the generated wc_cal_image_loop_limits), in this order, which is the order of
# wc_cal_loop_error_t's codes (1 = the first). Reasons:
#   shift_enabled      0 or 1 (shift control off/on: the loop's config.shift = &set->shift)
#   timeouts           >= 1 period (0 would keep the input stale for ever: no control at all);
#                      <= 1000 periods, 1 s at the 1 ms period: a clutch input older than that is
#                      not an input (wc_tcu's command line takes up to 1e6 for the loop's tests; an
#                      image is what a vehicle runs)
#   max_delta_counter  AUTOSAR E2E Profile 1 MaxDeltaCounter, 1 (no loss) .. 7: the alive counter
#                      has 4 bits, so a jump of 8 or more is as much a counter gone back (16 - delta
#                      <= 8) as frames lost; small, so a sender that jumps is a wrong sequence
#   sync_counter       SyncCounter, 1 .. 15: in-sequence frames after a timeout or a wrong sequence
#                      before the input is used again (0 acts as 1); more than one turn of the
#                      counter only delays the recovery
#   recovery_periods   >= 1: leaving the safe state is debounced (DESIGN 8); <= 10000 (10 s at 1 ms)
LOOP_LIMITS = {
    "shift_enabled": (0, 1),
    "sensor_timeout_periods": (1, 1000),
    "request_timeout_periods": (1, 1000),
    "e2e.max_delta_counter": (1, 7),
    "e2e.sync_counter": (1, 15),
    "recovery_periods": (1, 10000),
}
LOOP_DEFAULTS = {"shift_enabled": 0, "sensor_timeout_periods": 10, "request_timeout_periods": 10,
                 "e2e.max_delta_counter": 2, "e2e.sync_counter": 3, "recovery_periods": 20}  # WC_LOOP_CONFIG_DEFAULT
_LOOP = (
    ("shift_enabled", "shift_enabled", "bool", "shift control on (1) or off (0); off: the shift fields 0"),
    ("sensor_timeout_periods", "loop.sensor_timeout_periods", "", "ClutchSensors freshness limit"),
    ("request_timeout_periods", "loop.request_timeout_periods", "", "TorqueRequest (and ShiftCommand) freshness limit"),
    ("e2e.max_delta_counter", "loop.e2e.max_delta_counter", "uint8_t", "E2E MaxDeltaCounter: largest accepted counter step"),
    ("e2e.sync_counter", "loop.e2e.sync_counter", "uint8_t", "E2E SyncCounter: in-sequence frames after a timeout"),
    ("recovery_periods", "loop.recovery_periods", "", "both inputs fresh this long before the safe state ends"),
)


def _loop_fields() -> list[Field]:
    units = {"shift_enabled": "1", "e2e.max_delta_counter": "1", "e2e.sync_counter": "1"}
    return [Field(f"loop.{name}", member, "u32", 1, units.get(name, "periods"), *LOOP_LIMITS[name], description,
                  c_type=c_type) for name, member, c_type, description in _LOOP]


def _with_offsets(fields: list[Field]) -> tuple[Field, ...]:
    out, offset = [], 0
    for f in fields:
        out.append(Field(**{**f.__dict__, "offset": offset}))
        offset += f.bytes
    return tuple(out)


FIELDS: tuple[Field, ...] = _with_offsets([*_clutch_fields(), *_FILM, *_shift_fields(), *_loop_fields()])
BY_NAME: dict[str, Field] = {f.name: f for f in FIELDS}


def payload_bytes() -> int:
    """The payload's length in bytes (wc_cal_image_payload_bytes)."""
    return FIELDS[-1].offset + FIELDS[-1].bytes


def group_span(group: str) -> tuple[int, int]:
    """[start, end) byte offsets of a group's fields (clutch, shift, loop): each group is contiguous."""
    fields = [f for f in FIELDS if f.group == group]
    return fields[0].offset, fields[-1].offset + fields[-1].bytes


assert payload_bytes() <= PAYLOAD_MAX_BYTES
assert len(BY_NAME) == len(FIELDS)
