"""Signal processing of one record: filters, segmenting, the exclusion rules.

Samples a step cannot use are excluded by rule, and every exclusion is counted
and named (experiment, reason, time range): non-finite values, the edges of
records and NaN stretches (the temperature derivative is undefined there),
slip below a threshold (the clutch is stopped or stuck and the measured torque
is static friction, which eq. 17 does not describe), no contact force, and the
squeeze-film transient after every load change. The two reductions at the end
(prepare_friction, prepare_thermal) turn one record into what the steps use;
they run in worker processes (campaign.prepare_campaign).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import fftconvolve, savgol_filter

from ..reference.model import RAD_S_PER_RPM
from .settings import Settings

# ---------------------------------------------------------------------------
# Exclusions

REASONS = {
    "missing_file": "measurement file listed in the index does not exist",
    "nan": "non-finite value (NaN stretch) in a needed column",
    "edge": "within half a smoothing window of a record edge or NaN stretch (temperature derivative undefined)",
    "short": "segment shorter than the smoothing window",
    "static": "slip below the threshold: clutch stopped or stuck, the torque is static friction (eq. 17 does not apply)",
    "no_contact": "load-cell force below the contact threshold",
    "film": "squeeze-film transient after a load change or at the record start (eq. 16 steady film not reached)",
    "viscosity_row": "viscosity.csv row with a non-finite or non-positive value",
}


@dataclass
class Exclusion:
    step: str
    experiment: str
    reason: str
    t_from_s: float
    t_to_s: float
    samples: int
    seconds: float = 0.0

    def row(self) -> dict:
        return {"step": self.step, "experiment": self.experiment, "reason": self.reason,
                "t_from_s": round(self.t_from_s, 4), "t_to_s": round(self.t_to_s, 4), "samples": self.samples,
                "seconds": round(self.seconds, 4)}


def _runs(mask: np.ndarray):
    """(start, stop) index pairs of the True runs of a boolean array."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _exclusions_from_codes(step: str, exp_id: str, t: np.ndarray, codes: np.ndarray, names: list[str], dt: float):
    """One Exclusion per contiguous run of the same non-zero code."""
    out = []
    if codes.size == 0:
        return out
    change = np.flatnonzero(np.diff(codes)) + 1
    starts = np.concatenate([[0], change])
    stops = np.concatenate([change, [codes.size]])
    tt = np.where(np.isfinite(t), t, np.nan)
    for a, b in zip(starts, stops):
        c = int(codes[a])
        if c == 0:
            continue
        seg = tt[a:b]
        finite = seg[np.isfinite(seg)]
        lo = float(finite[0]) if finite.size else float("nan")
        hi = float(finite[-1]) if finite.size else float("nan")
        out.append(Exclusion(step, exp_id, names[c], lo, hi, int(b - a), float((b - a) * dt)))
    return out


# ---------------------------------------------------------------------------
# Filters

def _odd_window(seconds: float, dt: float, polyorder: int) -> int:
    n = max(int(round(seconds / dt)), polyorder + 2)
    return n + 1 if n % 2 == 0 else n


def _segment_smooth(x: np.ndarray, valid: np.ndarray, window: int, polyorder: int, derivs, dt: float):
    """Savitzky-Golay per valid segment; returns (arrays per deriv, interior mask, short mask)."""
    outs = [np.full(x.shape, np.nan) for _ in derivs]
    interior = np.zeros(x.shape, bool)
    short = np.zeros(x.shape, bool)
    half = window // 2
    for a, b in _runs(valid):
        if b - a < window + 2:
            short[a:b] = True
            continue
        for o, d in zip(outs, derivs):
            o[a:b] = savgol_filter(x[a:b], window, polyorder, deriv=d, delta=dt, mode="interp")
        interior[a + half:b - half] = True
    return outs, interior, short


def _moving_average(x: np.ndarray, valid: np.ndarray, n: int) -> np.ndarray:
    """Centred moving average over n samples of the valid ones (NaN where none is valid); n odd keeps it
    centred (np.convolve 'same' with an even n is off by half a sample)."""
    if n <= 1:
        return np.where(valid, x, np.nan)
    w = np.ones(n)
    cnt = np.convolve(valid.astype(float), w, "same")
    tot = np.convolve(np.where(valid, x, 0.0), w, "same")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(valid & (cnt > 0), tot / cnt, np.nan)


def _kernel_filter(x: np.ndarray, valid: np.ndarray, half_s: float, dt: float, derivs):
    """Modulating-function filter: x convolved with g(s) = (1 - (s/H)^2)^3 on [-H, H] (unit area), and with
    g' and g'' for the first and second derivatives. g and g' vanish at +-H, so by parts
    (g * x') = (g' * x) and (g * x'') = (g'' * x) exactly: a linear ODE such as eq. 1 holds exactly for
    the filtered signals, and the derivatives of noisy data come without differencing.
    Returns (arrays per deriv, interior mask, short mask); per valid segment, H trimmed at both ends."""
    m = max(int(round(half_s / dt)), 2)
    s = np.arange(-m, m + 1) * dt
    u = s / (m * dt)
    g0 = (1.0 - u * u) ** 3
    area = g0.sum() * dt
    kernels = {0: g0 / area,
               1: -6.0 * u * (1.0 - u * u) ** 2 / (m * dt) / area,
               2: (-6.0 * (1.0 - u * u) ** 2 + 24.0 * u * u * (1.0 - u * u)) / (m * dt) ** 2 / area}
    outs = [np.full(x.shape, np.nan) for _ in derivs]
    interior = np.zeros(x.shape, bool)
    short = np.zeros(x.shape, bool)
    for a, b in _runs(valid):
        if b - a < 2 * m + 3:
            short[a:b] = True
            continue
        for o, d in zip(outs, derivs):
            # a true convolution (the kernel flipped): sum_j x[k - j] K[j] dt = integral g(s) x(t - s) ds
            o[a + m:b - m] = fftconvolve(x[a:b], kernels[d] * dt, mode="valid")
        interior[a + m:b - m] = True
    return outs, interior, short


def _load_changes(force: np.ndarray, dt: float, s: Settings) -> np.ndarray:
    """Samples inside a load change or within film_settle_s after one. The record start and the end of
    a gap in the force are treated as load changes too (the film state is unknown there)."""
    n = force.size
    ok = np.isfinite(force)
    w = 2 * int(round(0.05 / dt / 2.0)) + 1
    avg = _moving_average(force, ok, w)
    rate = np.zeros(n)
    for a, b in _runs(ok):
        if b - a > 1:
            rate[a:b] = np.abs(np.gradient(avg[a:b], dt))
    changing = rate > s.force_rate_N_s
    changing[[a for a, _ in _runs(ok)]] = True
    settle = int(round(s.film_settle_s / dt))
    # extend every changing sample forward by the settle time
    idx = np.flatnonzero(changing)
    mark = np.zeros(n + 1, int)
    np.add.at(mark, idx, 1)
    np.add.at(mark, np.minimum(idx + settle + 1, n), -1)
    return np.cumsum(mark[:n]) > 0


# ---------------------------------------------------------------------------
# One record reduced to the samples of a step

FRICTION_CODES = ["", "nan", "short", "edge", "static", "no_contact", "film"]


def prepare_friction(exp_id, t, cols, valid, dt, effective_radius, s: Settings) -> dict:
    slip, force, torque, theta = cols["slip_rpm"], cols["force_N"], cols["torque_Nm"], cols["theta_clutch_degC"]
    window = _odd_window(s.smooth_friction_s, dt, 2)
    (theta_sm, dtheta), interior, short = _segment_smooth(theta, valid, window, 2, (0, 1), dt)
    sign = np.where(np.nansum(slip) < 0, -1.0, 1.0)     # the record's slip direction
    n_avg = 2 * int(round(s.smooth_slip_s / dt / 2.0)) + 1     # odd: an even window shifts by half a sample
    slip_avg = _moving_average(slip * sign, valid, n_avg)
    # stuck: the averaged slip below the threshold, widened by half the averaging window so that the
    # average is only used where it does not straddle the lock (a moving average is biased at the kink)
    stuck = ~(slip_avg >= s.slip_min_rpm)
    if n_avg > 1:
        stuck = np.convolve(stuck.astype(float), np.ones(2 * (n_avg // 2) + 1), "same") > 0
    film = _load_changes(force, dt, s)
    # one reason per sample, the first that applies: nan > short > static > no_contact > film > edge
    codes = np.zeros(t.size, np.int8)
    codes[valid & ~interior] = 3
    codes[film] = 6
    codes[force < s.force_min_N] = 5
    codes[stuck] = 4
    codes[short] = 2
    codes[~valid] = 1
    use = codes == 0
    # slip noise: robust sample-to-sample differences over the slipping samples (a smooth signal adds
    # only its slope to the differences, which the median removes)
    dif = np.diff(slip[use])[np.diff(np.flatnonzero(use)) == 1] if use.sum() > 2 else np.zeros(0)
    slip_noise = float(1.4826 * np.median(np.abs(dif - np.median(dif))) / math.sqrt(2.0)) if dif.size > 20 else math.nan
    k = np.floor((t - t[0]) / s.bin_s + 1e-6).astype(np.int64)
    k = k[use]
    # bins of consecutive usable samples: average; a bin never spans excluded samples
    breaks = np.concatenate([[True], (np.diff(k) != 0) | (np.diff(np.flatnonzero(use)) != 1)]) if k.size else \
        np.zeros(0, bool)   # no usable sample: no bin
    group = np.cumsum(breaks) - 1
    count = np.bincount(group).astype(float)

    def mean(x):
        return np.bincount(group, weights=x[use]) / count if count.size else np.zeros(0)

    return {
        "bins": {
            "t_s": mean(t), "slip_rpm": mean(slip_avg), "force_N": mean(force),
            "torque_Nm": mean(torque * sign), "theta_m_degC": mean(theta), "dtheta_m_K_s": mean(dtheta),
            "count": count,
        },
        "exclusions": [e.row() for e in _exclusions_from_codes("friction", exp_id, t, codes, FRICTION_CODES, dt)],
        "used_samples": int(use.sum()),
        # the noise left on a bin's slip: a moving average of n_avg white samples, averaged over the bin
        "slip_noise_rpm": slip_noise,
        "slip_noise_bin_rpm": slip_noise * math.sqrt(float(np.sum(np.convolve(
            np.ones(n_avg) / n_avg, np.ones(max(int(round(s.bin_s / dt)), 1)) / max(int(round(s.bin_s / dt)), 1)) ** 2))),
    }


THERMAL_CODES = ["", "nan", "short", "edge"]


def prepare_thermal(exp_id, t, cols, valid, dt, s: Settings) -> dict:
    # heat input T dw (W): the signed product is unbiased under speed and torque noise (|T dw| is not
    # where the slip is near zero); the sign convention of the record is taken from its mean
    product = cols["torque_Nm"] * cols["slip_rpm"] * RAD_S_PER_RPM
    power = product * (1.0 if np.nansum(product) >= 0 else -1.0)
    half = s.smooth_thermal_s
    (th_f, d1, d2), interior, short = _kernel_filter(cols["theta_clutch_degC"], valid, half, dt, (0, 1, 2))
    (p_f,), _, _ = _kernel_filter(power, valid, half, dt, (0,))
    (oil_f, oil_d1), _, _ = _kernel_filter(cols["theta_oil_degC"], valid, half, dt, (0, 1))
    (hou_f, hou_d1), _, _ = _kernel_filter(cols["theta_housing_degC"], valid, half, dt, (0, 1))
    codes = np.zeros(t.size, np.int8)
    codes[valid & ~interior] = 3
    codes[short] = 2
    codes[~valid] = 1
    stride = max(int(round(s.thermal_step_s / dt)), 1)
    use = np.flatnonzero(codes == 0)
    use = use[::stride]
    # raw series, averaged over stride-long blocks, for the output-error check (simulation of eq. 1)
    nb = t.size // stride
    blk = slice(0, nb * stride)

    def block(x):
        return x[blk].reshape(nb, stride).mean(axis=1)
    seg = np.concatenate([[0], np.cumsum(np.diff(use) > stride)]) if use.size else np.zeros(0, int)
    return {
        "regression": {"t_s": t[use], "power_W": p_f[use], "theta_m_degC": th_f[use], "dtheta_K_s": d1[use],
                       "d2theta_K_s2": d2[use], "theta_oil_degC": oil_f[use], "theta_housing_degC": hou_f[use],
                       "dtheta_oil_K_s": oil_d1[use], "dtheta_housing_K_s": hou_d1[use], "segment": seg},
        "series": {"t_s": block(t), "power_W": block(power), "theta_m_degC": block(cols["theta_clutch_degC"]),
                   "theta_oil_degC": block(cols["theta_oil_degC"]), "theta_housing_degC": block(cols["theta_housing_degC"])},
        "exclusions": [e.row() for e in _exclusions_from_codes("thermal", exp_id, t, codes, THERMAL_CODES, dt)],
        "used_samples": int((codes == 0).sum()),
    }
