"""The clutch step (wc_clutch_step) in double precision: ClutchReference, one period per step, and
clutch_steps over arrays."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .correction import NONE, Correction, effective
from .constants import (MODE_LOCKED, MODE_TORQUE, RAD_S_PER_RPM, STATUS_CURRENT_CLAMPED, STATUS_LOCKED,
                        STATUS_OVER_TEMPERATURE, THETA_MAX_DEGC, THETA_MIN_DEGC, THETA_OVER_DEGC,
                        THETA_OVER_HYSTERESIS_K, TORQUE_MAX_NM)
from .film import hbar_from_pressure_m
from .friction import (band_fraction, band_pressure_Pa, force_max_N, retracted_fraction, static_capacity_Nm,
                       torque_parts)
from .inverse import holding_inverse, inverse, kiss_pressure_Pa
from .lockup import Lockup
from .squeeze_film import film_advance_m, film_contact_pressure_Pa, film_damping_N_s_m2
from .thermal import thermal_decay, thermal_steady_degC

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


CLUTCH_OUTPUTS = ("current_mA", "pressure_command_Pa", "pressure_model_Pa", "force_command_N", "theta_degC",
                  "torque_Nm", "mu_f", "hbar_m", "contact_force_N", "static_capacity_Nm", "status")
LEAD_TIME_MAX_S = 10.0   # WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s: a longer lag-compensation time counts as off


def _solenoid_current(cal: Calibration, current_mA: float) -> tuple[float, int]:
    """current_mA in the solenoid's range, and STATUS_CURRENT_CLAMPED if it was not (wc_vfs_current_mA)."""
    if current_mA > cal.vfs_current_max:
        return cal.vfs_current_max, STATUS_CURRENT_CLAMPED
    if current_mA < cal.vfs_current_min:
        return cal.vfs_current_min, STATUS_CURRENT_CLAMPED
    return current_mA, 0


class ClutchReference:
    """The firmware's wc_clutch_step in double precision, one period per step() (clutch_steps runs it over
    arrays). Per step: inverse at theta (a locked clutch: holding_inverse; the open/locked modes: the
    solenoid's minimum/maximum current) -> current, led ahead of the squeeze film and the VFS lag when
    lag_compensation_time_s > 0 (DESIGN 9: lead_film, lead_lag); VFS lag (exact, tau) -> reached pressure ->
    apply force F = max(P A_p - F_s, 0) -> contact force (F, or with the squeeze-film state on, the asperity
    force at the film state, which then advances under F: film_advance_m) -> model torque (the piston below its
    spring's band, friction.retracted_fraction, and no bench force: the open element's drag, friction.open_gap_m,
    DESIGN 15); lock-up (Lockup)
    against the static capacity with the required torque (the measured torque on a bench, else
    carried_torque_Nm when given, else the request, in the lock direction); while locked the held torque
    (Lockup.torque_Nm), no heat and STATUS_LOCKED; observer advanced with |T dw| and kept in
    [THETA_MIN_DEGC, THETA_MAX_DEGC], STATUS_OVER_TEMPERATURE above THETA_OVER_DEGC until it falls
    THETA_OVER_HYSTERESIS_K below. theta_from_oil: the model takes the oil temperature (thermal-blind).
    correction: the adaptation's (model/correction.py, DESIGN 12): mu_f scaled in the torque, the inverse and
    the static capacity, the film's damping scaled in its advance and the film lead, the kiss offset a change
    of the spring's preload both ways (contact force max(P A_p - F_s - offset, 0), the wanted contact force F
    commanded at max(F + F_s + offset, 0) / A_p); None or out of range: none. band_release (DESIGN 15;
    wc_step_input_t.band_release): in torque control, slipping, with an open drag calibrated, a request the
    inverse gives no force for commands the pressure in the return spring's band whose open drag is the request
    (friction.band_fraction; before the kiss offset, as the retracted fraction).
    The inputs are taken as valid (the frame loop's reference, hil/replay.py, holds invalid ones)."""

    def __init__(self, cal: Calibration, theta_start_degC: float):
        self.cal = cal
        self.a_th = thermal_decay(cal, cal.period)
        self.a_vfs = math.exp(-cal.period / cal.vfs_time_constant)
        self.theta = float(theta_start_degC)
        self.pressure = cal.vfs_gain * cal.vfs_current_min
        self.film_on = cal.film_squeeze_factor > 0.0
        self.hbar = float(hbar_from_pressure_m(cal, max(self.pressure * cal.piston_area - cal.return_spring_force,
                                                        0.0) / cal.friction_area))
        self.lockup = Lockup(cal)
        self.over = False

    def _lead_film(self, theta: float, time_s: float, force_cmd: float, current: float,
                   corr: Correction = NONE) -> float:
        """DESIGN 9: the apply force that squeezes the film state towards the wanted force's film with time
        constant time_s, never below the wanted force, at most F_max; its current (wc_clutch.c lead_film)."""
        cal = self.cal
        if not self.film_on or not time_s <= LEAD_TIME_MAX_S:
            return current
        target = float(hbar_from_pressure_m(cal, force_cmd / cal.friction_area))
        if not self.hbar > target:
            return current
        contact = cal.friction_area * float(film_contact_pressure_Pa(cal, self.hbar)[0])
        squeeze = (float(film_damping_N_s_m2(cal, theta)) * corr.film_factor * (self.hbar - target)
                   / (time_s * self.hbar ** 3))
        force = contact + squeeze
        if not force > force_cmd:
            return current
        force = min(force, force_max_N(cal))
        # the current clamped to the solenoid's range, no status (the firmware's lead_film drops it too)
        return _solenoid_current(cal, float(kiss_pressure_Pa(cal, force, corr.kiss_offset_N)) / cal.vfs_gain)[0]

    def _lead_lag(self, time_s: float, current: float) -> tuple[float, int]:
        """DESIGN 9: K i = P + (P* - P) (1 - e^(-dt/t)) / (1 - e^(-dt/tau)), clamped (wc_clutch.c lead_lag)."""
        cal = self.cal
        if not time_s <= LEAD_TIME_MAX_S:
            return current, 0
        wanted = cal.vfs_gain * current
        gain = (1.0 - math.exp(-cal.period / time_s)) / (1.0 - self.a_vfs)
        return _solenoid_current(cal, (self.pressure + (wanted - self.pressure) * gain) / cal.vfs_gain)

    def step(self, slip_rpm: float, oil_degC: float, housing_degC: float, request_Nm: float, mode: int,
             bench_force_N: float = math.nan, bench_torque_Nm: float = math.nan, lag_compensation_time_s: float = 0.0,
             theta_from_oil: bool = False, carried_torque_Nm: float = 0.0,
             correction: Correction | None = None, band_release: bool = False) -> dict:
        cal = self.cal
        corr = effective(correction)
        lockup = self.lockup
        theta_model = oil_degC if theta_from_oil else self.theta
        if mode == MODE_TORQUE:
            inv = (holding_inverse(cal, theta_model, request_Nm, corr.friction_factor, corr.kiss_offset_N)
                   if lockup.locked else inverse(cal, slip_rpm, theta_model, request_Nm, corr.friction_factor,
                                                 corr.kiss_offset_N))
            current, force_cmd, status = float(inv["current_mA"]), float(inv["force_N"]), int(inv["status"])
        else:
            current = cal.vfs_current_max if mode == MODE_LOCKED else cal.vfs_current_min
            force_cmd = max(cal.vfs_gain * current * cal.piston_area - cal.return_spring_force, 0.0)
            status = 0
        open_drag = cal.open_clearance > 0.0 or cal.open_aeration_speed > 0.0
        if band_release and open_drag and mode == MODE_TORQUE and not lockup.locked and not force_cmd > 0.0:
            # DESIGN 15: a request below the kiss point's drag retracts the piston into its spring's band: the
            # fraction whose open drag (plus the film's contact torque) is the request
            hbar = self.hbar if self.film_on else float(hbar_from_pressure_m(cal, 0.0))
            contact = cal.friction_area * float(film_contact_pressure_Pa(cal, hbar)[0]) if self.film_on else 0.0
            at_film = torque_parts(cal, abs(slip_rpm), theta_model, contact, hbar_m=hbar,
                                   friction_factor=corr.friction_factor)
            r = band_fraction(cal, request_Nm - abs(float(at_film["coulomb_Nm"])),
                              abs(float(at_film["viscous_Nm"])) * hbar, hbar, slip_rpm)
            # never above the learned kiss point (an earlier one would apply the pack in the band)
            kiss = float(kiss_pressure_Pa(cal, 0.0, corr.kiss_offset_N))
            current, clamped = _solenoid_current(cal, min(band_pressure_Pa(cal, r), kiss) / cal.vfs_gain)
            status |= clamped
        lead = mode == MODE_TORQUE and lag_compensation_time_s > 0.0
        if lead:
            current = self._lead_film(theta_model, lag_compensation_time_s, force_cmd, current, corr)
        target = cal.vfs_gain * current
        if lead:
            current, clamped = self._lead_lag(lag_compensation_time_s, current)
            status |= clamped
        self.pressure = cal.vfs_gain * current + (self.pressure - cal.vfs_gain * current) * self.a_vfs
        pressure = self.pressure
        # DESIGN 12: the kiss offset moves the spring's preload (0: the calibration's); a bench's load cell
        # measures the apply force itself
        force = max(pressure * cal.piston_area - cal.return_spring_force - corr.kiss_offset_N, 0.0)
        if not math.isnan(bench_force_N):
            force = bench_force_N
        # inside the lock band the torque keeps the lock direction (the slip's sign there is noise)
        in_band = abs(slip_rpm) * RAD_S_PER_RPM < cal.lock_slip
        # DESIGN 15: the open element (the modelled piston off the pack by the retracted fraction, before the
        # kiss offset; on a bench all the way while no load on the cell) drags through its clearance, aerated
        open_element = retracted_fraction(cal, pressure) if math.isnan(bench_force_N) else \
            (0.0 if bench_force_N > 0.0 else 1.0)
        if self.film_on:
            contact = cal.friction_area * float(film_contact_pressure_Pa(cal, self.hbar)[0])
            parts = torque_parts(cal, abs(slip_rpm), theta_model, contact, hbar_m=self.hbar,
                                 friction_factor=corr.friction_factor, open_element=open_element)
            self.hbar = film_advance_m(cal, self.hbar, force, theta_model,
                                       squeeze_factor=cal.film_squeeze_factor * corr.film_factor)
        else:
            contact = force
            parts = torque_parts(cal, abs(slip_rpm), theta_model, force, friction_factor=corr.friction_factor,
                                 open_element=open_element)
        sign = lockup.direction if in_band else (-1.0 if slip_rpm < 0.0 else 1.0)
        torque = float(parts["torque_Nm"]) * sign
        coulomb = abs(float(parts["coulomb_Nm"])) * sign
        capacity = float(static_capacity_Nm(cal, theta_model, contact)) * corr.friction_factor
        bench_torque = not math.isnan(bench_torque_Nm)
        carried = 0.0 < carried_torque_Nm <= TORQUE_MAX_NM   # else the request (wc_clutch_step)
        required = bench_torque_Nm if bench_torque else lockup.direction * (carried_torque_Nm if carried else request_Nm)
        slip_rad_s = slip_rpm * RAD_S_PER_RPM
        if lockup.update(slip_rad_s, required, capacity):
            torque = lockup.torque_Nm(required, capacity)
            coulomb = torque               # static friction only (wc_clutch_step)
            status |= STATUS_LOCKED
            power = 0.0
        else:
            power = abs((bench_torque_Nm if bench_torque else torque) * slip_rad_s)
        theta_used = theta_model
        steady = float(thermal_steady_degC(cal, power, oil_degC, housing_degC))
        theta = steady + (self.theta - steady) * self.a_th
        self.theta = min(max(theta, THETA_MIN_DEGC), THETA_MAX_DEGC)      # thermal envelope
        if self.theta > THETA_OVER_DEGC:
            self.over = True
        elif self.theta < THETA_OVER_DEGC - THETA_OVER_HYSTERESIS_K:
            self.over = False
        if self.over:
            status |= STATUS_OVER_TEMPERATURE
        return {"current_mA": current, "pressure_command_Pa": target, "pressure_model_Pa": pressure,
                "force_command_N": force_cmd, "theta_degC": theta_used, "torque_Nm": torque,
                "mu_f": float(parts["mu_f"]), "hbar_m": float(parts["hbar_m"]), "contact_force_N": contact,
                "static_capacity_Nm": capacity, "status": status,
                # the adaptation's samples (reference/adaptation.py): the Coulomb part, per newton of contact
                "coulomb_Nm": coulomb,
                "coulomb_per_N": cal.effective_radius * cal.friction_pairs * float(parts["mu_f"])}


def clutch_steps(cal: Calibration, slip_rpm, theta_oil_degC, theta_housing_degC, torque_request_Nm,
                 mode=None, theta_start_degC=None, bench_force_N=None, bench_torque_Nm=None, band_release=False,
                 lag_compensation_time_s=0.0, correction=None):
    """The firmware's wc_clutch_step, composed in double precision, one row per period (ClutchReference).
    Returns a dict of arrays; theta_degC[k] is the estimate used in step k (before its update). On a bench
    (rows where bench_force_N / bench_torque_Nm are given and not NaN) the torque model uses the measured force
    and the observer's heat input the measured torque. band_release, lag_compensation_time_s, correction: every
    step's (ClutchReference.step)."""
    slip = np.asarray(slip_rpm, dtype=float)
    n = slip.size
    oil = np.broadcast_to(np.asarray(theta_oil_degC, dtype=float), (n,))
    housing = np.broadcast_to(np.asarray(theta_housing_degC, dtype=float), (n,))
    request = np.broadcast_to(np.asarray(torque_request_Nm, dtype=float), (n,))
    modes = np.broadcast_to(np.asarray(MODE_TORQUE if mode is None else mode), (n,))
    def optional(x):
        return np.broadcast_to(np.asarray(np.nan if x is None else x, dtype=float), (n,))
    measured, measured_torque = optional(bench_force_N), optional(bench_torque_Nm)
    ref = ClutchReference(cal, float(oil[0]) if theta_start_degC is None else float(theta_start_degC))
    out = {k: np.empty(n) for k in CLUTCH_OUTPUTS}
    for k in range(n):
        row = ref.step(float(slip[k]), float(oil[k]), float(housing[k]), float(request[k]), int(modes[k]),
                       float(measured[k]), float(measured_torque[k]), band_release=bool(band_release),
                       lag_compensation_time_s=float(lag_compensation_time_s), correction=correction)
        for key in CLUTCH_OUTPUTS:
            out[key][k] = row[key]
    out["status"] = out["status"].astype(int)
    return out
