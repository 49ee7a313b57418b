"""The adaptation's golden vectors (DESIGN 12, include/wetclutch/wc_adapt.h), part of ``wetclutch vectors``:
from the double-precision reference (reference/adaptation.py) on synthetic inertia-phase windows whose truth
is known, for tests/c/test_adapt.c.

A window is what wc_adapt_sample sees after each clutch step of an inertia phase: the phase time, the slip,
drive = a T_t / I_t, the step's model torque, its Coulomb part, mu_f, contact force, theta and status. The
slip is integrated from a chosen true clutch torque with the driveline model of the header,
d(slip)/dt = drive - m T_true, so the torque the driveline implies is T_true and the truth of each case is
known: a friction scale s_true on the Coulomb part, a contact force dF lower than modelled (a later kiss
point), a film slower than modelled (less torque early in the window); the true torque stands on the model's
film (the residual is the Coulomb part's alone, r = (s - 1) x1 - s dF x2 exactly). Every input is rounded to float32
before the reference sees it (the C test reads the same values, written with 9 significant digits).

The adaptation calibration of the vectors (SETTINGS) is fixed here, not read from shift_1_2.toml: the
vectors test the algorithm and stay valid when the shift calibration is retuned; its times avoid an exact
multiple of the period (the window's start and its early part are not decided by a float rounding).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..reference import adaptation as adapt_ref, model

DT_S = 0.001                       # table1's control period
SAMPLES = 220                      # periods of a window's inertia phase
TURBINE_RATIO, TURBINE_INERTIA = 1.0, 0.25      # the driveline of m (shift_1_2.toml's values)
OUTPUT_RATIO, OUTPUT_INERTIA = 3.1, 15.1
FILM_SQUEEZE_FACTOR = 0.1          # the film state on (the film update needs it): table1 with this factor

# The adaptation calibration of the vectors (names of shift_1_2.toml); float32 values.
SETTINGS = {
    "adaptation": 1, "min_start_slip": 5.0,
    "adapt_theta_node0": 40.0, "adapt_theta_node1": 70.0, "adapt_theta_node2": 100.0, "adapt_theta_node3": 130.0,
    "adapt_theta_node4": 160.0,
    "adapt_scale_band": 0.25, "adapt_scale_step": 0.06, "adapt_scale_gain": 0.6, "adapt_confidence_gain": 0.3,
    "adapt_film_factor_min": 0.2, "adapt_film_factor_max": 5.0, "adapt_film_step": 0.3, "adapt_film_gain": 0.5,
    "adapt_kiss_band": 60000.0, "adapt_kiss_step": 10000.0, "adapt_kiss_gain": 0.5,
    "adapt_window_skip": 0.0205, "adapt_film_window": 0.0405, "adapt_min_slip_drop": 0.3,
    "adapt_min_conditioning": 0.02,
}
SETTINGS = {k: (v if isinstance(v, int) else adapt_ref.f32(v)) for k, v in SETTINGS.items()}
C_FIELDS = (("adapt_theta_node_degC[0]", "adapt_theta_node0"), ("adapt_theta_node_degC[1]", "adapt_theta_node1"),
            ("adapt_theta_node_degC[2]", "adapt_theta_node2"), ("adapt_theta_node_degC[3]", "adapt_theta_node3"),
            ("adapt_theta_node_degC[4]", "adapt_theta_node4"), ("adapt_scale_band", "adapt_scale_band"),
            ("adapt_scale_step", "adapt_scale_step"), ("adapt_scale_gain", "adapt_scale_gain"),
            ("adapt_confidence_gain", "adapt_confidence_gain"), ("adapt_film_factor_min", "adapt_film_factor_min"),
            ("adapt_film_factor_max", "adapt_film_factor_max"), ("adapt_film_step", "adapt_film_step"),
            ("adapt_film_gain", "adapt_film_gain"), ("adapt_kiss_band_Pa", "adapt_kiss_band"),
            ("adapt_kiss_step_Pa", "adapt_kiss_step"), ("adapt_kiss_gain", "adapt_kiss_gain"),
            ("adapt_window_skip_s", "adapt_window_skip"), ("adapt_film_window_s", "adapt_film_window"),
            ("adapt_min_slip_drop", "adapt_min_slip_drop"), ("adapt_min_conditioning", "adapt_min_conditioning"),
            ("min_start_slip_rad_s", "min_start_slip"))

LEARNED = adapt_ref.AdaptValues([adapt_ref.f32(x) for x in (0.92, 0.97, 1.04, 1.12, 1.2)],    # the C's floats
                                [adapt_ref.f32(x) for x in (0.9, 0.6, 0.3, 0.0, 0.5)], adapt_ref.f32(1.3), -8000.0, 7)
CORRECTION_THETA_DEGC = (-40.0, 20.0, 40.0, 55.0, 69.9, 70.0, 85.5, 100.0, 129.0, 160.0, 200.0, 250.0)


@dataclass(frozen=True)
class Case:
    """One synthetic window and its truth."""
    name: str
    what: str
    s_true: float = 1.0                 # the plant's Coulomb torque / the calibration's (unscaled) model's
    kiss_true_N: float = 0.0            # the plant's contact force: the apply force minus this
    film_dip: float = 0.0               # the true torque x (1 - dip e^(-t / FILM_TIME_S)) from the window start
    slip_end_rad_s: float = 20.0        # the slip at the last period (a constant drive chosen for it)
    theta_degC: tuple = (75.0, 95.0)    # theta at the first and the last period
    film_on: bool = True
    adaptation: int = 1
    abort_reason: int = 0
    fault_status: int = 0               # a status bit on one window sample
    nan_drive: bool = False             # a NaN drive on one window sample
    slip_noise_rad_s: float = 0.0       # uniform noise on the measured slip below 2 min_start_slip (a fixed seed)
    values: adapt_ref.AdaptValues = field(default_factory=adapt_ref.AdaptValues)


FILM_TIME_S = 0.012
FAULT_PERIOD = 120                     # the sample that carries the fault

CASES = (
    Case("matched", "the model matches the plant (rho 1): scales stay, confidences rise"),
    Case("friction_plus10", "the plant's friction +10 %: the scales move up", s_true=1.1),
    Case("kiss_later", "contact force 60 N below the model's (a kiss point 12 kPa later): the kiss offset moves up",
         kiss_true_N=60.0),
    Case("film_slow", "a film slower than modelled (35 % less torque at the window's start, 12 ms): the film factor"
         " moves up", film_dip=0.35),
    Case("film_off", "as film_slow with the clutch's film state off: no film update", film_dip=0.35, film_on=False),
    Case("learned", "learned values inside their bands, +6 % friction over 60..140 degC: the normalised update, the"
         " unlearned node's prior, the band", s_true=1.06, theta_degC=(60.0, 140.0), values=LEARNED),
    Case("implausible", "the plant's friction x 0.4: rho outside [0.5, 2], nothing learned", s_true=0.4),
    Case("excitation", "the slip falls 20 % over the window (< adapt_min_slip_drop): nothing learned",
         s_true=1.1, slip_end_rad_s=72.0),
    Case("input_fault", "an invalid slip (status bit) on one window sample: nothing learned", s_true=1.1,
         fault_status=model.STATUS_SLIP_INVALID),
    Case("aborted", "the shift aborted: nothing learned", s_true=1.1, abort_reason=1),
    Case("off", "adaptation 0: nothing learned, the report's defaults", s_true=1.1, adaptation=0),
    # the header's rules where wc_adapt.c read them otherwise (reported; tests/c/test_adapt.c: test_spec_edges)
    Case("nan_drive", "a NaN drive on one window sample (\"NaN samples mark the window invalid\"): an input"
         " fault, nothing learned", s_true=1.1, nan_drive=True),
    Case("slip_reenters", "the plant's friction +10 %, the slip falls below min_start_slip and, with +-0.8 rad/s"
         " of noise near it, crosses it again (\"while the slip stays above\"): the window closes at the first crossing",
         s_true=1.1, slip_end_rad_s=3.0, slip_noise_rad_s=0.8),
)
SPEC_EDGE_CASES = ("nan_drive", "slip_reenters")


def _f32(x):
    return np.asarray(x, dtype=np.float32).astype(float)


def window(cal, case: Case) -> dict:
    """The case's samples (float32 values as float) and m."""
    m = float(_f32(TURBINE_RATIO**2 / TURBINE_INERTIA + OUTPUT_RATIO**2 / OUTPUT_INERTIA))
    k = np.arange(SAMPLES)
    t = k * DT_S
    theta = case.theta_degC[0] + (case.theta_degC[1] - case.theta_degC[0]) * k / (SAMPLES - 1)
    apply = 2200.0 + 1000.0 * (t / t[-1]) + 600.0 * np.sin(2.0 * math.pi * t / 0.07)   # varied: the kiss's LS
    # the model's contact force: the apply force minus the learned kiss offset (wc_model_correction_t)
    force = np.maximum(apply - case.values.kiss_offset_Pa * cal.piston_area, 0.0)
    nodes = [SETTINGS[f"adapt_theta_node{i}"] for i in range(adapt_ref.NODES)]
    scale_model = np.array([adapt_ref.interpolated_scale(case.values, nodes, th) for th in theta])
    start = int(round(SETTINGS["adapt_window_skip"] / DT_S + 0.5))
    dip = 1.0 - case.film_dip * np.exp(-np.maximum(k - start, 0) * DT_S / FILM_TIME_S)
    def integrate(drive: float) -> tuple[np.ndarray, dict]:
        slip = np.empty(SAMPLES)
        slip[0] = 90.0
        rows = {n: np.empty(SAMPLES) for n in ("torque_Nm", "coulomb_Nm", "mu_f", "true_Nm")}
        for j in range(SAMPLES):
            rpm = slip[j] / model.RAD_S_PER_RPM
            p = model.torque_parts(cal, rpm, theta[j], force[j], friction_factor=scale_model[j])
            true = model.torque_parts(cal, rpm, theta[j], max(apply[j] - case.kiss_true_N, 0.0),
                                      hbar_m=p["hbar_m"], friction_factor=case.s_true)
            rows["torque_Nm"][j], rows["coulomb_Nm"][j], rows["mu_f"][j] = p["torque_Nm"], p["coulomb_Nm"], p["mu_f"]
            rows["true_Nm"][j] = float(true["torque_Nm"]) * dip[j]
            if j + 1 < SAMPLES:
                slip[j + 1] = float(_f32(slip[j] + DT_S * (drive - m * rows["true_Nm"][j])))
        return slip, rows

    # a constant drive that takes the slip from 90 rad/s to slip_end (the torques depend on the slip only
    # through the Stribeck and viscous terms: a few passes)
    drive = float(_f32(m * 350.0))
    for _ in range(4):
        slip, rows = integrate(drive)
        drive = float(_f32(drive + (case.slip_end_rad_s - slip[-1]) / ((SAMPLES - 1) * DT_S)))
    slip, rows = integrate(drive)
    if case.slip_noise_rad_s:
        near = slip < 2.0 * SETTINGS["min_start_slip"]      # near the lock only
        slip = _f32(slip + near * case.slip_noise_rad_s * np.random.default_rng(20).uniform(-1.0, 1.0, SAMPLES))
    out = {"elapsed_s": _f32(_f32(k) * _f32(DT_S)), "slip_rad_s": _f32(slip), "drive_rad_s2": np.full(SAMPLES, drive),
           "torque_Nm": _f32(rows["torque_Nm"]), "coulomb_Nm": _f32(rows["coulomb_Nm"]), "mu_f": _f32(rows["mu_f"]),
           "contact_force_N": _f32(force), "theta_degC": _f32(theta), "status": np.zeros(SAMPLES, dtype=int)}
    if case.fault_status:
        out["status"][FAULT_PERIOD] = case.fault_status
    if case.nan_drive:
        out["drive_rad_s2"][FAULT_PERIOD] = math.nan
    return {"samples": out, "inverse_inertia": m}


def run_case(cal, case: Case) -> dict:
    """The reference on the case's window: the values before and after, the change."""
    settings = adapt_ref.AdaptSettings.from_values({**SETTINGS, "adaptation": case.adaptation})
    w = window(cal, case)
    ref = adapt_ref.AdaptationReference(settings, DT_S, cal.piston_area, case.film_on, case.values)
    ref.begin()
    s = w["samples"]
    for j in range(SAMPLES):
        out = {"torque_Nm": s["torque_Nm"][j], "coulomb_Nm": s["coulomb_Nm"][j], "theta_degC": s["theta_degC"][j],
               "coulomb_per_N": s["coulomb_Nm"][j] / s["contact_force_N"][j], "status": int(s["status"][j])}
        ref.sample(float(s["elapsed_s"][j]), float(s["slip_rad_s"][j]), float(s["drive_rad_s2"][j]),
                   w["inverse_inertia"], out)
    change = ref.finish(case.abort_reason)
    return {"window": w, "before": case.values, "after": ref.values, "change": change, "samples": ref.window.samples}


def _c(x: float) -> str:
    return f"{x:.9g}" if math.isfinite(x) else "NAN"


def _cf(x: float) -> str:
    """A C float literal (a decimal point or an exponent before the f)."""
    t = _c(x)
    return t + ("f" if any(ch in t for ch in ".e") else ".0f")


def _values(v: adapt_ref.AdaptValues) -> str:
    return ("{ { " + ", ".join(_c(x) for x in v.friction_scale) + " }, { " + ", ".join(_c(x) for x in v.confidence)
            + f" }}, {_c(v.film_factor)}, {_c(v.kiss_offset_Pa)}, {v.shifts_learned}u }}")


def header_part(cal) -> str:
    """The adaptation's part of wc_golden_vectors.h."""
    sample_rows, case_rows = [], []
    for case in CASES:
        r = run_case(cal, case)
        s = r["window"]["samples"]
        first = len(sample_rows)
        for j in range(SAMPLES):
            sample_rows.append("    {" + ", ".join(_c(float(s[n][j])) for n in (
                "elapsed_s", "slip_rad_s", "drive_rad_s2", "torque_Nm", "coulomb_Nm", "mu_f", "contact_force_N",
                "theta_degC")) + f", {int(s['status'][j])}u}},")
        ch = r["change"]
        case_rows.append(
            f"    /* {case.name}: {case.what}; reference: {r['samples']} samples, rho {_c(ch['rho'])},"
            f" rho_early {_c(ch['rho_early'])}, kiss estimate {_c(ch['kiss_dP_Pa'])} Pa */\n"
            f"    {{ \"{case.name}\", {first}u, {SAMPLES}u, {int(case.film_on)}u, {case.adaptation}u, {case.abort_reason}u,"
            f" {_c(r['window']['inverse_inertia'])},\n      {_values(r['before'])},\n      {_values(r['after'])},\n"
            f"      {ch['result']}u, {ch['node']}u, {r['samples']}u }},")
    corr_rows = []
    for theta in CORRECTION_THETA_DEGC:
        settings = adapt_ref.AdaptSettings.from_values(SETTINGS)
        c = adapt_ref.correction(LEARNED, settings, cal.piston_area, theta)
        corr_rows.append(f"    {{ {_c(theta)}, {_c(c.friction_scale_delta)}, {_c(c.film_factor_delta)},"
                         f" {_c(c.kiss_offset_N)} }},")
    fields = " \\\n".join(f"        (cal)->{c} = {_cf(float(SETTINGS[n]))};" for c, n in C_FIELDS)
    return (
        "\n/* The adaptation (DESIGN 12, include/wetclutch/wc_adapt.h) from tools/wetclutch/reference/adaptation.py\n"
        " * on synthetic inertia-phase windows (tools/wetclutch/generate/adapt_vectors.py): table1 with\n"
        f" * film_squeeze_factor = {FILM_SQUEEZE_FACTOR} (the film state on; off where film_on is 0), control period"
        f" {DT_S} s,\n * the adaptation calibration below. */\n"
        f"#define WC_GOLDEN_ADAPT_FILM_SQUEEZE_FACTOR {FILM_SQUEEZE_FACTOR}f\n"
        "/* the adaptation calibration of the vectors, set on a wc_shift_calibration_t */\n"
        "#define WC_GOLDEN_ADAPT_CALIBRATION(cal) \\\n    do { \\\n        (cal)->adaptation = 1u; \\\n"
        f"{fields} \\\n    }} while (0)\n\n"
        "typedef struct { double elapsed_s, slip_rad_s, drive_rad_s2, torque_Nm, coulomb_Nm, mu_f, contact_force_N,"
        " theta_degC; unsigned status; } wc_golden_adapt_sample_t;\n"
        "typedef struct { double friction_scale[5], confidence[5]; double film_factor, kiss_offset_Pa;"
        " unsigned shifts_learned; } wc_golden_adapt_values_t;\n"
        "typedef struct { const char *name; unsigned first, count, film_on, adaptation, abort_reason;"
        " double inverse_inertia;\n    wc_golden_adapt_values_t before, after; unsigned result, node, samples; }"
        " wc_golden_adapt_case_t;\n"
        "typedef struct { double theta_degC, friction_scale_delta, film_factor_delta, kiss_offset_N; }"
        " wc_golden_adapt_correction_t;\n\n"
        "/* wc_adapt_sample's inputs, one row per inertia-phase period */\n"
        "static const wc_golden_adapt_sample_t wc_golden_adapt_samples[] = {\n" + "\n".join(sample_rows) + "\n};\n\n"
        "/* each case: its samples, the values before (wc_adapt_t.values) and after wc_adapt_finish, the result,\n"
        " * the report's node, the window's sample count */\n"
        "static const wc_golden_adapt_case_t wc_golden_adapt_cases[] = {\n" + "\n".join(case_rows) + "\n};\n\n"
        f"/* wc_adapt_correction of the values {_values(LEARNED)} (the learned case's)\n"
        " * at theta_degC, table1's piston area */\n"
        "static const wc_golden_adapt_correction_t wc_golden_adapt_correction[] = {\n" + "\n".join(corr_rows) + "\n};\n"
    )
