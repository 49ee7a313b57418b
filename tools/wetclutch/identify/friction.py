"""Steps asperity and mu, on the friction runs (Table 2).

asperity  N from the viscous drag: in the flat part of eq. 18 (v >> v_s)
          T / (R N_c) = mu1 F + mu1 mu3 F (theta - theta1)/theta2
                        + mu_v(theta) A_f v / h_bar(F)
          is linear in mu1, mu1 mu3 and 1/h_bar per force level, so one linear
          regression over all runs gives h_bar at each applied force (the slope
          of torque against mu_v v). Eq. 9 and 15 then give N for each level
          in closed form, and N is fitted to the h_bar(F) points by weighted
          least squares. Without a known lag (asperity alone), tau is the
          value that minimises the regression's residual.
mu        eq. 17 samples (viscous part removed with mu_v at the lag-corrected
          temperature and h_bar at the measured force), eq. 18 fitted by
          scipy.optimize.least_squares; mu2 and v_s corrected for the slip
          noise (errors in variables) by SIMEX. The slip is a 0.1 s moving
          average (the stuck test needs it: the encoder noise alone would
          let stuck samples through).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, minimize_scalar

from ..reference import model
from ..calibration import Calibration
from ..reference.model import RAD_S_PER_RPM
from .campaign import stack
from .settings import IdentifyError, Settings
from .statistics import check_identifiable, confidence, r2_rmse

# h_bar(F) for many samples: model.FilmTable with 4001 nodes, within 3.4e-6 (relative) of the exact form
# (tests/python/test_model_film.py), far below the noise of the drag slope it is compared with
FILM_TABLE_NODES = 4001


def hbar_of_force(cal: Calibration, force_N):
    """h_bar(F/A_f) (eq. 9, 15, 16) from the dense film table of model.FilmTable (no per-sample bisection)."""
    return model.FilmTable(cal, FILM_TABLE_NODES).hbar_from_pressure_m(np.asarray(force_N, float) / cal.friction_area)


# ---------------------------------------------------------------------------
# Friction data

@dataclass
class FrictionData:
    t_s: np.ndarray
    slip_rpm: np.ndarray
    speed_m_s: np.ndarray
    force_N: np.ndarray
    torque_Nm: np.ndarray
    theta_m_degC: np.ndarray
    dtheta_m_K_s: np.ndarray
    experiment: np.ndarray          # index into ids
    level: np.ndarray               # force level index
    level_force_N: np.ndarray       # nominal force per level
    ids: list[str]
    slip_noise_bin_rpm: float = math.nan   # std of the noise on a bin's slip (for the SIMEX correction)

    def theta(self, tau: float) -> np.ndarray:
        """Surface temperature from the thermistor: theta_m + tau theta_m' (first-order lag)."""
        return self.theta_m_degC + tau * self.dtheta_m_K_s

    def subset(self, mask: np.ndarray) -> "FrictionData":
        return FrictionData(*(getattr(self, f)[mask] for f in ("t_s", "slip_rpm", "speed_m_s", "force_N", "torque_Nm",
                                                               "theta_m_degC", "dtheta_m_K_s", "experiment", "level")),
                            self.level_force_N, self.ids, self.slip_noise_bin_rpm)


def friction_data(prepared: list[dict], cal: Calibration, notes: list[str] | None = None) -> FrictionData:
    for p in prepared:
        if p["bins"]["t_s"].size == 0 and notes is not None:
            notes.append(f"friction: experiment {p['id']} has no usable sample (every sample excluded, see the"
                         " exclusions): it does not enter the fits")
    prepared = [p for p in prepared if p["bins"]["t_s"].size > 0]
    if not prepared:
        raise IdentifyError("friction: no usable samples in any experiment (see the exclusions)")
    d = stack(prepared, "bins")
    # force levels: the index's nominal force, else the experiment's median measured force (1 % clusters)
    nominal = []
    for i, p in enumerate(prepared):
        f = p["meta"].get("force_N")
        nominal.append(float(f) if isinstance(f, float) and math.isfinite(f) else
                       float(np.median(d["force_N"][d["experiment"] == i])))
    nominal = np.array(nominal)
    levels = []
    for f in sorted(nominal):
        if not levels or abs(f - levels[-1]) > 0.01 * levels[-1]:
            levels.append(f)
    levels = np.array(levels)
    level_of_exp = np.array([int(np.argmin(np.abs(levels - f))) for f in nominal])
    noise = [p["slip_noise_bin_rpm"] for p in prepared if math.isfinite(p["slip_noise_bin_rpm"])]
    return FrictionData(d["t_s"], d["slip_rpm"], cal.effective_radius * d["slip_rpm"] * RAD_S_PER_RPM,
                        d["force_N"], d["torque_Nm"], d["theta_m_degC"], d["dtheta_m_K_s"], d["experiment"],
                        level_of_exp[d["experiment"]], levels, [p["id"] for p in prepared],
                        float(np.median(noise)) if noise else math.nan)


def mu_samples(fd: FrictionData, cal: Calibration, tau: float) -> np.ndarray:
    """Eq. 17: mu_f = (T - R N_c mu_v(theta) A_f v / h_bar(F)) / (R N_c F)."""
    rn = cal.effective_radius * cal.friction_pairs
    theta = fd.theta(tau)
    viscous = rn * model.viscosity_Pa_s(cal, theta) * cal.friction_area * fd.speed_m_s / hbar_of_force(cal, fd.force_N)
    return (fd.torque_Nm - viscous) / (rn * fd.force_N)


def _eq18(p, v, theta, theta1, theta2):
    mu1, mu2, mu3, vs = p
    e = np.exp(-v / vs)
    stribeck = mu1 + (mu2 - mu1) * e
    g = 1.0 + mu3 * (theta - theta1) / theta2
    return stribeck * g, e, stribeck, g


# ---------------------------------------------------------------------------
# Step: mu (eq. 17, 18)

def _simex(fd: FrictionData, cal: Calibration, p: np.ndarray, tau: float, seed: int = 0) -> dict:
    """SIMEX correction of mu2 and v_s for the noise on the measured slip (a regressor of eq. 18).

    Noise on v biases a nonlinear fit (errors in variables): here v_s up and mu2 up, most at the steep
    low-speed end that carries their information. SIMEX adds more noise of known size (lambda times the
    noise already there), refits, and extrapolates the trend quadratically back to lambda = -1 (no noise).
    Done on the low-speed samples (v < 8 v_s) with mu1, mu3 held (the flat part fixes them and they do not
    move with the noise); the noise level comes from the data (robust sample-to-sample differences)."""
    sigma_rpm = fd.slip_noise_bin_rpm
    if not (math.isfinite(sigma_rpm) and sigma_rpm > 0):
        return {"applied": False, "why": "slip noise not estimable"}
    mu1, mu2, mu3, vs = p
    low = fd.speed_m_s < 8.0 * vs
    if low.sum() < 50:
        return {"applied": False, "why": "too few low-speed samples"}
    d = fd.subset(low)
    th1, th2 = cal.theta1, cal.theta2
    rn = cal.effective_radius * cal.friction_pairs
    theta = d.theta(tau)
    g = 1.0 + mu3 * (theta - th1) / th2
    t_per = d.torque_Nm / (rn * d.force_N)
    visc = model.viscosity_Pa_s(cal, theta) * cal.friction_area / hbar_of_force(cal, d.force_N) / (rn * d.force_N) * rn
    sigma_v = sigma_rpm * cal.effective_radius * RAD_S_PER_RPM

    def fit(v):
        y = t_per - visc * v          # eq. 17 with this v

        def fun(q):
            return (mu1 + (q[0] - mu1) * np.exp(-v / q[1])) * g - y
        return least_squares(fun, [mu2, vs], bounds=([0.0, 1e-5], [1.0, 1.0]), x_scale="jac").x

    rng = np.random.default_rng(seed)
    lams = (0.0, 0.5, 1.0, 1.5, 2.0)
    est = [fit(d.speed_m_s)]
    for lam in lams[1:]:
        est.append(np.mean([fit(d.speed_m_s + rng.normal(0.0, math.sqrt(lam) * sigma_v, d.speed_m_s.size))
                            for _ in range(4)], axis=0))
    est = np.array(est)
    extrap = np.array([np.polyval(np.polyfit(lams, est[:, j], 2), -1.0) for j in range(2)])
    delta = extrap - est[0]
    return {"applied": True, "slip_noise_rpm": sigma_rpm, "samples": int(low.sum()),
            "delta_mu2": float(delta[0]), "delta_stribeck_speed": float(delta[1]),
            "trend": {"lambda": list(lams), "mu2": est[:, 0].tolist(), "stribeck_speed": est[:, 1].tolist()}}


def identify_mu(fd: FrictionData, cal: Calibration, tau: float | None, tau_source: str = "given",
                simex: bool = True) -> dict:
    """Fit of eq. 18 to the eq. 17 samples; tau None: the thermistor lag is fitted with them."""
    n_exp = len(set(fd.experiment.tolist()))
    if n_exp < 2:
        raise IdentifyError(f"mu: {n_exp} usable experiment(s): eq. 18 needs runs at several temperatures"
                            " and speeds (the Table 2 campaign has 184)")
    vs0 = cal.stribeck_speed
    low = fd.speed_m_s < 3.0 * vs0
    if low.sum() < 20:
        raise IdentifyError(f"mu: {int(low.sum())} samples below {3 * vs0 / cal.effective_radius / RAD_S_PER_RPM:.3g}"
                            " rpm (3 v_s): mu2 and v_s are not identifiable (no low-speed ramp-down data?)")
    if np.ptp(fd.theta_m_degC) < 10.0:
        raise IdentifyError(f"mu: the temperature spans only {np.ptp(fd.theta_m_degC):.3g} K: mu3 is not identifiable")
    th1, th2 = cal.theta1, cal.theta2
    rn = cal.effective_radius * cal.friction_pairs
    v, F = fd.speed_m_s, fd.force_N
    hb = hbar_of_force(cal, F)
    visc_per_pa_s = rn * cal.friction_area * v / hb / (rn * F)     # mu_v -> its share of mu (eq. 17)
    T_per = fd.torque_Nm / (rn * F)
    free_tau = tau is None

    def split(q):
        return q[:4], (q[4] if free_tau else tau)

    def fun(q):
        p, tq = split(q)
        theta = fd.theta_m_degC + tq * fd.dtheta_m_K_s
        m, *_ = _eq18(p, v, theta, th1, th2)
        return m - (T_per - model.viscosity_Pa_s(cal, theta) * visc_per_pa_s)

    def jac(q):
        p, tq = split(q)
        mu1, mu2, mu3, vs = p
        theta = fd.theta_m_degC + tq * fd.dtheta_m_K_s
        m, e, stribeck, g = _eq18(p, v, theta, th1, th2)
        cols = [(1 - e) * g, e * g, stribeck * (theta - th1) / th2, (mu2 - mu1) * e * v / vs ** 2 * g]
        if free_tau:
            cols.append((stribeck * mu3 / th2 + model.viscosity_slope_Pa_s_per_K(cal, theta) * visc_per_pa_s) * fd.dtheta_m_K_s)
        return np.column_stack(cols)

    q0 = [cal.mu1, cal.mu2, cal.mu3, cal.stribeck_speed] + ([0.0] if free_tau else [])
    lo = [0.0, 0.0, -5.0, 1e-5] + ([0.0] if free_tau else [])
    hi = [1.0, 1.0, 5.0, 1.0] + ([20.0] if free_tau else [])
    res = least_squares(fun, q0, jac=jac, bounds=(lo, hi), x_scale="jac", xtol=1e-12, ftol=1e-12)
    p, tq = split(res.x)
    labels = ["mu1", "mu2", "mu3", "v_s"] + (["tau"] if free_tau else [])
    check_identifiable("mu (eq. 18)", res.jac, labels)
    ci, rho, cov, ci_method = confidence(res.jac, res.fun, fd.experiment)
    uncorrected = dict(zip(("mu1", "mu2", "mu3", "stribeck_speed"), map(float, p)))
    sx = _simex(fd, cal, np.array(p, float), float(tq)) if simex else {"applied": False, "why": "--no-simex"}
    if sx["applied"]:
        p = np.array(p, float)
        p[1] += sx["delta_mu2"]
        p[3] += sx["delta_stribeck_speed"]
    theta = fd.theta(tq)
    samples = mu_samples(fd, cal, tq)
    fitted, *_ = _eq18(p, v, theta, th1, th2)
    r2, rmse = r2_rmse(samples, fitted)
    names = ("mu1", "mu2", "mu3", "stribeck_speed")
    return {
        "values": dict(zip(names, map(float, p))),
        "ci95": dict(zip(names, map(float, ci[:4]))),
        "thermistor_lag_s": float(tq),
        "thermistor_lag_ci95": float(ci[4]) if free_tau else 0.0,
        "thermistor_lag_source": "fitted with eq. 18" if free_tau else tau_source,
        "r2": r2, "rmse": rmse, "residual_rho": rho, "ci_method": ci_method,
        "simex": sx, "without_simex": uncorrected,
        "samples": int(samples.size), "experiments": n_exp,
        "mu_samples": samples, "mu_fit": fitted, "theta_degC": theta,
    }


def mu_grid(r: dict, slip_step=5.0, theta_step=5.0) -> dict:
    """Fig. 12: averages over a 5 rpm x 5 degC grid, and R2/RMSE of the fit on the cell averages."""
    fd = r["fd"]
    i = np.floor(fd.slip_rpm / slip_step).astype(int)
    j = np.floor(r["theta_degC"] / theta_step).astype(int)
    key = i * 10000 + (j + 1000)
    uniq, inv = np.unique(key, return_inverse=True)
    cnt = np.bincount(inv)
    mean_mu = np.bincount(inv, weights=r["mu_samples"]) / cnt
    mean_fit = np.bincount(inv, weights=r["mu_fit"]) / cnt
    slip_c = (uniq // 10000 + 0.5) * slip_step
    theta_c = (uniq % 10000 - 1000 + 0.5) * theta_step
    r2, rmse = r2_rmse(mean_mu, mean_fit)
    return {"cells": int(uniq.size), "r2": r2, "rmse": rmse, "slip_rpm": slip_c, "theta_degC": theta_c,
            "mu": mean_mu, "count": cnt}


# ---------------------------------------------------------------------------
# Step: asperity density (eq. 8, 9, 15)

def identify_asperity(fd: FrictionData, cal: Calibration, tau: float | None, s: Settings,
                      tau_source: str = "given") -> dict:
    """h_bar per force level from the viscous slope in the flat-mu region, then N (eq. 9, 15).
    tau None: the thermistor lag is found by a bounded 1-D search on the regression's residual."""
    v_flat = max(s.flat_speed_m_s, 6.0 * cal.stribeck_speed)
    flat = fd.speed_m_s >= v_flat
    d = fd.subset(flat)
    if d.t_s.size < 50:
        raise IdentifyError(f"asperity: {d.t_s.size} samples above {v_flat:.3g} m/s (flat mu_f region): no drag data")
    rn = cal.effective_radius * cal.friction_pairs
    th1, th2 = cal.theta1, cal.theta2
    y = d.torque_Nm / rn
    used_levels = sorted(set(d.level.tolist()))
    labels = ["mu1", "mu1*mu3"] + [f"1/h_bar({fd.level_force_N[lv]:.0f} N)" for lv in used_levels]

    def design(tq):
        theta = d.theta(tq)
        cols = [d.force_N, d.force_N * (theta - th1) / th2]
        visc = model.viscosity_Pa_s(cal, theta) * cal.friction_area * d.speed_m_s
        for lv in used_levels:
            cols.append(np.where(d.level == lv, visc, 0.0))
        return np.column_stack(cols)

    def ssr(tq):
        A = design(tq)
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        r = A @ coef - y
        return float(r @ r)

    if tau is None:
        found = minimize_scalar(ssr, bounds=(0.0, 5.0), method="bounded", options={"xatol": 1e-3})
        tau, tau_source = float(found.x), "fitted in the drag regression"
    A = design(tau)
    check_identifiable("asperity (drag regression)", A, labels)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = A @ coef - y
    ci, rho, cov, ci_method = confidence(A, resid, d.experiment)
    r2, rmse = r2_rmse(y * rn, (A @ coef) * rn)
    g = coef[2:]
    g_se = np.sqrt(np.abs(np.diag(cov)[2:]))
    force_mean = np.array([float(np.mean(d.force_N[d.level == lv])) for lv in used_levels])
    hbar = 1.0 / g
    # closed form per level: h from h_bar (eq. 9, monotone), then N from eq. 15 at p_c = F/A_f
    n_level = np.array([_density_from_hbar(cal, hb, f / cal.friction_area) for hb, f in zip(hbar, force_mean)])

    def fun(logn):
        c = cal.with_values(asperity_density=math.exp(logn[0]))
        return (1.0 / hbar_of_force(c, force_mean) - g) / g_se

    start = math.log(np.exp(np.mean(np.log(n_level[np.isfinite(n_level)])))) if np.any(np.isfinite(n_level)) \
        else math.log(cal.asperity_density)
    res = least_squares(fun, [start], x_scale=[1.0], diff_step=1e-6)
    n_fit = math.exp(res.x[0])
    # CI: delta method on log N; chi2 scaled when the levels disagree more than their errors say
    j = res.jac[:, 0]
    dof = max(len(used_levels) - 1, 1)
    scale = max(float(res.fun @ res.fun) / dof, 1.0) if len(used_levels) > 1 else 1.0
    se_log = math.sqrt(scale / float(j @ j)) if float(j @ j) > 0 else float("inf")
    ci_n = 1.96 * se_log * n_fit
    hbar_model = hbar_of_force(cal.with_values(asperity_density=n_fit), force_mean)
    return {
        "values": {"asperity_density": n_fit},
        "ci95": {"asperity_density": ci_n},
        "levels": [{"force_N": float(f), "hbar_m": float(h), "hbar_ci95_m": float(1.96 * se / gg ** 2),
                    "hbar_model_m": float(hm), "asperity_density": float(nl)}
                   for f, h, se, gg, hm, nl in zip(force_mean, hbar, g_se, g, hbar_model, n_level)],
        "flat_mu1": float(coef[0]), "flat_mu3": float(coef[1] / coef[0]),
        "r2_torque": r2, "rmse_torque_Nm": rmse, "residual_rho": rho, "ci_method": ci_method,
        "samples": int(d.t_s.size), "flat_speed_m_s": v_flat, "thermistor_lag_s": tau,
        "thermistor_lag_source": tau_source,
        "levels_spread_rel": float(np.std(n_level) / np.mean(n_level)) if len(n_level) > 1 else float("nan"),
    }


def _density_from_hbar(cal: Calibration, hbar: float, pressure: float) -> float:
    """N from one (h_bar, p_c) pair: invert eq. 9 for h (bisection), then eq. 15 for N."""
    s = cal.roughness_rms
    lo, hi = -60.0 * s, 60.0 * s
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if float(model.film_thickness_m(cal, mid)) < hbar:
            lo = mid
        else:
            hi = mid
    h = 0.5 * (lo + hi)
    x = h / (math.sqrt(2.0) * s)
    shape = math.sqrt(math.pi / 2.0) * cal.youngs_modulus * cal.asperity_tip_radius * s * (
        math.exp(-x * x) - (h / s) * math.sqrt(math.pi / 2.0) * math.erfc(x))
    return pressure / shape if shape > 0 else float("nan")
