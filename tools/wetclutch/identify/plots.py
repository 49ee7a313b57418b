"""The identification plots (PNG), one function per figure: the paper's Fig. 11a-c and 12 for mu,
Fig. 13 style and eq. 19 for the thermal step, eq. 2 for the viscosity, h_bar(F) for the asperity density."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..reference import model
from ..util import plotting
from ..calibration import Calibration
from ..reference.model import RAD_S_PER_RPM
from .friction import hbar_of_force, mu_grid

if TYPE_CHECKING:
    from .result import Result

MU_SAMPLES_SHOWN = 30000        # mu samples drawn in Fig. 11a, 11b (a random subset: the files stay small)
MU_SAMPLES_SHOWN_3D = 8000      # ... and in Fig. 11c
EQ19_SAMPLES_SHOWN = 20000


def plots(res: Result, out_dir: Path, truth: dict | None) -> list[str]:
    """Every plot of the steps that ran; returns the files written."""
    out_dir = Path(out_dir)
    rng = np.random.default_rng(0)      # the subsets shown: the same plots for the same data
    files = []
    if "mu" in res.results:
        files += _mu_plots(res.cal, res.results["mu"], out_dir, rng)
    if "thermal" in res.results:
        files.append(_thermal_plot(res.results["thermal"], out_dir, rng))
    if "viscosity" in res.results:
        files.append(_viscosity_plot(res, truth, out_dir))
    if "asperity" in res.results:
        files.append(_asperity_plot(res, truth, out_dir))
    return files


# ---------------------------------------------------------------------------
# mu (Fig. 11, 12)

@dataclass
class _MuView:
    """What the mu figures share: the fit, a random subset of its samples and the fitted surface."""
    cal: Calibration
    r: dict                  # the mu step's result
    pick: np.ndarray         # indices of the samples shown
    vgrid: np.ndarray        # slip (rpm) for the fitted curves
    sg: np.ndarray           # slip x temperature grid of the fitted surface
    tg2: np.ndarray
    surf: np.ndarray

    @property
    def slip(self):
        return self.r["fd"].slip_rpm[self.pick]

    @property
    def theta(self):
        return self.r["theta_degC"][self.pick]

    @property
    def mu(self):
        return self.r["mu_samples"][self.pick]


def _mu_plots(cal: Calibration, r: dict, out_dir: Path, rng) -> list[str]:
    fd = r["fd"]
    n = r["mu_samples"].size
    pick = rng.choice(n, size=min(n, MU_SAMPLES_SHOWN), replace=False)
    theta = r["theta_degC"][pick]
    vgrid = np.linspace(0, max(fd.slip_rpm.max(), 1), 600)
    sg, tg2 = np.meshgrid(np.linspace(0, vgrid[-1], 40), np.linspace(theta.min(), theta.max(), 30))
    surf = model.friction_coefficient(cal, cal.effective_radius * sg * RAD_S_PER_RPM, tg2)
    view = _MuView(cal, r, pick, vgrid, sg, tg2, surf)
    return [_fig11a(view, out_dir), _fig11b(view, out_dir), _fig11c(view, out_dir), _fig12(view, out_dir)]


def _fig11a(v: _MuView, out_dir: Path) -> str:
    """Fig. 11a: mu_f against slip speed, coloured by temperature, fitted curves at 20..100 degC."""
    cal = v.cal
    f, axs = plotting.subplots(1, 2, figsize=(12, 4.8))
    for ax, xmax in zip(axs, (v.vgrid[-1], 30.0)):
        sc = ax.scatter(v.slip, v.mu, c=v.theta, s=1, cmap="coolwarm", rasterized=True)
        for th in (20, 40, 60, 80, 100):
            ax.plot(v.vgrid, model.friction_coefficient(cal, cal.effective_radius * v.vgrid * RAD_S_PER_RPM, th),
                    "k-", lw=0.8)
        ax.set_xlim(0, xmax)
        plotting.fit_y_to_x(ax)   # the Stribeck detail: the samples below 30 rpm, not all of them
        plotting.style(ax, "slip speed (rpm)", "mu_f (eq. 17)")
    axs[0].set_title(f"Fig. 11a: mu_f vs slip ({v.pick.size} of {v.r['mu_samples'].size} samples),"
                     " eq. 18 at 20..100 °C")
    axs[1].set_title("low-speed (Stribeck) detail")
    f.colorbar(sc, ax=axs[1], label="temperature (°C)")
    return plotting.save(f, out_dir / "fig11a_mu_vs_slip.png")


def _fig11b(v: _MuView, out_dir: Path) -> str:
    """Fig. 11b: mu_f against temperature, coloured by slip."""
    f, ax = plotting.subplots(figsize=(7.5, 4.8))
    theta = v.theta
    sc = ax.scatter(theta, v.mu, c=v.slip, s=1, cmap="viridis", rasterized=True)
    tg = np.linspace(theta.min(), theta.max(), 100)
    ax.plot(tg, model.friction_coefficient(v.cal, 1.0, tg), "k-", lw=1, label="eq. 18, flat (v >> v_s)")
    ax.plot(tg, model.friction_coefficient(v.cal, 0.0, tg), "k--", lw=1, label="eq. 18, v = 0")
    plotting.style(ax, "clutch temperature (°C)", "mu_f (eq. 17)", "Fig. 11b: mu_f vs temperature", legend=True)
    f.colorbar(sc, ax=ax, label="slip (rpm)")
    return plotting.save(f, out_dir / "fig11b_mu_vs_temperature.png")


def _fig11c(v: _MuView, out_dir: Path) -> str:
    """Fig. 11c: the samples in 3D and the fitted surface."""
    r = v.r
    f = plotting.figure(figsize=(8, 6))
    ax = f.add_subplot(projection="3d")
    few = v.pick[:MU_SAMPLES_SHOWN_3D]
    ax.scatter(r["fd"].slip_rpm[few], r["theta_degC"][few], r["mu_samples"][few], s=1, c="tab:blue", alpha=0.3)
    ax.plot_wireframe(v.sg, v.tg2, v.surf, color="k", lw=0.4)
    ax.set_zlabel("mu_f")
    plotting.style(ax, "slip (rpm)", "temperature (°C)",
                   f"Fig. 11c: samples and eq. 18 (R² {r['r2']:.4f}, RMSE {r['rmse']:.5f})", grid=None)
    return plotting.save(f, out_dir / "fig11c_mu_surface.png")


def _fig12(v: _MuView, out_dir: Path) -> str:
    """Fig. 12: 5 rpm x 5 degC cell means with the fitted surface, and their residuals."""
    cal = v.cal
    g = mu_grid(v.r)
    f = plotting.figure(figsize=(13, 5.5))
    ax = f.add_subplot(1, 2, 1, projection="3d")
    ax.scatter(g["slip_rpm"], g["theta_degC"], g["mu"], c=g["mu"], cmap="viridis", s=8)
    ax.plot_wireframe(v.sg, v.tg2, v.surf, color="k", lw=0.3)
    ax.set_zlabel("mu_f")
    plotting.style(ax, "slip (rpm)", "temperature (°C)", "Fig. 12: cell means (5 rpm x 5 °C) and eq. 18", grid=None)
    ax = f.add_subplot(1, 2, 2)
    fit_cells = model.friction_coefficient(cal, cal.effective_radius * g["slip_rpm"] * RAD_S_PER_RPM,
                                           g["theta_degC"])
    residual = g["mu"] - fit_cells
    reach = float(np.nanmax(np.abs(residual)))   # the colour scale fitted to the residuals, centred on 0
    sc = ax.scatter(g["slip_rpm"], g["theta_degC"], c=residual, cmap="RdBu_r", s=14, vmin=-reach, vmax=reach)
    plotting.style(ax, "slip (rpm)", "temperature (°C)",
                   f"cell mean - eq. 18 (grid R² {g['r2']:.4f}, RMSE {g['rmse']:.5f})", grid=None)
    f.colorbar(sc, ax=ax, label="mu_f residual")
    return plotting.save(f, out_dir / "fig12_mu_grid.png")


# ---------------------------------------------------------------------------
# thermal, viscosity, asperity

def _thermal_plot(r: dict, out_dir: Path, rng) -> str:
    """Fig. 13 style: each run's thermistor against eq. 1 + lag simulated; eq. 19 after filtering."""
    k = len(r["sim"])
    f, axs = plotting.subplots(k + 1, 1, figsize=(10, 3.0 * (k + 1)))
    axs = np.atleast_1d(axs)
    for ax, (tt, meas, sim), ident in zip(axs, r["sim"], r.get("ids", [""] * k)):
        ax.plot(tt, meas, lw=0.8, label="thermistor (measured)")
        ax.plot(tt, sim, lw=0.8, label="eq. 1 + lag, identified k1, k2")
        plotting.style(ax, "time (s)", "°C", f"Fig. 13 style: {ident}: RMSE {np.sqrt(np.mean((meas - sim) ** 2)):.3f} K",
                       legend={"loc": "best"})
    ax = axs[-1]
    sel = rng.choice(r["lhs"].size, size=min(r["lhs"].size, EQ19_SAMPLES_SHOWN), replace=False)
    ax.scatter(r["rhs"][sel], r["lhs"][sel], s=1)
    lim = [min(r["rhs"].min(), r["lhs"].min()), max(r["rhs"].max(), r["lhs"].max())]
    ax.plot(lim, lim, "k-", lw=0.8)
    plotting.style(ax, "k1 (theta-theta_oil) + k2 (theta-theta_housing)  (W)", "T dw - C dtheta/dt  (W)",
                   f"eq. 19, filtered: R² {r['r2_eq19']:.5f}")
    return plotting.save(f, out_dir / "thermal_eq19.png")


def _viscosity_plot(res: Result, truth: dict | None, out_dir: Path) -> str:
    """Eq. 2: the points, the fit, the base calibration's curve (and the true one)."""
    r = res.results["viscosity"]
    th = np.linspace(*r["theta_range_degC"], 200)
    f, ax = plotting.subplots(figsize=(7, 4.5))
    ax.semilogy(r["data"]["theta_degC"], r["data"]["viscosity_Pa_s"] * 1e3, "o", label="data")
    ax.semilogy(th, model.viscosity_Pa_s(res.base.with_values(**r["values"]), th) * 1e3, "-", label="eq. 2 fit")
    ax.semilogy(th, model.viscosity_Pa_s(res.base, th) * 1e3, ":", label="base calibration")
    if truth and all(n in truth for n in ("mv1", "mv2", "mv3", "mv4")):
        tc = res.base.with_values(**{n: truth[n] for n in ("mv1", "mv2", "mv3", "mv4")})
        ax.semilogy(th, model.viscosity_Pa_s(tc, th) * 1e3, "--", label="true")
    plotting.style(ax, "temperature (°C)", "viscosity (mPa s)",
                   f"eq. 2: R² {r['r2']:.5f}, max rel. error {r['max_rel_error'] * 100:.2f} %", legend=True, grid="both")
    return plotting.save(f, out_dir / "viscosity_eq2.png")


def _asperity_plot(res: Result, truth: dict | None, out_dir: Path) -> str:
    """h_bar from the drag slope per force level against h_bar(F) with the fitted, base (and true) N."""
    r = res.results["asperity"]
    lv = r["levels"]
    F = np.array([x["force_N"] for x in lv])
    fg = np.linspace(F.min() * 0.8, F.max() * 1.2, 100)
    f, ax = plotting.subplots(figsize=(7, 4.5))
    ax.errorbar(F, [x["hbar_m"] * 1e6 for x in lv], yerr=[x["hbar_ci95_m"] * 1e6 for x in lv], fmt="o",
                label="h_bar from the drag slope (95 %)")
    ax.plot(fg, hbar_of_force(res.base.with_values(asperity_density=r["values"]["asperity_density"]), fg) * 1e6,
            "-", label=f"eq. 9/15, N = {r['values']['asperity_density']:.4g}")
    ax.plot(fg, hbar_of_force(res.base, fg) * 1e6, ":", label=f"base N = {res.base.asperity_density:.4g}")
    if truth and "asperity_density" in truth:
        ax.plot(fg, hbar_of_force(res.base.with_values(asperity_density=truth["asperity_density"]), fg) * 1e6,
                "--", label=f"true N = {truth['asperity_density']:.4g}")
    plotting.style(ax, "applied force (N)", "h_bar (µm)", "average film thickness from the viscous drag", legend=True)
    return plotting.save(f, out_dir / "asperity_hbar.png")
