"""Statistics of the fits: confidence intervals, R² and RMSE, residual autocorrelation, identifiability."""
from __future__ import annotations

import numpy as np
from scipy.stats import t as student_t

from .settings import IdentifyError


def _ar1_factor(residual: np.ndarray, groups: np.ndarray | None = None) -> tuple[float, float]:
    """Lag-1 autocorrelation rho of the residuals (within groups) and the variance factor (1+rho)/(1-rho)."""
    r = residual
    same = np.ones(r.size - 1, bool) if groups is None else (np.diff(groups) == 0)
    num = float(np.sum((r[:-1] * r[1:])[same]))
    den = float(np.sum(r * r))
    rho = min(max(num / den if den > 0 else 0.0, 0.0), 0.999)
    return rho, (1.0 + rho) / (1.0 - rho)


def confidence(jac: np.ndarray, residual: np.ndarray, groups=None, level: float = 0.95):
    """Half-widths of the confidence intervals from the Jacobian at the solution.

    With 10 or more groups (experiments): the cluster-robust (sandwich) covariance
    (J'J)^-1 (sum_g J_g' r_g r_g' J_g) (J'J)^-1 G/(G-1), which allows any correlation of the residuals
    within an experiment (lag-correction error, film state, sensor offsets), with a t quantile on G-1
    degrees of freedom. Otherwise the Gauss-Newton covariance s^2 (J'J)^-1 with s^2 inflated by
    (1+rho)/(1-rho) for the lag-1 autocorrelation rho of the residuals.
    Returns (half-widths, rho, covariance, method)."""
    n, p = jac.shape
    rho, factor = _ar1_factor(residual, groups)
    try:
        inv = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(p, np.inf), rho, np.full((p, p), np.inf), "singular"
    n_groups = 0 if groups is None else int(np.unique(groups).size)
    if n_groups >= 10:
        _, inv_idx = np.unique(groups, return_inverse=True)
        scores = np.zeros((n_groups, p))
        np.add.at(scores, inv_idx, jac * residual[:, None])
        cov = inv @ (scores.T @ scores) @ inv * n_groups / (n_groups - 1)
        q = float(student_t.ppf(0.5 + level / 2.0, n_groups - 1))
        method = f"cluster-robust over {n_groups} experiments"
    else:
        s2 = float(residual @ residual) / max(n - p, 1)
        cov = inv * s2 * factor
        n_eff = max(n / factor, p + 1.0)
        q = float(student_t.ppf(0.5 + level / 2.0, max(n_eff - p, 1.0)))
        method = f"Gauss-Newton, AR(1)-inflated (rho {rho:.3f})"
    return q * np.sqrt(np.abs(np.diag(cov))), rho, cov, method


def r2_rmse(y: np.ndarray, fit: np.ndarray) -> tuple[float, float]:
    """Coefficient of determination and root-mean-square error of a fit."""
    res = y - fit
    ss = float(np.sum((y - y.mean()) ** 2))
    return (1.0 - float(res @ res) / ss if ss > 0 else float("nan")), float(np.sqrt(np.mean(res * res)))


def check_identifiable(name: str, jac: np.ndarray, labels) -> None:
    """IdentifyError when the (column-normalised) regressors are collinear: the parameters are not determined."""
    sv = np.linalg.svd(jac / np.maximum(np.linalg.norm(jac, axis=0), 1e-300), compute_uv=False)
    if sv[-1] < 1e-8 * sv[0]:
        raise IdentifyError(f"{name}: parameters {', '.join(labels)} are not identifiable from this data"
                            f" (the regressors are collinear, condition {sv[0] / max(sv[-1], 1e-300):.3g})")
