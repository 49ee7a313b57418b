"""The bench's true clutch in closed form and its squeeze film by the Reynolds force balance (DESIGN 9)."""
from __future__ import annotations

import math

import numpy as np
from scipy.special import erf, erfc

from ...calibration import Calibration
from ...reference import model


def film_constant_m4(cal: Calibration) -> float:
    """K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri) (m^4): Reynolds' squeeze film between parallel annular plates.

    The two terms nearly cancel for a narrow annulus (here K / (Ro^4 - Ri^4) = 0.0036, about 2.5 digits
    lost). With u = ln(Ro/Ri), Ro^2 + Ri^2 = 2 Ro Ri cosh u and Ro^2 - Ri^2 = 2 Ro Ri sinh u, so
    K = (Ro^2 - Ri^2) 2 Ro Ri (cosh u - sinh u / u), and cosh u - sinh u / u = sum_n>=1 2n u^2n / (2n+1)!
    has only positive terms: no cancellation (matches a 50-digit evaluation to 1e-15). For a wide annulus
    (u > 1, no cancellation to fear) the direct form.
    """
    ro, ri = cal.outer_radius, cal.inner_radius
    u = math.log(ro / ri)
    if u > 1.0:
        return ro ** 4 - ri ** 4 - (ro * ro - ri * ri) ** 2 / u
    total, term, n = 0.0, 1.0, 0
    while True:
        n += 1
        term *= u * u / ((2 * n) * (2 * n + 1))          # u^2n / (2n+1)!
        if 2 * n * term <= 1e-18 * total:
            break
        total += 2 * n * term
    return (ro - ri) * (ro + ri) * 2.0 * ro * ri * total


class _Physics:
    """The true clutch in closed form (eq. 2, 8, 9, 15, 18) and the squeeze film (DESIGN 9), constants
    precomputed for the loop."""

    def __init__(self, cal: Calibration, dt: float, actuator_time_constant_s: float, substeps: int):
        s = cal.roughness_rms
        self.s = s
        self.inv_s_sqrt2 = 1.0 / (math.sqrt(2.0) * s)
        self.pc_k = math.sqrt(math.pi / 2.0) * cal.youngs_modulus * cal.roughness_parameter   # eq. 15
        self.sqrt_pi_2 = math.sqrt(math.pi / 2.0)
        self.hbar_k = s / math.sqrt(2.0 * math.pi)                                            # eq. 9
        self.area = cal.friction_area
        self.rn = cal.effective_radius * cal.friction_pairs
        self.r_eff = cal.effective_radius
        self.mu1, self.dmu, self.vs = cal.mu1, cal.mu2 - cal.mu1, cal.stribeck_speed
        self.mu2 = cal.mu2
        self.mu3_th2, self.th1 = cal.mu3 / cal.theta2, cal.theta1
        self.mv = (cal.mv1, cal.mv2, cal.mv3, cal.mv4)
        self.static_factor = cal.static_friction_factor
        # The squeeze film: dh/dt = rate_k / mu_v * (F_c(h) - F_app) * h_bar^3 / (1 + erf x).
        self.phi = cal.film_squeeze_factor
        self.K = film_constant_m4(cal)
        self.rate_k = 4.0 / (3.0 * math.pi * self.phi * self.K) if self.phi > 0.0 else 0.0
        self.pc_area = self.area * self.pc_k
        self.pc_lin = self.sqrt_pi_2 / s
        self.h_min, self.h_max, _, _ = model.film_domain(cal)
        self.substeps = int(substeps)
        self.hh = dt / self.substeps
        # the actuator force within a step, exactly: F = F_cmd + (F_app - F_cmd) e^(-s/tau_a) at s = j hh / 2
        self.act_decay = [math.exp(-j * 0.5 * self.hh / actuator_time_constant_s) for j in range(2 * self.substeps + 1)]

    def viscosity(self, theta):
        mv1, mv2, mv3, mv4 = self.mv
        return mv1 * np.exp(mv2 * theta) + mv3 * np.exp(mv4 * theta)                       # eq. 2

    def clutch(self, h, w_abs, theta):
        """(|T|, |T_c|, |T_v|, F_c, h_bar, static capacity) for separation h and |slip|."""
        x = h * self.inv_s_sqrt2
        ex = np.exp(-x * x)
        f_c = self.pc_area * (ex - h * self.pc_lin * erfc(x))                               # eq. 15
        hbar = 0.5 * h * (1.0 + erf(x)) + self.hbar_k * ex                                 # eq. 9
        speed = self.r_eff * w_abs
        temp = 1.0 + self.mu3_th2 * (theta - self.th1)
        coulomb = self.rn * (self.mu1 + self.dmu * np.exp(-speed / self.vs)) * temp * f_c
        viscous = self.rn * self.viscosity(theta) * self.area * speed / hbar
        static = (self.static_factor * self.rn * self.mu2) * temp * f_c                     # DESIGN 9
        return coulomb + viscous, coulomb, viscous, f_c, hbar, static

    def contact(self, h: float) -> tuple[float, float]:
        """(F_c, h_bar) at one separation h, in scalar math: the per-step form the plants' clutches use."""
        x = h * self.inv_s_sqrt2
        ex = math.exp(-x * x)
        return (self.pc_area * (ex - h * self.pc_lin * math.erfc(x)),                       # eq. 15
                0.5 * h * (1.0 + math.erf(x)) + self.hbar_k * ex)                           # eq. 9

    def film_rate(self, h, f_app, rate_mu):
        """dh/dt from the Reynolds force balance F_app = F_c(h) + F_h, F_h = phi 3 pi mu_v K / (2 h_bar^3) (-dh_bar/dt),
        dh_bar/dh = (1 + erf x) / 2; rate_mu = rate_k / mu_v."""
        x = h * self.inv_s_sqrt2
        ex = np.exp(-x * x)
        f_c = self.pc_area * (ex - h * self.pc_lin * erfc(x))
        slope2 = erfc(-x)                                  # 1 + erf x, exact also for h < 0
        hbar = 0.5 * h * slope2 + self.hbar_k * ex
        return rate_mu * (f_c - f_app) * (hbar * hbar * hbar / slope2)

    def film_step(self, h, f_app, f_cmd, theta):
        """h at t + dt from h at t: classical RK4 in `substeps` substeps, the actuator force exact within the
        step (it relaxes from f_app to the held command f_cmd), the viscosity at the clutch temperature held;
        h kept in the film domain [h_min, h_max] after each substep (an open clutch rests at h_max)."""
        rate_mu = self.rate_k / self.viscosity(theta)
        df = f_app - f_cmd
        dec = self.act_decay
        hh = self.hh
        for i in range(self.substeps):
            f0 = f_cmd + df * dec[2 * i]
            fm = f_cmd + df * dec[2 * i + 1]
            f1 = f_cmd + df * dec[2 * i + 2]
            k1 = self.film_rate(h, f0, rate_mu)
            k2 = self.film_rate(h + (0.5 * hh) * k1, fm, rate_mu)
            k3 = self.film_rate(h + (0.5 * hh) * k2, fm, rate_mu)
            k4 = self.film_rate(h + hh * k3, f1, rate_mu)
            h = np.minimum(np.maximum(h + (hh / 6.0) * (k1 + 2.0 * (k2 + k3) + k4), self.h_min), self.h_max)
        return h


def film_time_constant_s(cal: Calibration, force_N, theta_degC):
    """The squeeze film's equivalent first-order time constant at its steady state under force_N (DESIGN 9):
    the force balance linearized about F_c(h_ss) = F_app,
    tau = phi 3 pi mu_v K (dh_bar/dh) / (2 h_bar^3 A_f |dp_c/dh|), dp_c/dh = -(pi/2) E N beta erfc x."""
    h = model.separation_from_pressure_m(cal, np.asarray(force_N, dtype=float) / cal.friction_area)
    x = h / (math.sqrt(2.0) * cal.roughness_rms)
    dpc = 0.5 * math.pi * cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius * erfc(x)
    hbar = model.film_thickness_m(cal, h)
    mu = model.viscosity_Pa_s(cal, theta_degC)
    return (cal.film_squeeze_factor * 3.0 * math.pi * mu * film_constant_m4(cal) * 0.5 * (1.0 + erf(x))
            / (2.0 * hbar ** 3 * cal.friction_area * dpc))
