"""The report of an identification: figures.json, report.md, exclusions.csv (and the plots, plots.py)."""
from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..reference import model
from ..util.atomic import Staged
from .friction import identify_mu, mu_grid
from .plots import plots as make_plots
from .result import identified_values
from .signals import REASONS, Exclusion

if TYPE_CHECKING:
    from .result import Result

PAPER = {"r2": 0.9858, "rmse": 0.002102}       # Shin & Choi, section 3.3
TARGETS = {"rel_error": 0.03, "r2": 0.985, "runtime_s": 60.0}
SYMBOLS = {  # calibration name -> the paper's symbol
    "oil_conductance": "k1", "housing_conductance": "k2", "mv1": "mu_v1", "mv2": "mu_v2", "mv3": "mu_v3",
    "mv4": "mu_v4", "asperity_density": "N", "mu1": "mu1", "mu2": "mu2", "mu3": "mu3", "stribeck_speed": "v_s",
    "separator_specific_heat": "c_p,separator", "lining_specific_heat": "c_p,lining",
    "film_squeeze_factor": "phi", "static_friction_factor": "k_static",
}
EDGE_PARAMETERS = ("film_squeeze_factor", "static_friction_factor")   # issue 12: within 5 % of the truth
EDGE_REL_ERROR = 0.05
TARGET_PARAMETERS = ("mu1", "mu2", "mu3", "stribeck_speed", "oil_conductance", "housing_conductance")
EXCLUSION_COLUMNS = ["step", "experiment", "reason", "t_from_s", "t_to_s", "samples", "seconds"]


def _num(x):
    """JSON-safe float."""
    x = float(x)
    return x if math.isfinite(x) else None


def _exclusion_summary(exclusions: list[Exclusion]) -> dict:
    out = {}
    for e in exclusions:
        key = f"{e.step}/{e.reason}"
        d = out.setdefault(key, {"step": e.step, "reason": e.reason, "meaning": REASONS.get(e.reason, e.reason),
                                 "events": 0, "samples": 0, "seconds": 0.0, "experiments": set()})
        d["events"] += 1
        d["samples"] += e.samples
        d["seconds"] += e.seconds
        d["experiments"].add(e.experiment)
    for d in out.values():
        d["experiments"] = len(d["experiments"])
        d["seconds"] = round(d["seconds"], 3)
    return out


# ---------------------------------------------------------------------------
# figures.json

def _parameters(res: Result, truth: dict | None) -> dict:
    """Per identified parameter: symbol, step, base, identified, 95 % CI and, with a truth, the error."""
    values = identified_values(res)
    params = {}
    ci_all = {}
    for step, r in res.results.items():
        ci_all.update(r.get("ci95", {}))
    for name, v in values.items():
        entry = {"symbol": SYMBOLS.get(name, name), "step": next(st for st, r in res.results.items() if name in r["values"]),
                 "base": _num(res.base.values[name]), "identified": _num(v), "ci95": _num(ci_all.get(name, float("nan")))}
        if truth and name in truth:
            entry["true"] = truth[name]
            entry["error_pct"] = _num((v / truth[name] - 1.0) * 100.0)
            if name in TARGET_PARAMETERS:
                entry["within_3pct"] = bool(abs(v / truth[name] - 1.0) <= TARGETS["rel_error"])
            if name in EDGE_PARAMETERS:
                entry["within_5pct"] = bool(abs(v / truth[name] - 1.0) <= EDGE_REL_ERROR)
        params[name] = entry
    return params


def _mu_figures(res: Result, truth: dict | None) -> dict:
    r = res.results["mu"]
    grid = mu_grid(r)
    fig = {"r2": _num(r["r2"]), "rmse": _num(r["rmse"]), "paper_r2": PAPER["r2"],
           "paper_rmse": PAPER["rmse"], "samples": r["samples"], "experiments": r["experiments"],
           "residual_rho": _num(r["residual_rho"]), "thermistor_lag_s": _num(r["thermistor_lag_s"]),
           "thermistor_lag_source": r["thermistor_lag_source"],
           "simex": {k: v for k, v in r["simex"].items()},
           "without_simex": r["without_simex"],
           "grid_5rpm_5K": {"cells": grid["cells"], "r2": _num(grid["r2"]), "rmse": _num(grid["rmse"])}}
    names = ("mv1", "mv2", "mv3", "mv4", "asperity_density")
    if truth and all(k in truth for k in names + tuple(r["values"])):
        exact = identify_mu(r["fd"], res.cal.with_values(**{k: truth[k] for k in names}), r["thermistor_lag_s"])
        fig["with_true_viscosity_and_N"] = {k: _num((v / truth[k] - 1.0) * 100.0)
                                            for k, v in exact["values"].items()}
    return fig


def _thermal_figures(r: dict) -> dict:
    return {k: (_num(v) if isinstance(v, (float, np.floating)) else v) for k, v in r.items()
            if k in ("thermistor_lag_s", "thermistor_lag_ci95", "thermistor_lag_source", "heat_capacity_J_K",
                     "heat_capacity_ci95", "heat_capacity_source", "r2_eq19", "rmse_eq19_W",
                     "residual_rho", "samples", "runs", "theta_oil_housing_spread_K", "sim_rmse_K",
                     "without_lag_correction", "ids")}


def _viscosity_figures(res: Result, truth: dict | None) -> dict:
    r = res.results["viscosity"]
    fig = {"r2": _num(r["r2"]), "rmse_Pa_s": _num(r["rmse_Pa_s"]),
           "max_rel_error": _num(r["max_rel_error"]), "points": r["points"],
           "theta_range_degC": r["theta_range_degC"], "source": r["source"]}
    if truth and all(k in truth for k in ("mv1", "mv2", "mv3", "mv4")):
        th = np.linspace(*r["theta_range_degC"], 200)
        tcal = res.base.with_values(**{k: truth[k] for k in ("mv1", "mv2", "mv3", "mv4")})
        ical = res.base.with_values(**r["values"])
        fig["curve_max_rel_error_vs_true"] = _num(np.max(np.abs(
            model.viscosity_Pa_s(ical, th) / model.viscosity_Pa_s(tcal, th) - 1.0)))
    return fig


def _asperity_figures(r: dict) -> dict:
    fig = {k: r[k] for k in ("levels", "flat_speed_m_s", "samples")}
    fig.update({k: _num(r[k]) for k in ("flat_mu1", "flat_mu3", "r2_torque", "rmse_torque_Nm",
                                        "residual_rho", "levels_spread_rel", "thermistor_lag_s")})
    return fig


def _targets(res: Result, params: dict, truth: dict | None) -> dict:
    targets = {}
    if "mu" in res.results:
        targets["mu_r2>=0.985"] = bool(res.results["mu"]["r2"] >= TARGETS["r2"])
    if truth:
        for name in TARGET_PARAMETERS:
            if name in params and "within_3pct" in params[name]:
                targets[f"{SYMBOLS[name]} within 3%"] = params[name]["within_3pct"]
        for name in EDGE_PARAMETERS:
            if name in params and "within_5pct" in params[name]:
                targets[f"{SYMBOLS[name]} within 5%"] = params[name]["within_5pct"]
    # The runtime (TARGETS["runtime_s"]) is a figure, printed and in figures.json, not a target that sets the exit
    # code: a wall-clock time says how fast the host is, not what the code does (a loaded 2-core CI machine took
    # 82 s for what takes 33 s alone, issue 28)
    return targets


def figures(res: Result, command: str, truth: dict | None, true_path: str | None, calinfo: dict) -> dict:
    """Every number of the report (figures.json, without the plot list)."""
    params = _parameters(res, truth)
    fig = {
        "command": command, "data_dir": str(res.data_dir), "base_calibration": res.base.path,
        "true_parameters": true_path, "steps": list(res.results), "campaigns": res.campaigns,
        "runtime_s": {k: round(v, 3) for k, v in res.timings.items()},
        "parameters": params, "notes": res.notes, "calibration": calinfo,
        "settings": dict(vars(res.settings)) if res.settings else {},
    }
    if "mu" in res.results:
        fig["mu"] = _mu_figures(res, truth)
    if "thermal" in res.results:
        fig["thermal"] = _thermal_figures(res.results["thermal"])
    if "viscosity" in res.results:
        fig["viscosity"] = _viscosity_figures(res, truth)
    if "asperity" in res.results:
        fig["asperity"] = _asperity_figures(res.results["asperity"])
    for step in ("film", "static"):
        if step in res.results:
            fig[step] = {k: v for k, v in res.results[step].items() if k not in ("values", "ci95")}
    fig["exclusions"] = {"events": len(res.exclusions), "by_reason": _exclusion_summary(res.exclusions)}
    fig["targets"] = _targets(res, params, truth)
    return fig


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, set):
        return sorted(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def write_report(res: Result, out_dir: Path, command: str, truth: dict | None, true_path: str | None,
                 calinfo: dict, plots: bool = True) -> dict:
    """exclusions.csv, the plots, figures.json and report.md in out_dir, all or nothing (atomic.Staged; joins
    the caller's block); returns the figures."""
    out_dir = Path(out_dir)
    fig = figures(res, command, truth, true_path, calinfo)
    with Staged() as out:
        with out.open(out_dir / "exclusions.csv", newline="") as f:
            w = csv.DictWriter(f, fieldnames=EXCLUSION_COLUMNS, lineterminator="\n")
            w.writeheader()
            for e in res.exclusions:
                w.writerow(e.row())
        fig["plots"] = make_plots(res, out_dir, truth) if plots else []
        out.write_text(out_dir / "figures.json", json.dumps(fig, indent=2, default=_json_default) + "\n")
        out.write_text(out_dir / "report.md", markdown(res, fig))
    return fig


# ---------------------------------------------------------------------------
# report.md, one function per section

def _fmt_val(x) -> str:
    if x is None:
        return "-"
    return f"{x:.5g}"


def markdown(res: Result, fig: dict) -> str:
    L = _md_header(res, fig)
    if "mu" in fig:
        L += _md_mu(fig["mu"])
    if "thermal" in fig:
        L += _md_thermal(fig["thermal"], res.results["thermal"]["filter_half_width_s"])
    if "viscosity" in fig:
        L += _md_viscosity(fig["viscosity"])
    if "asperity" in fig:
        L += _md_asperity(fig["asperity"])
    if "film" in fig:
        L += _md_film(fig["film"], res.results["film"]["values"]["film_squeeze_factor"])
    if "static" in fig:
        L += _md_static(fig["static"], res.results["static"]["values"]["static_friction_factor"])
    L += _md_exclusions(fig)
    L += _md_output(res, fig)
    return "\n".join(L) + "\n"


def _md_header(res: Result, fig: dict) -> list[str]:
    """Title, command, data, the parameter table and the targets."""
    L = [f"# Identification from bench data: {', '.join(fig['steps'])}", "",
         f"Command: `{fig['command']}`  ",
         f"Data: `{fig['data_dir']}`; base calibration `{fig['base_calibration']}`"
         + (f"; true parameters `{fig['true_parameters']}`" if fig["true_parameters"] else "") + "  ",
         f"Identification time: {fig['runtime_s']['total']:.2f} s on {os.cpu_count()} CPU(s) ("
         + ", ".join(f"{k} {v:.2f} s" for k, v in fig["runtime_s"].items() if k != "total")
         + f"; the goal {TARGETS['runtime_s']:g} s is a figure, not a target: wall clock)", ""]
    for c in fig["campaigns"]:
        L.append(f"- campaign `{c['index']}`: {c['kind']}, {c['experiments']} experiment(s)")
    L += ["", "## Parameters", "",
          "| parameter | symbol | step | base | identified | 95 % CI (±) | true | error | target |",
          "|---|---|---|---|---|---|---|---|---|"]
    for name, p in fig["parameters"].items():
        err = f"{p['error_pct']:+.2f} %" if p.get("error_pct") is not None else "-"
        tgt = ("met" if p["within_3pct"] else "MISSED") + " (3 %)" if "within_3pct" in p else "-"
        L.append(f"| {name} | {p['symbol']} | {p['step']} | {_fmt_val(p['base'])} | {_fmt_val(p['identified'])} |"
                 f" {_fmt_val(p['ci95'])} | {_fmt_val(p.get('true'))} | {err} | {tgt} |")
    methods = "; ".join(f"{st}: {r['ci_method']}" for st, r in res.results.items() if "ci_method" in r)
    L += ["", "95 % confidence intervals from the Jacobian at the solution (" + methods + "). Cluster-robust"
          " means the sandwich covariance summed per experiment, which allows any correlation of the"
          " residuals within a run. They cover the noise, not the systematic effects discussed below"
          " (errors carried over from the viscosity curve and N, model error).", ""]
    if fig["targets"]:
        L += ["Targets: " + "; ".join(f"{k}: {'met' if v else 'MISSED'}" for k, v in fig["targets"].items()), ""]
    return L


def _md_mu(m: dict) -> list[str]:
    """The Coulomb friction coefficient section (eq. 17, 18)."""
    L = ["## Coulomb friction coefficient (eq. 17, 18)", "",
         "| | this fit | paper |", "|---|---|---|",
         f"| R² | {m['r2']:.4f} | {m['paper_r2']} |", f"| RMSE | {m['rmse']:.6f} | {m['paper_rmse']} |",
         f"| samples / experiments | {m['samples']} / {m['experiments']} | 184 experiments |",
         f"| on the Fig. 12 grid (5 rpm x 5 °C cell means, {m['grid_5rpm_5K']['cells']} cells) |"
         f" R² {m['grid_5rpm_5K']['r2']:.4f}, RMSE {m['grid_5rpm_5K']['rmse']:.6f} | |", "",
         "Each sample (10 ms bin of the measurement) gives mu_f by eq. 17 with the measured torque, slip and"
         " load-cell force, the viscous part removed with mu_v at the clutch temperature and h_bar at the"
         " measured force (eq. 9, 15, 16, with the asperity density of this calibration). The clutch"
         " temperature is the thermistor corrected for its first-order lag, theta_m + tau theta_m'"
         f" (tau = {m['thermistor_lag_s']:.4g} s, {m['thermistor_lag_source']}; theta_m' from a 0.5 s"
         " Savitzky-Golay derivative). Eq. 18 is fitted to the samples with"
         " scipy.optimize.least_squares (analytic Jacobian).", ""]
    sx = m["simex"]
    if sx.get("applied"):
        L += [f"Errors in variables: the slip is a regressor of eq. 18 and carries noise ({sx['slip_noise_rpm']:.3g}"
              " rpm on a sample after the moving average, estimated from the sample-to-sample differences);"
              " at the steep low-speed end this biases mu2 and v_s upward. SIMEX (refits with 0.5..2 times more"
              " noise added, quadratic extrapolation to no noise, on the"
              f" {sx['samples']} samples below 8 v_s with mu1, mu3 held) corrects mu2 by {sx['delta_mu2']:+.3g}"
              f" and v_s by {sx['delta_stribeck_speed']:+.3g} m/s (uncorrected: mu2"
              f" {m['without_simex']['mu2']:.5g}, v_s {m['without_simex']['stribeck_speed']:.5g} m/s).", ""]
    else:
        L += [f"No errors-in-variables (SIMEX) correction: {sx.get('why')}.", ""]
    if m.get("with_true_viscosity_and_N"):
        w = m["with_true_viscosity_and_N"]
        L += ["Where the errors come from: the same fit with the true viscosity curve and N (the viscous part"
              " of eq. 17 exact) gives " + ", ".join(f"{SYMBOLS[k]} {v:+.2f} %" for k, v in w.items())
              + ": the rest of the errors above is carried over from the identified viscosity and N.", ""]
    return L


def _md_thermal(t: dict, half_width_s: float) -> list[str]:
    """The thermal conductances section (eq. 19)."""
    L = ["## Thermal conductances (eq. 19)", "",
         f"Runs: {t['runs']} ({', '.join(map(str, t.get('ids', [])))}), {t['samples']} regression samples;"
         f" std of theta_oil - theta_housing {t['theta_oil_housing_spread_K']:.3g} K (what separates k1 from k2).",
         "",
         "Method: P = T dw (measured torque times slip; the signed product, unbiased under sensor noise),"
         " the thermistor temperatures and their derivatives all pass through the same modulating function"
         f" g(s) = (1-(s/H)²)³, H = {half_width_s:g} s: (g*x)' = g'*x and"
         " (g*x)'' = g''*x exactly, so eq. 19 holds exactly for the filtered signals and no noisy"
         " differencing is needed. Thermistor lag: every thermistor is a first-order lag"
         " (tau theta_m' + theta_m = theta), so theta = theta_m + tau theta_m'; substituted in eq. 19 this"
         " adds theta_m' and theta_m'' terms, and tau is estimated with k1 and k2 (nonlinear least squares"
         " started from the unconstrained linear regression)"
         + (" — here fixed by --thermistor-lag." if "fixed" in t["thermistor_lag_source"] else "."), "",
         "| | value |", "|---|---|",
         f"| thermistor lag tau | {t['thermistor_lag_s']:.4g} s (± {t['thermistor_lag_ci95']:.2g}), {t['thermistor_lag_source']} |",
         f"| heat capacity C | {t['heat_capacity_J_K']:.5g} J/K, {t['heat_capacity_source']} |",
         f"| eq. 19 fit | R² {t['r2_eq19']:.6f}, RMSE {t['rmse_eq19_W']:.4g} W |",
         f"| eq. 1 + lag simulated vs thermistor | RMSE {t['sim_rmse_K']:.4g} K |",
         f"| without the lag correction | k1 {t['without_lag_correction']['oil_conductance']:.5g},"
         f" k2 {t['without_lag_correction']['housing_conductance']:.5g} W/K |", "",
         "Bias that remains: the lag model is first order with one tau for the three thermistors; a sensor"
         " with a different dynamic would leave a bias of the order of the 'without the lag correction'"
         " row times the relative error of the lag model. With C from the calibration, an error in C goes"
         " into k1 and k2 through the theta' term (use --fit-heat-capacity to estimate C).", ""]
    return L


def _md_viscosity(v: dict) -> list[str]:
    """The viscosity section (eq. 2)."""
    L = ["## Viscosity (eq. 2)", "",
         f"{v['points']} points, {v['theta_range_degC'][0]:g}..{v['theta_range_degC'][1]:g} °C from `{v['source']}`;"
         " least squares on log(mu_v) (equal relative weight at every temperature).",
         f"R² {v['r2']:.6f}, RMSE {v['rmse_Pa_s']:.4g} Pa s, largest relative error {v['max_rel_error'] * 100:.2f} %"
         + (f"; the fitted curve is within {v['curve_max_rel_error_vs_true'] * 100:.2f} % of the true one over"
            " the range" if v.get("curve_max_rel_error_vs_true") is not None else "") + ".",
         "The four parameters of a double exponential are strongly correlated: individually they scatter"
         " more than the curve (which is what the model uses).", ""]
    return L


def _md_asperity(a: dict) -> list[str]:
    """The asperity density section."""
    L = ["## Asperity density N (from the viscous drag)", "",
         f"In the flat part of eq. 18 (v ≥ {a['flat_speed_m_s']:.3g} m/s, where e^(-v/v_s) is negligible)"
         " eq. 8 reads T/(R N_c) = mu1 F + mu1 mu3 F (theta-theta1)/theta2 + mu_v(theta) A_f v / h_bar(F):"
         " linear in mu1, mu1 mu3 and one 1/h_bar per applied force. One linear regression over all runs"
         " (temperature from the lag-corrected thermistor) gives h_bar at each force; inverting eq. 9 gives"
         " h and eq. 15 with p_c = F/A_f gives N per force; N is then fitted to the h_bar(F) points"
         " (weighted by their standard errors).", "",
         f"Drag regression: {a['samples']} samples, torque R² {a['r2_torque']:.5f}, RMSE {a['rmse_torque_Nm']:.3g} Nm;"
         f" it also gives mu1 = {a['flat_mu1']:.5g}, mu3 = {a['flat_mu3']:.5g} (a check on the eq. 18 fit).", "",
         "| force (N) | h_bar from the slope (µm) | ± (95 %) | h_bar(F; N fitted) (µm) | N from this level (1/m²) |",
         "|---|---|---|---|---|"]
    for lv in a["levels"]:
        L.append(f"| {lv['force_N']:.1f} | {lv['hbar_m'] * 1e6:.4f} | {lv['hbar_ci95_m'] * 1e6:.4f} |"
                 f" {lv['hbar_model_m'] * 1e6:.4f} | {lv['asperity_density']:.5g} |")
    spread = a["levels_spread_rel"]
    L += ["", "Accuracy: N's 95 % interval in the parameter table; spread of the per-force values"
          + (f" {spread * 100:.2f} %" if spread is not None else " (one force level only)")
          + ". h_bar changes by only about half the relative change of N (eq. 15 is steep in h), so N is"
          " about twice as uncertain as the drag slope; it also inherits the viscosity curve's error one"
          " to one (mu_v/h_bar is what the slope measures).", ""]
    return L


def _md_film(f: dict, phi: float) -> list[str]:
    """The squeeze-film section (DESIGN 9)."""
    L = ["## Squeeze-film factor phi (from the engagement transients)", "",
         "The torque of eq. 8 on the squeeze-film state (F_app = F_c(h_bar) + 3 pi phi mu_v K / (2 h_bar^3)"
         f" (-dh_bar/dt), K = {f['reynolds_factor_m4']:.5g} m^4), driven by the load cell, the slip and the observer"
         f" temperature, fitted to the measured torque from contact to contact + 0.3 s ({f['samples']} samples,"
         f" {f['substeps']} substeps per period): phi = {phi:.5g} ({f['ci_method']}).", "",
         f"Torque RMSE over the transients: {f['rmse_Nm']:.2f} Nm with the film state, {f['rmse_steady_Nm']:.2f} Nm"
         " with the steady film (eq. 16).", "",
         "| run | samples | largest transient error, steady (Nm) | with the film state (Nm) |", "|---|---|---|---|"]
    for r in f["runs"]:
        L.append(f"| {r['id']} | {r['samples']} | {r['transient_max_error_steady_Nm']:.1f} |"
                 f" {r['transient_max_error_film_Nm']:.1f} |")
    return L + [""]


def _md_static(f: dict, factor: float) -> list[str]:
    """The static friction section (DESIGN 9)."""
    L = ["## Static friction factor (from the breakaway runs)", "",
         "At breakaway the shaft torque equals the static capacity k_static mu_f(0, theta) R_eff N_c F_c; the torque"
         " is read on a line through the ramp's last 60 ms before it drops to the kinetic torque (the noisy maximum"
         " would be biased up)."
         f" k_static = {factor:.5g} ({f['ci_method']}; spread {f['spread_rel'] * 100:.2f} %).", "",
         "| run | force (N) | theta (degC) | torque at breakaway (Nm) | ramp (Nm/s) | k_static |", "|---|---|---|---|---|---|"]
    for r in f["runs"]:
        L.append(f"| {r['id']} | {r['force_N']:.1f} | {r['theta_degC']:.1f} | {r['torque_Nm']:.2f} |"
                 f" {r['ramp_Nm_s']:.1f} | {r['static_factor']:.5g} |")
    return L + [""]


def _md_exclusions(fig: dict) -> list[str]:
    """The exclusion rules and the summary table."""
    ex = fig["exclusions"]["by_reason"]
    st = fig["settings"]
    L = ["## Exclusions", "",
         f"Rules: slip (moving average over {st.get('smooth_slip_s')} s) below {st.get('slip_min_rpm')} rpm = stuck;"
         f" force below {st.get('force_min_N')} N = no contact; a load change is |dF/dt| > {st.get('force_rate_N_s')} N/s"
         f" (50 ms average), the film is taken as settled {st.get('film_settle_s')} s after it (and after the"
         " record start); NaN or empty cells exclude their row; a smoothing window needs valid samples on both"
         " sides.", "",
         f"{fig['exclusions']['events']} excluded stretches; every one is listed below and in exclusions.csv.", "",
         "| step | reason | meaning | stretches | samples | seconds | experiments |", "|---|---|---|---|---|---|---|"]
    for d in ex.values():
        L.append(f"| {d['step']} | {d['reason']} | {d['meaning']} | {d['events']} | {d['samples']} | {d['seconds']:g} |"
                 f" {d['experiments']} |")
    if not ex:
        L.append("| - | - | none | 0 | 0 | 0 | 0 |")
    return L


def _md_output(res: Result, fig: dict) -> list[str]:
    """Notes, the files written, and every exclusion."""
    L = []
    if res.notes:
        L += ["", "## Notes", ""] + [f"- {n}" for n in res.notes]
    c = fig["calibration"]
    L += ["", "## Output", "",
          f"- `{c['path']}`: the base calibration with the identified values (sources say so); accepted by"
          f" calibration.load, film LUT built from it: {c['lut_nodes']} nodes, max relative error"
          f" {c['lut_max_rel_error']:.3e}. Headers: `wetclutch lut {c['path']} --out DIR`.",
          "- `figures.json`: every number of this report; `exclusions.csv`: the exclusions."]
    for p in fig["plots"]:
        L.append(f"- ![{Path(p).stem}]({Path(p).name})")
    L += ["", "## Appendix: every exclusion", "", "| step | experiment | reason | t from (s) | t to (s) | samples |",
          "|---|---|---|---|---|---|"]
    for e in res.exclusions:
        t_from = f"{e.t_from_s:.3f}" if math.isfinite(e.t_from_s) else "-"
        t_to = f"{e.t_to_s:.3f}" if math.isfinite(e.t_to_s) else "-"
        L.append(f"| {e.step} | {e.experiment} | {e.reason} | {t_from} | {t_to} | {e.samples} |")
    return L
