"""Double-precision reference of the control model (DESIGN.md section 2).

Independent of the firmware: NumPy/SciPy in float64, vectorized, with the
film thickness solved exactly (no table). FilmTable, beside the exact form, is
the tabulated h_bar(p_c) for many samples (bench simulator, identification),
tested against it. Equation numbers are the paper's.
Units: SI, temperatures in degC, slip speed in rpm at the interfaces.

One module per concern, all names importable from here (``model.torque_parts``):

constants     unit conversion, status bits, thermal envelope, input ranges, clutch modes
film          the steady film: p_c(h) (eq. 15), h_bar(h) (eq. 9), inverses, film domain, FilmTable
squeeze_film  the squeeze-film state (DESIGN 9): film_advance_m, FilmDynamics
friction      viscosity (eq. 2), mu_f (eq. 18), torque (eq. 3-8), static capacity, the open element's gap
inverse       torque request -> force -> pressure -> current (slipping and locked)
thermal       eq. 1: decay, steady state, the observer over a series
lockup        the lock-up state machine (wc_lockup.c)
clutch        the clutch step (wc_clutch_step): ClutchReference, clutch_steps
correction    the adaptation's correction of the model (wc_model_correction_t, DESIGN 12)
"""
from __future__ import annotations

from .constants import (FORCE_MAX_N, MODE_LOCKED, MODE_OPEN, MODE_TORQUE, RAD_S_PER_RPM, SLIP_MAX_RAD_S,
                        STATUS_BELOW_DRAG, STATUS_CURRENT_CLAMPED, STATUS_FORCE_INVALID, STATUS_INPUT_INVALID,
                        STATUS_LOCKED, STATUS_NOT_INITIALISED, STATUS_OVER_TEMPERATURE, STATUS_POWER_INVALID,
                        STATUS_SATURATED, STATUS_SLIP_INVALID, STATUS_THETA_INVALID, STATUS_TORQUE_INVALID,
                        THETA_MAX_DEGC, THETA_MIN_DEGC, THETA_OVER_DEGC, THETA_OVER_HYSTERESIS_K, TORQUE_MAX_NM)
from .film import (FilmTable, contact_pressure_Pa, film_domain, film_slope_m_per_Pa, film_thickness_m,
                   hbar_from_pressure_m, separation_from_pressure_m)
from .squeeze_film import (FilmDynamics, film_advance_m, film_contact_pressure_Pa, film_damping_N_s_m2,
                           reynolds_factor_m4, separation_from_hbar_m)
from .friction import (band_fraction, band_pressure_Pa, force_max_N, friction_coefficient, open_gap_m, retracted_fraction, static_capacity_Nm,
                       torque_at_film_Nm, torque_parts, viscosity_Pa_s, viscosity_slope_Pa_s_per_K)
from .inverse import holding_inverse, inverse
from .thermal import thermal_decay, thermal_observer, thermal_steady_degC
from .lockup import Lockup
from .clutch import CLUTCH_OUTPUTS, LEAD_TIME_MAX_S, ClutchReference, clutch_steps

__all__ = [
    "CLUTCH_OUTPUTS", "ClutchReference", "FORCE_MAX_N", "FilmDynamics", "FilmTable", "LEAD_TIME_MAX_S", "Lockup",
    "MODE_LOCKED", "MODE_OPEN", "MODE_TORQUE", "RAD_S_PER_RPM", "SLIP_MAX_RAD_S", "STATUS_BELOW_DRAG",
    "STATUS_CURRENT_CLAMPED", "STATUS_FORCE_INVALID", "STATUS_INPUT_INVALID", "STATUS_LOCKED",
    "STATUS_NOT_INITIALISED", "STATUS_OVER_TEMPERATURE", "STATUS_POWER_INVALID", "STATUS_SATURATED",
    "STATUS_SLIP_INVALID", "STATUS_THETA_INVALID", "STATUS_TORQUE_INVALID", "THETA_MAX_DEGC", "THETA_MIN_DEGC",
    "THETA_OVER_DEGC", "THETA_OVER_HYSTERESIS_K", "TORQUE_MAX_NM", "clutch_steps", "contact_pressure_Pa",
    "film_advance_m", "film_contact_pressure_Pa", "film_damping_N_s_m2", "film_domain", "film_slope_m_per_Pa",
    "film_thickness_m", "force_max_N", "friction_coefficient", "hbar_from_pressure_m", "holding_inverse", "inverse",
    "band_fraction", "band_pressure_Pa", "open_gap_m", "retracted_fraction", "reynolds_factor_m4", "separation_from_hbar_m", "separation_from_pressure_m",
    "static_capacity_Nm",
    "thermal_decay", "thermal_observer", "thermal_steady_degC", "torque_at_film_Nm", "torque_parts",
    "viscosity_Pa_s", "viscosity_slope_Pa_s_per_K",
]
