"""What every identification step shares: the settings and the error it raises."""
from __future__ import annotations

from dataclasses import dataclass


class IdentifyError(RuntimeError):
    """Data that cannot be identified from; the message says which file, line or column and why.
    (A RuntimeError, so the command line prints it without a traceback and exits 2.)"""


@dataclass(frozen=True)
class Settings:
    slip_min_rpm: float = 1.0        # |slip| (smoothed) below: stopped or stuck (static friction), not eq. 17
    smooth_slip_s: float = 0.1       # moving average of the slip (encoder noise) for v and the stuck test
    force_min_N: float = 50.0        # below: no contact
    film_settle_s: float = 0.5       # 5x the squeeze-film time constant (0.05-0.1 s, DESIGN 7)
    force_rate_N_s: float = 500.0    # |dF/dt| above this (50 ms average) is a load change
    bin_s: float = 0.01              # friction samples are averaged over bins of this length
    smooth_friction_s: float = 0.5   # Savitzky-Golay window for theta' in the friction runs
    smooth_thermal_s: float = 1.0    # half-width of the eq. 19 modulating function (kernel filter)
    thermal_step_s: float = 0.02     # the thermal regression's sample spacing after filtering
    flat_speed_m_s: float = 0.16     # asperity step: mu_f flat above max(this, 6 v_s) (paper: 20 rpm)
    thermistor_lag_s: float | None = None   # fixed lag instead of fitting it
    lag_all_thermistors: bool = True        # oil and housing thermistors lag like the clutch one
    simex: bool = True               # mu: correct mu2, v_s for the slip noise (errors in variables)
    fit_heat_capacity: bool = False
    jobs: int = 2
