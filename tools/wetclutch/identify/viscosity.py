"""Step viscosity: eq. 2 fitted to the (theta, mu_v) points of viscosity.csv, relative (log) residuals."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from ..calibration import Calibration
from .campaign import VISCOSITY_COLUMNS, read_table
from .settings import IdentifyError
from .signals import Exclusion
from .statistics import confidence, r2_rmse


def identify_viscosity(path: Path, cal: Calibration, log: list[Exclusion]) -> dict:
    cols = read_table(Path(path), VISCOSITY_COLUMNS)
    th, mu = cols["theta_degC"], cols["viscosity_Pa_s"]
    bad = ~(np.isfinite(th) & np.isfinite(mu) & (mu > 0))
    for k in np.flatnonzero(bad):
        log.append(Exclusion("viscosity", f"{Path(path).name} line {k + 2}", "viscosity_row",
                             float(th[k]), float(th[k]), 1))
    th, mu = th[~bad], mu[~bad]
    if th.size < 6:
        raise IdentifyError(f"{path}: {th.size} usable (theta, viscosity) points; eq. 2 has 4 parameters,"
                            " at least 6 points over the temperature range are needed")
    if np.ptp(th) < 30.0:
        raise IdentifyError(f"{path}: the points span {np.ptp(th):.3g} K; eq. 2 (two exponentials) needs"
                            " at least 30 K")
    if np.median(mu) > 5.0:
        raise IdentifyError(f"{path}: median viscosity {np.median(mu):.4g}: column viscosity_Pa_s looks like"
                            " mPa*s, expected Pa*s")
    p0 = np.array([cal.mv1, cal.mv2, cal.mv3, cal.mv4])

    def fun(p):
        return np.log(p[0] * np.exp(p[1] * th) + p[2] * np.exp(p[3] * th)) - np.log(mu)

    best = None
    starts = [p0, np.array([p0[0] * 2, p0[1] * 1.5, p0[2] * 0.5, p0[3] * 0.7]),
              np.array([p0[0] * 0.5, p0[1] * 0.7, p0[2] * 2, p0[3] * 1.3])]
    for start in starts:
        r = least_squares(fun, start, bounds=([0, -1, 0, -1], [10, 0.1, 10, 0.1]), x_scale="jac",
                          xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=5000)
        if best is None or r.cost < best.cost:
            best = r
    p, jac = best.x.copy(), best.jac
    if p[1] > p[3]:   # the steeper exponential first, as in the paper's table
        p, jac = p[[2, 3, 0, 1]], jac[:, [2, 3, 0, 1]]
    fit = p[0] * np.exp(p[1] * th) + p[2] * np.exp(p[3] * th)
    r2, rmse = r2_rmse(mu, fit)
    ci, _, _, ci_method = confidence(jac, fun(p))
    return {
        "values": {"mv1": p[0], "mv2": p[1], "mv3": p[2], "mv4": p[3]},
        "ci95": {"mv1": ci[0], "mv2": ci[1], "mv3": ci[2], "mv4": ci[3]},
        "r2": r2, "rmse_Pa_s": rmse, "max_rel_error": float(np.max(np.abs(fit / mu - 1.0))), "ci_method": ci_method,
        "points": int(th.size), "theta_range_degC": [float(th.min()), float(th.max())],
        "data": {"theta_degC": th, "viscosity_Pa_s": mu},
        "source": str(path),
    }
