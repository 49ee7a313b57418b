"""The adaptation (src/model/wc_adapt.c, DESIGN 12) in double precision, written from the specification in
include/wetclutch/wc_adapt.h's header comment, not from the C: the independent reference the firmware's
golden vectors (generate/vectors.py) and closed-loop shifts (shift.ShiftReference) are checked against.

Per clutch, learned from what a vehicle TCU measures:
  - a friction scale at NODES surface temperatures (the observer's theta), interpolated, held beyond;
  - the squeeze-film factor, as a multiplier of the calibration's;
  - the kiss point, as a pressure offset from the calibration's.

The measurement (DESIGN 10, 12): in the inertia phase
    d(slip)/dt = a T_t / I_t - T_c (a^2 / I_t + b^2 / I_out)
 => T_imp,j = (drive_{j-1} - (slip_j - slip_{j-1}) / dt) / m,   drive = a T_t / I_t,  m = a^2/I_t + b^2/I_out,
paired with the model torque of period j-1. The update at the shift's end (finish): rho = sum T_imp /
sum T_model, each node's share q_i of sum w_i(theta) T_model, normalised by Q = sum q_j^2 so that the
interpolated scale at the window's temperatures moves by the gain times its error: each node's own step
a_i = clip(gain (q_i / Q) s_i (rho - 1), +-step (1 - c_i / 2)), the window's scale after them
L = sum q_j (s_j + a_j), and s_i += clip(c_i a_i + (1 - c_i) (L - s_i), +-step) in its band (a node not yet
learned takes the window's scale); the confidence c_i += gain_c q_i (1 - c_i) (c_i before the update); the kiss point from the least squares of
r = T_imp - T_model on the model's Coulomb torque x1 and its Coulomb torque per newton x2; the film factor
from the early window's ratio rho_e against rho.

Readings of the specification where its text leaves a choice (each a report item when the C differs):
  - the window's start: the first period at adapt_window_skip or later after the inertia phase's start,
    decided on the float32 phase time the firmware is given (phase periods times the float period: at an
    exact multiple of the period, double and float disagree by one sample otherwise);
  - "while the slip stays above min_start_slip": the window closes at the first sample at or below it (no
    pairing of two slips across a gap);
  - its early part: the samples whose period starts inside the first adapt_film_window, (j - 1) dt < W in
    exact arithmetic on the float32 dt and W;
  - an invalid input: a status bit of an invalid slip, temperature or torque request (the bench's force and
    power bits cannot occur in a shift), or a non-finite sample value ("NaN samples mark the window invalid");
  - x2, the Coulomb torque per newton of contact force: R_eff N_c mu_f (1 + scale delta) of the step.
Every other quantity is double.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .model.constants import STATUS_SLIP_INVALID, STATUS_THETA_INVALID, STATUS_TORQUE_INVALID
from .model.correction import KISS_MAX_N, Correction

NODES = 5                               # WC_ADAPT_NODES
RHO_MIN, RHO_MAX = 0.5, 2.0             # WC_ADAPT_RHO_MIN / _MAX: a plausible shift's torque ratio
RESULT_OFF, RESULT_UPDATED, RESULT_ABORTED, RESULT_INPUT_FAULT, RESULT_EXCITATION, RESULT_IMPLAUSIBLE = range(6)
RESULT_NAMES = {RESULT_OFF: "off", RESULT_UPDATED: "updated", RESULT_ABORTED: "aborted",
                RESULT_INPUT_FAULT: "input fault", RESULT_EXCITATION: "excitation", RESULT_IMPLAUSIBLE: "implausible"}
SHIFTS_LEARNED_MAX = 2**32 - 1
KISS_MIN_SCALE = 0.5                    # 1 + b1 >= 0.5, else no kiss update (wc_adapt.h)
INPUT_INVALID = STATUS_SLIP_INVALID | STATUS_THETA_INVALID | STATUS_TORQUE_INVALID   # a shift's invalid inputs


def f32(x: float) -> float:
    """x rounded to float32 (the firmware's representation of a calibration value or a time)."""
    return float(np.float32(x))


@dataclass(frozen=True)
class AdaptSettings:
    """The adapt_* fields of a shift calibration (wc_shift_calibration_t), by their names in the TOML file
    (calibration/shift.py)."""
    on: bool
    theta_node_degC: tuple
    scale_band: float
    scale_step: float
    scale_gain: float
    confidence_gain: float
    film_factor_min: float
    film_factor_max: float
    film_step: float
    film_gain: float
    kiss_band_Pa: float
    kiss_step_Pa: float
    kiss_gain: float
    window_skip_s: float
    film_window_s: float
    min_slip_drop: float
    min_conditioning: float
    min_start_slip_rad_s: float

    @classmethod
    def from_values(cls, v: dict) -> "AdaptSettings":
        """From a shift calibration's values (ShiftCalibration.values); no `adaptation` key: off."""
        if not v.get("adaptation", 0):
            return cls(False, (0.0,) * NODES, *(0.0,) * 15, v.get("min_start_slip", 0.0))
        return cls(True, tuple(float(v[f"adapt_theta_node{i}"]) for i in range(NODES)),
                   *(float(v[f"adapt_{n}"]) for n in (
                       "scale_band", "scale_step", "scale_gain", "confidence_gain", "film_factor_min",
                       "film_factor_max", "film_step", "film_gain", "kiss_band", "kiss_step", "kiss_gain",
                       "window_skip", "film_window", "min_slip_drop", "min_conditioning")),
                   float(v["min_start_slip"]))


@dataclass
class AdaptValues:
    """What persists per clutch (wc_adapt_values_t); the defaults are the calibration's values."""
    friction_scale: list = field(default_factory=lambda: [1.0] * NODES)
    confidence: list = field(default_factory=lambda: [0.0] * NODES)
    film_factor: float = 1.0
    kiss_offset_Pa: float = 0.0
    shifts_learned: int = 0

    def copy(self) -> "AdaptValues":
        return replace(self, friction_scale=list(self.friction_scale), confidence=list(self.confidence))


def node_weights(nodes_degC, theta_degC: float) -> list:
    """The interpolation weights w_i(theta) of the nodes: linear between the two nodes around theta, all on
    the first (last) node below (above) them; they sum to 1."""
    w = [0.0] * NODES
    if not theta_degC > nodes_degC[0]:
        w[0] = 1.0
        return w
    if not theta_degC < nodes_degC[-1]:
        w[-1] = 1.0
        return w
    for i in range(NODES - 1):
        if theta_degC <= nodes_degC[i + 1]:
            t = (theta_degC - nodes_degC[i]) / (nodes_degC[i + 1] - nodes_degC[i])
            w[i], w[i + 1] = 1.0 - t, t
            return w
    raise AssertionError("unreachable: theta below the last node")


def interpolated_scale(values: AdaptValues, nodes_degC, theta_degC: float) -> float:
    return sum(w * s for w, s in zip(node_weights(nodes_degC, theta_degC), values.friction_scale))


def correction(values: AdaptValues | None, settings: AdaptSettings, piston_area_m2: float,
               theta_degC: float) -> Correction:
    """wc_adapt_correction: the interpolated scale at theta, the film factor, the kiss offset as a force
    (times the piston area, within the correction's range +-KISS_MAX_N: a band in Pa times a large piston
    would otherwise void the whole correction). Adaptation off or no values: none."""
    if values is None or not settings.on:
        return Correction()
    return Correction(interpolated_scale(values, settings.theta_node_degC, theta_degC) - 1.0,
                      values.film_factor - 1.0, _clip(values.kiss_offset_Pa * piston_area_m2, -KISS_MAX_N, KISS_MAX_N))


def _clip(x: float, lo: float, hi: float) -> float:
    return min(max(x, lo), hi)


@dataclass
class Window:
    """The running window of one shift's inertia phase (wc_adapt_window_t), sums in double."""
    started: bool = False
    closed: bool = False        # the slip fell to min_start_slip: no more samples
    fault: bool = False
    samples: int = 0
    slip_start: float = 0.0
    slip_prev: float = 0.0
    drive_prev: float = 0.0
    model_prev: float = 0.0
    coulomb_prev: float = 0.0
    coulomb_per_N_prev: float = 0.0
    theta_prev: float = 0.0
    sum_model: float = 0.0
    sum_implied: float = 0.0
    sum_model_early: float = 0.0
    sum_implied_early: float = 0.0
    weight: list = field(default_factory=lambda: [0.0] * NODES)
    s11: float = 0.0
    s12: float = 0.0
    s22: float = 0.0
    s1r: float = 0.0
    s2r: float = 0.0


class AdaptationReference:
    """One clutch's adaptation: begin at a shift's start, sample after each inertia-phase clutch step,
    finish at the shift's end (the update), correction before each clutch step. dt_s: the clutch's control
    period; piston_area_m2 and film_on (film_squeeze_factor > 0): the clutch calibration's."""

    def __init__(self, settings: AdaptSettings, dt_s: float, piston_area_m2: float, film_on: bool,
                 values: AdaptValues | None = None):
        self.settings = settings
        self.dt = dt_s
        self.dt32 = f32(dt_s)
        self.piston_area = piston_area_m2
        self.film_on = film_on
        self.values = values.copy() if values is not None else AdaptValues()
        self.window = Window()

    def correction(self, theta_degC: float) -> Correction:
        return correction(self.values, self.settings, self.piston_area, theta_degC)

    def begin(self):
        self.window = Window()

    def sample(self, elapsed_s: float, slip_rad_s: float, drive_rad_s2: float, inverse_inertia: float,
               out: dict) -> None:
        """One inertia-phase period after the clutch step. elapsed_s: the phase's time as the firmware has it
        (phase periods times the float period, a float32 value); out: the clutch step's output
        (torque_Nm, coulomb_Nm, coulomb_per_N, theta_degC, status)."""
        st = self.settings
        w = self.window
        if not st.on or not elapsed_s >= st.window_skip_s:
            return
        values = (slip_rad_s, drive_rad_s2, inverse_inertia, out["torque_Nm"], out["coulomb_Nm"],
                  out["coulomb_per_N"], out["theta_degC"])
        finite = all(math.isfinite(x) for x in values)
        if (int(out["status"]) & INPUT_INVALID) or not finite:
            w.fault = True          # the shift teaches nothing (its samples still go in: the report's node)
            if not finite:
                return
        if w.closed:
            return
        if not slip_rad_s > st.min_start_slip_rad_s:
            w.closed = w.started
            return
        if w.started:
            implied = (w.drive_prev - (slip_rad_s - w.slip_prev) / self.dt) / inverse_inertia
            model_t = w.model_prev
            w.samples += 1
            w.sum_model += model_t
            w.sum_implied += implied
            if (w.samples - 1) * self.dt32 < st.film_window_s:     # exact: a small integer times a float32
                w.sum_model_early += model_t
                w.sum_implied_early += implied
            for i, wi in enumerate(node_weights(st.theta_node_degC, w.theta_prev)):
                w.weight[i] += wi * model_t
            r = implied - model_t
            x1, x2 = w.coulomb_prev, w.coulomb_per_N_prev
            w.s11 += x1 * x1
            w.s12 += x1 * x2
            w.s22 += x2 * x2
            w.s1r += x1 * r
            w.s2r += x2 * r
        else:
            w.started = True
            w.slip_start = slip_rad_s
        w.slip_prev, w.drive_prev = slip_rad_s, drive_rad_s2
        w.model_prev, w.coulomb_prev, w.coulomb_per_N_prev = out["torque_Nm"], out["coulomb_Nm"], out["coulomb_per_N"]
        w.theta_prev = out["theta_degC"]

    def validity(self, abort_reason: int) -> int:
        """The result code of a finished shift before its update: RESULT_UPDATED when the shift is valid."""
        st, w = self.settings, self.window
        if not st.on:
            return RESULT_OFF
        if abort_reason != 0:
            return RESULT_ABORTED
        if w.fault:
            return RESULT_INPUT_FAULT
        if w.samples == 0 or not (w.slip_start - w.slip_prev >= st.min_slip_drop * w.slip_start):
            return RESULT_EXCITATION
        if not w.sum_model > 0.0:
            return RESULT_EXCITATION
        rho = w.sum_implied / w.sum_model
        if not RHO_MIN <= rho <= RHO_MAX:
            return RESULT_IMPLAUSIBLE
        return RESULT_UPDATED

    def finish(self, abort_reason: int) -> dict:
        """wc_adapt_finish: the update of a valid shift; returns what it changed (wc_adapt_change_t) and the
        measurement (rho, rho_e, the kiss point's estimate) for the tests."""
        st, w, v = self.settings, self.window, self.values
        before = v.copy()
        result = self.validity(abort_reason)
        info = {"rho": w.sum_implied / w.sum_model if w.sum_model > 0.0 else math.nan, "rho_early": math.nan,
                "kiss_dP_Pa": math.nan, "conditioning": math.nan}
        if result == RESULT_OFF:      # nothing learned, nothing shown: the defaults (wc_adapt_change_t)
            return {"result": result, "node": 0, "friction_scale": 1.0, "friction_scale_change": 0.0,
                    "confidence": 0.0, "film_factor": 1.0, "film_factor_change": 0.0, "kiss_offset_Pa": 0.0,
                    "kiss_offset_change_Pa": 0.0, **info}
        node = 0
        if result == RESULT_UPDATED:
            rho = w.sum_implied / w.sum_model
            total = sum(w.weight)
            share = [wi / total for wi in w.weight]
            node = max(range(NODES), key=lambda i: (share[i], -i))      # the first of equal shares
            q2 = sum(q * q for q in share)                              # in [1/NODES, 1]
            band = st.scale_band
            own = []                                                    # each node's own step
            for i in range(NODES):
                limit = st.scale_step * (1.0 - 0.5 * v.confidence[i])     # a confident node moves less per shift
                own.append(_clip(st.scale_gain * share[i] / q2 * v.friction_scale[i] * (rho - 1.0), -limit, limit))
            level = sum(q * (s + a) for q, s, a in zip(share, v.friction_scale, own))   # the window's scale after
            for i in range(NODES):
                c, s = v.confidence[i], v.friction_scale[i]
                step = _clip(c * own[i] + (1.0 - c) * (level - s), -st.scale_step, st.scale_step)
                v.friction_scale[i] = _clip(s + step, 1.0 - band, 1.0 + band)
                v.confidence[i] += st.confidence_gain * share[i] * (1.0 - c)
            # the kiss point: r = b1 x1 + b2 x2, b1 = s - 1, b2 = -s dF
            prod = w.s11 * w.s22
            det = prod - w.s12 * w.s12
            if prod > 0.0:
                info["conditioning"] = det / prod
            if prod > 0.0 and det / prod >= st.min_conditioning:
                b1 = (w.s22 * w.s1r - w.s12 * w.s2r) / det
                b2 = (w.s11 * w.s2r - w.s12 * w.s1r) / det
                if 1.0 + b1 >= KISS_MIN_SCALE:
                    dp = -b2 / (1.0 + b1) / self.piston_area
                    info["kiss_dP_Pa"] = dp
                    step = _clip(st.kiss_gain * dp, -st.kiss_step_Pa, st.kiss_step_Pa)
                    v.kiss_offset_Pa = _clip(v.kiss_offset_Pa + step, -st.kiss_band_Pa, st.kiss_band_Pa)
            if self.film_on and w.sum_model_early > 0.0 and w.sum_implied_early > 0.0:
                rho_e = w.sum_implied_early / w.sum_model_early
                info["rho_early"] = rho_e
                rel = _clip(st.film_gain * (rho / rho_e - 1.0), -st.film_step, st.film_step)
                v.film_factor = _clip(v.film_factor * (1.0 + rel), st.film_factor_min, st.film_factor_max)
            v.shifts_learned = min(v.shifts_learned + 1, SHIFTS_LEARNED_MAX)
        elif w.weight and sum(w.weight) > 0.0:
            node = max(range(NODES), key=lambda i: (w.weight[i], -i))
        return {"result": result, "node": node, "friction_scale": v.friction_scale[node],
                "friction_scale_change": v.friction_scale[node] - before.friction_scale[node],
                "confidence": v.confidence[node], "film_factor": v.film_factor,
                "film_factor_change": v.film_factor - before.film_factor, "kiss_offset_Pa": v.kiss_offset_Pa,
                "kiss_offset_change_Pa": v.kiss_offset_Pa - before.kiss_offset_Pa, **info}
