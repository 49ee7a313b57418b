"""Golden test vectors for the C tests (``wetclutch vectors``), from the reference."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..calibration import Calibration
from ..reference import evaluate as reference, model
from ..reference.model.correction import Correction
from ..util import atomic
from . import adapt_vectors
from .lut import banner

SLIP_RPM = (-750.0, 0.0, 0.5, 3.0, 12.0, 50.0, 100.0, 300.0, 750.0, 1500.0, 3000.0)
THETA_DEGC = (10.0, 25.0, 40.0, 65.0, 90.0, 120.0)
FORCE_N = (0.0, 1.0, 50.0, 300.0, 903.0, 1188.0, 1613.0, 2200.0, 3000.0)
TORQUE_NM = (0.0, 2.0, 10.0, 40.0, 100.0, 150.0, 300.0, 600.0, 1500.0, 4000.0, 20000.0)


def _grid(*axes):
    mesh = np.meshgrid(*axes, indexing="ij")
    return [m.ravel() for m in mesh]


def thermal_profile(cal: Calibration):
    """A 3 s series: slip and torque steps, oil and housing steps, one row per period."""
    n = int(round(3.0 / cal.period))
    t = np.arange(n) * cal.period
    slip = np.where(t < 0.5, 0.0, np.where(t < 1.5, 750.0 - 500.0 * (t - 0.5), np.where(t < 2.2, 300.0, -100.0)))
    torque = np.where(t < 0.5, 0.0, np.where(t < 2.2, 150.0, 60.0))
    oil = np.where(t < 1.0, 40.0, 45.0)
    housing = np.where(t < 2.0, 38.0, 42.0)
    return {"t_s": t, "slip_rpm": slip, "torque_Nm": torque, "theta_oil_degC": oil, "theta_housing_degC": housing}


HOT_EVERY = 10  # rows of the hot-clutch series kept in the header (the C test steps every period)


def hot_clutch_profile(cal: Calibration):
    """The thermal envelope (DESIGN section 8): 1.2 s of torque control at 300 rad/s,
    400 Nm requested, oil and housing at 120 degC (the estimate passes the
    over-temperature threshold and is held at the envelope's 250 degC), then
    1.6 s released at standstill (it cools below the threshold minus the hysteresis)."""
    n = int(round(2.8 / cal.period))
    t = np.arange(n) * cal.period
    hot = t < 1.2
    return {"step": np.arange(n, dtype=float), "slip_rpm": np.where(hot, 300.0 / model.RAD_S_PER_RPM, 0.0),
            "theta_oil_degC": np.full(n, 120.0), "theta_housing_degC": np.full(n, 120.0),
            "torque_request_Nm": np.where(hot, 400.0, 0.0), "mode": np.where(hot, model.MODE_TORQUE, model.MODE_OPEN)}


# The engagement-edge series runs table1 with the squeeze-film state on and a static factor above 1 (so the
# capacity at the steady inverse's force is not exactly the request: no marginal lock decision); the C test
# sets the same two fields on its copy of wc_table1_calibration.
EDGES_SQUEEZE_FACTOR = 0.1
EDGES_STATIC_FACTOR = 1.25


def edges_profile(cal: Calibration):
    """Engagement edges (DESIGN 9) in 1.6 s: open at 300 rpm; torque control (120 Nm) from 0.1 s with the slip
    falling linearly to 0 at 0.8 s (contact: the squeeze film), then +-0.5 rpm of noise (lock after the dwell);
    the request steps to 200 Nm at 1.0 s (breakaway: the capacity lags with the VFS and the film) and the clutch
    locks again; at 1.45 s the slip steps to -20 rpm (breakaway by slip, the other direction)."""
    n = int(round(1.6 / cal.period))
    k = np.arange(n)
    t = k * cal.period
    slip = np.where(t < 0.1, 300.0, 300.0 * np.clip((0.8 - t) / 0.7, 0.0, None))
    slip = np.where(t >= 0.8, np.where(k % 2 == 0, 0.5, -0.5), slip)
    slip = np.where(t >= 1.45, -20.0, slip)
    request = np.where(t < 1.0, 120.0, 200.0)
    mode = np.where(t < 0.1, model.MODE_OPEN, model.MODE_TORQUE)
    return {"step": k.astype(float), "slip_rpm": slip, "theta_oil_degC": np.full(n, 40.0),
            "theta_housing_degC": np.full(n, 40.0), "torque_request_Nm": request, "mode": mode}


# The open element's drag (DESIGN 15) runs table1 with an 8-speed element's open drag: the retracted piston's
# 1.5 mm stroke over table1's 8 gaps and the open pack's aeration at 1500 rpm (tools/gearboxes/8hp.toml); the C
# test sets the same two fields on its copy of wc_table1_calibration.
OPEN_CLEARANCE_M = 1.875e-4
OPEN_AERATION_SPEED_RAD_S = 157.08
OPEN_SLIPS_RPM = (50.0, 150.0, 400.0, 1000.0, 1500.0, 2500.0, 4000.0, -1500.0, -300.0, 20.0)   # 60 ms each


def open_drag_profile(cal: Calibration):
    """The open element's drag (DESIGN 15) in 1 s: open (the piston at the solenoid's minimum, below its return
    spring) at each slip of OPEN_SLIPS_RPM for 60 ms; torque control (80 Nm at 750 rpm) from 0.6 s: the piston
    passes its spring, the clearance goes; open again from 0.8 s: the pressure falls below the spring, the
    clearance returns. Oil and housing at 60 degC, the estimate starting there."""
    n = int(round(1.0 / cal.period))
    k = np.arange(n)
    t = k * cal.period
    level = np.minimum((t / 0.06 + 1e-9).astype(int), len(OPEN_SLIPS_RPM) - 1)
    slip = np.where(t < 0.6, np.asarray(OPEN_SLIPS_RPM)[level], 750.0)
    torque = (t >= 0.6) & (t < 0.8)
    return {"step": k.astype(float), "slip_rpm": slip, "theta_oil_degC": np.full(n, 60.0),
            "theta_housing_degC": np.full(n, 60.0), "torque_request_Nm": np.where(torque, 80.0, 0.0),
            "mode": np.where(torque, model.MODE_TORQUE, model.MODE_OPEN)}


BAND_SLIPS_RPM = (400.0, 1500.0)
BAND_REQUESTS_NM = (0.0, 0.5, 2.0, 5.0, 150.0, 1.0, 0.2)     # 60 ms each, at each slip
# The band with the film state on, the lead and a learned correction (an earlier kiss point): the film's contact
# torque, lead_lag after the band and the cap at the learned kiss pressure are compared too.
BAND_LEAD_TIME_S = 0.015
BAND_CORRECTION = Correction(friction_scale_delta=0.05, film_factor_delta=0.0, kiss_offset_N=-50.0)


def band_profile(cal: Calibration):
    """The release into the spring's band (DESIGN 15; band_release on every step) in 0.84 s: torque control at
    each slip of BAND_SLIPS_RPM (0.42 s each) through the requests of BAND_REQUESTS_NM (60 ms each): from the
    solenoid's minimum at 0 Nm, into the band at the drags below the kiss point's, applied at 150 Nm, released
    again. Oil and housing at 60 degC, the estimate starting there."""
    n = int(round(0.84 / cal.period))
    k = np.arange(n)
    t = k * cal.period
    per_slip = len(BAND_REQUESTS_NM)
    level = np.minimum((t / 0.06 + 1e-9).astype(int), 2 * per_slip - 1)
    return {"step": k.astype(float), "slip_rpm": np.asarray(BAND_SLIPS_RPM)[level // per_slip],
            "theta_oil_degC": np.full(n, 60.0), "theta_housing_degC": np.full(n, 60.0),
            "torque_request_Nm": np.asarray(BAND_REQUESTS_NM)[level % per_slip],
            "mode": np.full(n, model.MODE_TORQUE)}


def _steps_with_open(cal: Calibration, profile: dict, theta_start_degC: float, **step_options) -> dict:
    """A profile's clutch_steps on cal, with the column open: how far the modelled piston stands off the pack."""
    out = model.clutch_steps(cal, profile["slip_rpm"], profile["theta_oil_degC"], profile["theta_housing_degC"],
                             profile["torque_request_Nm"], mode=profile["mode"], theta_start_degC=theta_start_degC,
                             **step_options)
    return {**profile, **out, "open": np.array([model.retracted_fraction(cal, p) for p in out["pressure_model_Pa"]])}


def _c_double(x: float) -> str:
    return f"{x:.9g}" if math.isfinite(x) else "NAN"


def _table(name: str, ctype: str, cols: dict, order) -> str:
    rows = []
    for k in range(next(iter(cols.values())).size):
        rows.append("    {" + ", ".join(
            str(int(cols[c][k])) if c == "status" else _c_double(float(cols[c][k])) for c in order) + "},")
    return (f"/* {', '.join(order)} */\nstatic const {ctype} {name}[] = {{\n" + "\n".join(rows) + "\n};\n")


HEADER = "wc_golden_vectors.h"


def generate(cal: Calibration, out_dir: Path, command: str) -> list[str]:
    """Writes out_dir/HEADER (atomically); an output it cannot write is reported before the 20 s of reference
    computation, not after."""
    path = Path(out_dir) / HEADER
    atomic.check_writable(path)
    text = header_text(cal, command)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, text)
    return [str(path)]


def header_text(cal: Calibration, command: str) -> str:
    """The header's text: every table from the reference."""
    slip, theta, force = _grid(SLIP_RPM, THETA_DEGC, FORCE_N)
    tin = {"slip_rpm": slip, "theta_degC": theta, "force_N": force}
    tout = reference.torque(cal, tin)
    slip, theta, req = _grid(SLIP_RPM, THETA_DEGC, TORQUE_NM)
    iin = {"slip_rpm": slip, "theta_degC": theta, "torque_Nm": req}
    iout = reference.inverse(cal, iin)
    thin = thermal_profile(cal)
    thout = reference.thermal(cal, thin)
    hin = hot_clutch_profile(cal)
    hout = model.clutch_steps(cal, hin["slip_rpm"], hin["theta_oil_degC"], hin["theta_housing_degC"],
                              hin["torque_request_Nm"], mode=hin["mode"], theta_start_degC=120.0)
    keep = np.arange(0, hin["step"].size, HOT_EVERY)
    hot = {k: np.asarray(v)[keep] for k, v in {**hin, **hout}.items()}
    edges_cal = cal.with_values(film_squeeze_factor=EDGES_SQUEEZE_FACTOR, static_friction_factor=EDGES_STATIC_FACTOR)
    ein = edges_profile(edges_cal)
    eout = model.clutch_steps(edges_cal, ein["slip_rpm"], ein["theta_oil_degC"], ein["theta_housing_degC"],
                              ein["torque_request_Nm"], mode=ein["mode"], theta_start_degC=40.0)
    edges = {**ein, **eout, "hbar_um": eout["hbar_m"] * 1e6}
    open_cal = cal.with_values(open_clearance=OPEN_CLEARANCE_M, open_aeration_speed=OPEN_AERATION_SPEED_RAD_S)
    oin = open_drag_profile(open_cal)
    film = model.clutch_steps(cal, oin["slip_rpm"], oin["theta_oil_degC"], oin["theta_housing_degC"],
                              oin["torque_request_Nm"], mode=oin["mode"], theta_start_degC=60.0)
    drag = {**_steps_with_open(open_cal, oin, 60.0), "film_torque_Nm": film["torque_Nm"],
            "film_theta_degC": film["theta_degC"]}
    bin_ = band_profile(open_cal)
    band = _steps_with_open(open_cal, bin_, 60.0, band_release=True)
    film_band = _steps_with_open(open_cal.with_values(film_squeeze_factor=EDGES_SQUEEZE_FACTOR), bin_, 60.0,
                                 band_release=True, lag_compensation_time_s=BAND_LEAD_TIME_S,
                                 correction=BAND_CORRECTION)
    return (
        banner(command)
        + f"/* Golden vectors from the double-precision reference (tools/wetclutch/reference/model),\n"
        f" * calibration {Path(cal.path).name}. Values rounded to 9 significant digits. */\n"
        "#ifndef WC_GOLDEN_VECTORS_H\n#define WC_GOLDEN_VECTORS_H\n\n"
        "typedef struct { double slip_rpm, theta_degC, force_N, torque_Nm, coulomb_Nm, viscous_Nm, hbar_um, mu_f; }"
        " wc_golden_torque_t;\n"
        "typedef struct { double slip_rpm, theta_degC, torque_Nm, force_N, pressure_kPa, current_mA; int status; }"
        " wc_golden_inverse_t;\n"
        "typedef struct { double t_s, slip_rpm, torque_Nm, theta_oil_degC, theta_housing_degC, theta_degC; }"
        " wc_golden_thermal_t;\n"
        "typedef struct { double step, slip_rpm, torque_request_Nm, current_mA, theta_degC; int status; }"
        " wc_golden_hot_clutch_t;\n"
        "typedef struct { double step, slip_rpm, torque_request_Nm, current_mA, torque_Nm, hbar_um, contact_force_N,"
        " static_capacity_Nm; int status; } wc_golden_edges_t;\n"
        "typedef struct { double step, slip_rpm, torque_request_Nm, mode, open, pressure_model_Pa, torque_Nm,"
        " theta_degC, film_torque_Nm, film_theta_degC; } wc_golden_open_drag_t;\n"
        "typedef struct { double step, slip_rpm, torque_request_Nm, current_mA, pressure_model_Pa, open, torque_Nm;"
        " int status; } wc_golden_band_t;\n\n"
        + _table("wc_golden_torque", "wc_golden_torque_t", {**tin, **tout},
                 ("slip_rpm", "theta_degC", "force_N", "torque_Nm", "coulomb_Nm", "viscous_Nm", "hbar_um", "mu_f"))
        + "\n" + _table("wc_golden_inverse", "wc_golden_inverse_t", {**iin, **iout},
                        ("slip_rpm", "theta_degC", "torque_Nm", "force_N", "pressure_kPa", "current_mA", "status"))
        + "\n" + _table("wc_golden_thermal", "wc_golden_thermal_t", {**thin, **thout},
                        ("t_s", "slip_rpm", "torque_Nm", "theta_oil_degC", "theta_housing_degC", "theta_degC"))
        + f"\n/* wc_clutch_step on the hot-clutch series (vectors.hot_clutch_profile: oil = housing =\n"
        f" * 120 degC, start 120 degC; torque control before step {int(round(1.2 / cal.period))}, open after),\n"
        f" * every {HOT_EVERY}th step; theta_degC is the estimate used in that step. */\n"
        + _table("wc_golden_hot_clutch", "wc_golden_hot_clutch_t", hot,
                 ("step", "slip_rpm", "torque_request_Nm", "current_mA", "theta_degC", "status"))
        + f"\n/* wc_clutch_step on the engagement-edge series (vectors.edges_profile), table1 with\n"
        f" * film_squeeze_factor = {EDGES_SQUEEZE_FACTOR} and static_friction_factor = {EDGES_STATIC_FACTOR}: squeeze film at"
        f" contact,\n * lock, breakaway by torque, lock, breakaway by slip. Every step. */\n"
        + _table("wc_golden_edges", "wc_golden_edges_t", edges,
                 ("step", "slip_rpm", "torque_request_Nm", "current_mA", "torque_Nm", "hbar_um", "contact_force_N",
                  "static_capacity_Nm", "status"))
        + f"\n/* wc_clutch_step on the open element's series (vectors.open_drag_profile), table1 with\n"
        f" * open_clearance_m = {OPEN_CLEARANCE_M} and open_aeration_speed_rad_s = {OPEN_AERATION_SPEED_RAD_S} (DESIGN 15);"
        "\n * open: how far the modelled piston stands off the pack (0 applied .. 1 retracted, across its"
        " spring's band);\n * film_*: the same series with both 0 (the film alone). Every step. */\n"
        + _table("wc_golden_open_drag", "wc_golden_open_drag_t", drag,
                 ("step", "slip_rpm", "torque_request_Nm", "mode", "open", "pressure_model_Pa", "torque_Nm",
                  "theta_degC", "film_torque_Nm", "film_theta_degC"))
        + "\n/* wc_clutch_step with band_release on the band series (vectors.band_profile), the open element's\n"
        " * calibration above (DESIGN 15: a request below the kiss point's drag retracts the piston into its\n"
        " * spring's band; open: how far, from the modelled pressure). Every step. */\n"
        + _table("wc_golden_band", "wc_golden_band_t", band,
                 ("step", "slip_rpm", "torque_request_Nm", "current_mA", "pressure_model_Pa", "open", "torque_Nm",
                  "status"))
        + f"\n/* The same with film_squeeze_factor = {EDGES_SQUEEZE_FACTOR}, lag compensation {BAND_LEAD_TIME_S} s and the"
        f" correction\n * (friction +{BAND_CORRECTION.friction_scale_delta}, kiss offset {BAND_CORRECTION.kiss_offset_N} N:"
        " an earlier kiss point, the band capped at it). */\n"
        + _table("wc_golden_band_film", "wc_golden_band_t", film_band,
                 ("step", "slip_rpm", "torque_request_Nm", "current_mA", "pressure_model_Pa", "open", "torque_Nm",
                  "status"))
        + adapt_vectors.header_part(cal)
        + "\n#endif /* WC_GOLDEN_VECTORS_H */\n"
    )
