"""The shift controller (src/model/wc_shift.c, DESIGN 10) in double precision: the independent reference the
firmware's closed-loop frames are checked against (tests/python/test_shift.py).

ShiftReference.step takes what the frame loop hands wc_shift_step (the decoded ShiftCommand, the loop's safe
state, the sensor values) and steps its own ClutchReference (reference/model), as the firmware steps its clutch.
With the shift calibration's adaptation on, its AdaptationReference (reference/adaptation.py) corrects the
clutch model before each step of a running or locked shift, samples the inertia phase and learns at the
shift's end; the learned values carry over to the reference's next shift (ShiftReference.adapt).
"""
from __future__ import annotations

import math

from . import model
from .adaptation import AdaptationReference, AdaptSettings, AdaptValues, f32

IDLE, PREPARE, TORQUE, INERTIA, LOCKUP, LOCKED, ABORTED = range(7)
RUNNING = (PREPARE, TORQUE, INERTIA, LOCKUP)
ABORT_NONE, ABORT_INERTIA_TIMEOUT, ABORT_LOCKUP_FAILED, ABORT_INPUT_LOST, ABORT_CANCELLED, \
    ABORT_INVALID_COMMAND, ABORT_NO_SLIP = range(7)
LOCKUP_WAIT = 4                  # WC_SHIFT_LOCKUP_WAIT
THETA_SOURCE_OIL = 1


def reference_slip(start_rad_s: float, target_s: float, elapsed_s: float) -> tuple[float, float]:
    """(reference, its rate): start (1 - (3x^2 - 2x^3)), x = elapsed / target in [0, 1] (wc_shift_reference_slip)."""
    x = elapsed_s / target_s if target_s > 0.0 else 1.0
    x = min(max(x, 0.0), 1.0) if x == x else 0.0
    rate = -6.0 * start_rad_s * x * (1.0 - x) / target_s if target_s > 0.0 else 0.0
    return start_rad_s * (1.0 - x * x * (3.0 - 2.0 * x)), rate


def feedforward_Nm(v: dict, turbine_torque_Nm: float, rate_rad_s2: float) -> float:
    """DESIGN 10, stiff driveshaft: T_ff = (a T_t / I_t - dref/dt) / (a^2 / I_t + b^2 / I_out), in [0, T_max]."""
    a, b, i_t = v["turbine_ratio"], v["output_ratio"], v["turbine_inertia"]
    t_ff = (a * turbine_torque_Nm / i_t - rate_rad_s2) / (a * a / i_t + b * b / v["output_inertia"])
    return min(max(t_ff, 0.0), model.TORQUE_MAX_NM)


class ShiftReference:
    def __init__(self, shift_cal, clutch_cal, theta_start_degC: float, adapt_values: AdaptValues | None = None):
        self.v = shift_cal.values
        self.cal = clutch_cal
        self.dt = clutch_cal.period
        self.clutch = model.ClutchReference(clutch_cal, theta_start_degC)
        # the learned values (the calibration's, or adapt_values: an image read at init)
        self.adapt = AdaptationReference(AdaptSettings.from_values(self.v), self.dt, clutch_cal.piston_area,
                                         clutch_cal.film_squeeze_factor > 0.0, adapt_values)
        self.last_request = False
        self.last_status = 0
        self._reset()
        self.phase = IDLE

    def _reset(self):
        self.phase, self.periods = IDLE, 0
        self.turbine_torque = self.target_s = self.start_slip = 0.0
        self.integral = self.request = self.phase_start_request = self.filtered = self.err_sq = 0.0
        self.inertia_periods = self.band_periods = 0
        self.report = {"inertia_time_s": 0.0, "slip_rmse_rad_s": 0.0, "peak_jerk_m_s3": 0.0,
                       "friction_energy_J": 0.0, "peak_theta_degC": 0.0, "flare": False, "tie_up": False,
                       "abort_reason": ABORT_NONE, "adaptation": None}

    def _periods(self, time_s: float) -> int:
        return int(time_s / self.dt + 0.5)

    def _enter(self, phase: int):
        self.phase, self.periods = phase, 0

    def _abort(self, reason: int):
        self._enter(ABORTED)
        self.report["abort_reason"] = reason

    def _phase_request(self, slip: float, saturated: bool) -> float:
        v = self.v
        share = self.turbine_torque / v["turbine_ratio"]
        if self.phase == PREPARE:
            if self.periods < self._periods(v["prepare_time"]):
                return 0.0
            self._enter(TORQUE)
        if self.phase == TORQUE:
            n = self._periods(v["torque_phase_time"])
            if self.periods < n:
                return share * (self.periods + 1) / n
            self._enter(INERTIA)
            self.start_slip = slip
            self.integral = self.request - v["feedforward_gain"] * feedforward_Nm(v, self.turbine_torque, 0.0)
            if not slip > v["min_start_slip"]:
                self._abort(ABORT_NO_SLIP)
                return 0.0
        if self.phase == INERTIA:
            ref, rate = reference_slip(self.start_slip, self.target_s, self.periods * self.dt)
            ff = v["feedforward_gain"] * feedforward_Nm(v, self.turbine_torque, rate)
            error = slip - ref
            self.err_sq += error * error
            self.inertia_periods += 1
            if not ((saturated and error > 0.0) or (self.request <= 0.0 and error < 0.0)):
                limit = v["integral_limit"]
                self.integral = min(max(self.integral + v["ki"] * error * self.dt, -limit), limit)
            if slip > self.start_slip + v["flare_slip"]:
                self.report["flare"] = True
            if slip >= self.start_slip and self.request > v["tie_up_factor"] * share:
                self.report["tie_up"] = True
            return ff + v["kp"] * error + self.integral
        if self.phase == LOCKUP:
            n = self._periods(v["lockup_ramp_time"])
            hold = v["holding_torque_factor"] * share
            x = (self.periods + 1) / n if n > 0 else 1.0
            return self.phase_start_request + (hold - self.phase_start_request) * min(x, 1.0)
        return v["holding_torque_factor"] * share

    def step(self, request: bool, target_gear: int, turbine_torque_Nm: float, target_inertia_s: float, safe: bool,
             slip_rpm: float, oil_degC: float, housing_degC: float) -> tuple[dict, dict | None]:
        """One period (wc_shift_step); returns the clutch step's output and, when the shift ended, its report."""
        v = self.v
        phase_before = self.phase
        edge = request and not self.last_request
        self.last_request = request
        slip = slip_rpm * model.RAD_S_PER_RPM
        saturated = bool(self.last_status & model.STATUS_SATURATED)
        if safe or not request:
            if self.phase in RUNNING:
                self._abort(ABORT_INPUT_LOST if safe else ABORT_CANCELLED)
            elif not request or self.phase == LOCKED:
                self._enter(IDLE)
        elif edge and self.phase == IDLE:
            self._reset()
            self.last_request = True
            valid = (target_gear == 2 and v["inertia_time_min"] <= target_inertia_s <= v["inertia_time_max"]
                     and 0.0 <= turbine_torque_Nm <= model.TORQUE_MAX_NM)
            if valid:
                self.turbine_torque, self.target_s, self.start_slip = turbine_torque_Nm, target_inertia_s, slip
                self.report["peak_theta_degC"] = model.THETA_MIN_DEGC
                self.adapt.begin()
                self._enter(PREPARE)
            else:
                self._abort(ABORT_INVALID_COMMAND)
        if self.phase in RUNNING and 0.0 <= turbine_torque_Nm <= model.TORQUE_MAX_NM:
            self.turbine_torque = turbine_torque_Nm
        mode, req, carried, correction = model.MODE_OPEN, 0.0, 0.0, None
        theta_from_oil = v["theta_source"] == THETA_SOURCE_OIL
        if self.phase in RUNNING or self.phase == LOCKED:
            # DESIGN 12: the learned values at the temperature the model uses (before the phase's law: also
            # in a step whose law aborts the shift)
            correction = self.adapt.correction(oil_degC if theta_from_oil else self.clutch.theta)
            r = min(max(self._phase_request(slip, saturated), 0.0), model.TORQUE_MAX_NM)
            if self.phase != ABORTED:
                mode, req = model.MODE_TORQUE, r
                self.request = r
                carried = feedforward_Nm(v, self.turbine_torque, 0.0)
        out = self.clutch.step(slip_rpm, oil_degC, housing_degC, req, mode,
                               lag_compensation_time_s=v["lag_compensation_time"],
                               theta_from_oil=theta_from_oil, carried_torque_Nm=carried, correction=correction)
        self.last_status = out["status"]
        phase_stepped = self.phase
        locked = bool(out["status"] & model.STATUS_LOCKED)
        if self.phase == INERTIA:   # the adaptation's sample of this period (the phase's time before its count)
            a, i_t = v["turbine_ratio"], v["turbine_inertia"]
            self.adapt.sample(f32(f32(self.periods) * f32(self.dt)), slip, a * self.turbine_torque / i_t,
                              a * a / i_t + v["output_ratio"] ** 2 / v["output_inertia"], out)
        if self.phase == INERTIA:
            elapsed = (self.periods + 1) * self.dt
            self.band_periods = self.band_periods + 1 if abs(slip) < self.cal.lock_slip else 0
            synchronous = self.band_periods >= self.cal.lock_dwell
            ended = elapsed >= self.target_s and abs(slip) <= v["min_start_slip"]
            if locked or synchronous or ended:
                self.report["inertia_time_s"] = elapsed
                self.phase_start_request = self.request
                self._enter(LOCKUP)
            elif elapsed > self.target_s * v["inertia_timeout_factor"]:
                self.report["inertia_time_s"] = elapsed
                self._abort(ABORT_INERTIA_TIMEOUT)
        elif self.phase == LOCKUP:
            ramp = self._periods(v["lockup_ramp_time"])
            if locked and self.periods + 1 >= ramp:
                self._enter(LOCKED)
            elif self.periods + 1 >= LOCKUP_WAIT * ramp + 1:
                self._abort(ABORT_LOCKUP_FAILED)
        if phase_before in RUNNING or self.phase in RUNNING:
            q = self.report
            q["friction_energy_J"] += abs(out["torque_Nm"] * slip) * self.dt
            q["peak_theta_degC"] = max(q["peak_theta_degC"], self.clutch.theta)
            alpha = self.dt / (v["jerk_filter_time"] + self.dt)
            filtered = self.filtered + (out["torque_Nm"] - self.filtered) * alpha
            jerk = abs(v["jerk_per_torque_rate"] * (filtered - self.filtered) / self.dt)
            if phase_before in RUNNING and jerk > q["peak_jerk_m_s3"]:
                q["peak_jerk_m_s3"] = jerk
            self.filtered = filtered
        if self.phase == phase_stepped:
            self.periods += 1
        if phase_before != self.phase and self.phase in (LOCKED, ABORTED):
            self.report["slip_rmse_rad_s"] = (math.sqrt(self.err_sq / self.inertia_periods)
                                              if self.inertia_periods else 0.0)
            self.report["adaptation"] = self.adapt.finish(self.report["abort_reason"])
            return out, dict(self.report)
        return out, None
