"""One shift element's TRUE clutch: its VFS with the lag, the piston's fill against the return spring (the kiss
point), the Reynolds squeeze film, the torque (eq. 8, 18) and static capacity (DESIGN 9), the pack's temperature
(eq. 1). The same physics as the 1->2 plant's on-coming clutch (wetclutch.simulate.plant.upshift: scalar forms of
the bench's _Physics), with the element's own calibration.

  VFS        P_vfs(s) = K i + (P_vfs0 - K i) e^(-s/tau)   within the period (exact, i held)
  fill       f = stroke fraction, df/dt = clip(g (P_vfs - P_s(f)), +-q_max) / 1, P_s(f) = F_s/A_p (0.8 + 0.2 f);
             g and q_max are the vehicle file's fill_flow_gain and fill_flow_max per its fill volume (fill
             volumes per s and Pa, per s): every element fills in the same time, its volume A_p x stroke
  apply      F = P_vfs A_p - F_s once f = 1 (the kiss point), 0 before
  film       approach (F > F_c(h)): dh/dt = rate_k / mu_v(theta) (F_c(h) - F) h_bar^3 / (1 + erf x) (RK4 per
             substep), h in [h_min, h_max] (DESIGN 9's Reynolds squeeze film: fast from a wide gap, slow near
             contact); release (F <= F_c(h)): the steady film of the falling force at once, h = h_ss(F) (eq. 16).
             The Reynolds form applied to a separation from deep asperity compression (h < 0, h_bar -> 0) would
             hold a released element for seconds (1000 -> 0 mA: 785 N*m of static capacity left after 1.5 s),
             which no clutch does (the lining's elastic recovery and the grooves feed the gap): a release's lag
             is the VFS's and the piston's. A film at rest (open with no force, or converged under a held
             force) is not integrated
  torque     |T| = s_f R_eff N_c (mu1 + (mu2 - mu1) e^(-R_eff |w| / v_s)) (1 + mu3 (theta - theta1)/theta2) F_c(h)
                   + R_eff N_c mu_v(theta) A_f R_eff |w| / (h_bar(h) + (1 - f) x_s / N_c)
                   x 1 / (1 + (1 - f) (|w| / w_a)^2)
             (s_f: the truth's friction scale; x_s / N_c: the retracted piston's stroke shared by the pack's
             N_c gaps, so an open element's drag is that of its clearance, not of the film at h_max = 4 sigma;
             w_a: the open pack's aeration: its drag peaks at w_a at half the Couette value and falls as 1/|w|
             beyond, as measured open clutches' drag does once air enters the gap (Pointner-Gabriel, Voelkel and
             Stahl, 'Drag Losses of Wet Brakes and Clutches - A Scoping Review', Lubricants 13(1) 27, 2025;
             Couette alone gave brake B 20 N*m, 10 kW at 4600 rpm in 7th); with the piston at the kiss point
             (f = 1) the film alone, as the 1->2 plant's clutch)
  static     s_f static_friction_factor mu2 (1 + mu3 (theta - theta1)/theta2) R_eff N_c F_c(h)
  heat       theta[k+1] = theta_ss + (theta[k] - theta_ss) e^(-(k1+k2) dt / C), theta_ss = (P + k1 th_oil +
             k2 th_housing)/(k1 + k2), P the period's mean friction power (eq. 1, exact zero-order hold)
"""
from __future__ import annotations

import math

from ...reference import model
from ..bench.physics import _Physics

FILM_AT_REST = 1e-7        # relative force mismatch under which a film under a held force counts as converged


class TrueElement:
    """The true clutch of one element; the mechanics read kinetic(|slip|), slope(|slip|) and static."""

    def __init__(self, name: str, cal, *, friction_scale: float, oil_degC: float, housing_degC: float,
                 fill_rate_gain: float, fill_rate_max: float, stroke_m: float, aeration_speed: float,
                 dt_s: float, substeps: int):
        self.name = name
        self.cal = cal
        ph = _Physics(cal, dt_s, 1.0, 1)
        self._ph = ph
        self.scale = float(friction_scale)
        self.oil, self.housing = float(oil_degC), float(housing_degC)
        self.gain = cal.vfs_gain
        self.i_min, self.i_max = cal.vfs_current_min, cal.vfs_current_max
        self.a_p, self.f_s = cal.piston_area, cal.return_spring_force
        self.p_kiss = self.f_s / self.a_p
        self.k1, self.k2 = cal.oil_conductance, cal.housing_conductance
        self.a_th = math.exp(-(self.k1 + self.k2) * dt_s / cal.heat_capacity)
        self.visc_k = ph.rn * ph.area * ph.r_eff
        self.hs = dt_s / substeps
        self.lag = [math.exp(-j * 0.5 * self.hs / cal.vfs_time_constant) for j in range(2 * substeps + 1)]
        self.fill_on = fill_rate_gain > 0.0
        self.fill_gain = fill_rate_gain
        self.fill_max = fill_rate_max if fill_rate_max > 0.0 else math.inf
        self.open_gap = stroke_m / cal.friction_pairs if self.fill_on else 0.0
        self.inv_wa2 = 1.0 / aeration_speed ** 2
        self._film_table = model.FilmTable(cal, 4001)
        self.current = 0.0
        self.P = 0.0
        self.p_cmd = 0.0
        self.dp = 0.0
        self.fill = 0.0 if self.fill_on else 1.0
        self.h = ph.h_max
        self.theta = self.oil
        self.power = 0.0
        self._contact_h = math.nan
        self._idle = False
        self._set_theta(self.theta)
        self._set_film(self.h)
        self._rest = True

    # ------------------------------------------------------------------ state
    def set_steady(self, current_mA: float, theta_degC: float | None = None) -> None:
        """Steady state at current_mA: the VFS pressure at K i, the piston full if that is above the kiss
        pressure (else empty), the film at its steady state under the apply force."""
        self.current = min(max(float(current_mA), self.i_min), self.i_max)
        self.P = self.p_cmd = self.gain * self.current
        self.dp = 0.0
        if theta_degC is not None:
            self.theta = float(theta_degC)
            self._set_theta(self.theta)
        full = self.P > self.p_kiss or not self.fill_on
        self.fill = 1.0 if full else 0.0
        f = self._force(self.P) if full else 0.0
        ph = self._ph
        if f > 0.0:
            h = float(model.separation_from_pressure_m(self.cal, f / ph.area))
            self.h = min(max(h, ph.h_min), ph.h_max)
        else:
            self.h = ph.h_max
        self._set_film(self.h)
        self._rest = True

    def _set_theta(self, theta):
        ph = self._ph
        self.mu_v = float(ph.viscosity(theta))
        self.temp = 1.0 + ph.mu3_th2 * (theta - ph.th1)
        self.rate_mu = ph.rate_k / self.mu_v if ph.phi > 0.0 else 0.0

    def _set_film(self, h):
        ph = self._ph
        if h != self._contact_h:           # the contact depends on h alone (the temperature changes every period)
            self._contact_h = h
            self.f_c, self.hbar = ph.contact(h)
        self.static = self.scale * ph.static_factor * ph.rn * ph.mu2 * self.temp * self.f_c
        self.coul_k = self.scale * ph.rn * self.temp * self.f_c
        self._set_open()

    def _set_open(self):
        """The viscous coefficient with the open clearance, the aeration factor's q = (1 - f) / w_a^2."""
        self.visc_c = self.visc_k * self.mu_v / (self.hbar + (1.0 - self.fill) * self.open_gap)
        self.aer_q = (1.0 - self.fill) * self.inv_wa2

    def _force(self, p):
        f = p * self.a_p - self.f_s
        return f if f > 0.0 else 0.0

    def _film_rate(self, h, f_app):
        ph = self._ph
        x = h * ph.inv_s_sqrt2
        ex = math.exp(-x * x)
        f_c = ph.pc_area * (ex - h * ph.pc_lin * math.erfc(x))
        slope2 = math.erfc(-x)
        hb = 0.5 * h * slope2 + ph.hbar_k * ex
        return self.rate_mu * (f_c - f_app) * (hb * hb * hb / slope2)

    def _fill_rate(self, p):
        q = self.fill_gain * (p - self.p_kiss * (0.8 + 0.2 * self.fill))
        m = self.fill_max
        return m if q > m else -m if q < -m else q

    # ------------------------------------------------------------------ the mechanics' view
    def kinetic(self, w_abs: float) -> float:
        """|T| while slipping at |slip| w_abs."""
        return self.kinetic_slope(w_abs)[0]

    def slope(self, w_abs: float) -> float:
        """d|T|/d|slip| (Stribeck + viscous with the aeration)."""
        return self.kinetic_slope(w_abs)[1]

    def kinetic_slope(self, w_abs: float) -> tuple[float, float]:
        """(kinetic(w_abs), slope(w_abs)) with one exponential: the mechanics ask for both every substep."""
        ph = self._ph
        x = self.aer_q * w_abs * w_abs
        e = math.exp(-ph.r_eff * w_abs / ph.vs)
        return (self.coul_k * (ph.mu1 + ph.dmu * e) + self.visc_c * w_abs / (1.0 + x),
                -self.coul_k * ph.dmu * (ph.r_eff / ph.vs) * e + self.visc_c * (1.0 - x) / ((1.0 + x) * (1.0 + x)))

    # ------------------------------------------------------------------ one period
    def step_begin(self, current_mA: float) -> None:
        i = float(current_mA)
        if not math.isfinite(i):
            raise ValueError(f"element {self.name}: current {current_mA!r} mA is not finite")
        self.current = min(max(i, self.i_min), self.i_max)
        self.p_cmd = self.gain * self.current
        self.dp = self.P - self.p_cmd
        # an empty piston whose pressure stays at or below the spring's preload all period (it moves from P to
        # p_cmd) and an open film at rest: every substep would leave it as it is (substep's first branches)
        ph = self._ph
        self._idle = self.fill_on and self.fill == 0.0 and ph.phi != 0.0 and self.h >= ph.h_max and \
            max(self.P, self.p_cmd) <= 0.8 * self.p_kiss

    def substep(self, j: int) -> None:
        """Advance the piston's fill and the film over substep j (the pressure exact within it); the film's
        torque, capacity and drag updated to its end."""
        if self._idle:
            return
        lag = self.lag
        p0 = self.p_cmd + self.dp * lag[2 * j]
        pm = self.p_cmd + self.dp * lag[2 * j + 1]
        p1 = self.p_cmd + self.dp * lag[2 * j + 2]
        if self.fill_on and (self.fill < 1.0 or pm < self.p_kiss):
            full0 = self.fill >= 1.0
            fill = min(max(self.fill + self.hs * self._fill_rate(pm), 0.0), 1.0)
            if fill != self.fill:
                self.fill = fill
                self._set_open()
            full1 = fill >= 1.0
            f0 = self._force(p0) if full0 else 0.0
            fm = self._force(pm) if full1 else 0.0
            f1 = self._force(p1) if full1 else 0.0
        else:
            f0, fm, f1 = self._force(p0), self._force(pm), self._force(p1)
        ph = self._ph
        h = self.h
        if ph.phi == 0.0:
            h = float(self._film_table.separation_from_pressure_m(f1 / ph.area))
        elif h >= ph.h_max and f0 == 0.0 and f1 == 0.0:
            return
        elif self._rest and abs(f1 - f0) <= FILM_AT_REST * max(f1, 1.0) \
                and abs(self.f_c - f1) <= FILM_AT_REST * max(f1, 1.0):
            return
        elif fm <= self.f_c:
            h = max(h, float(self._film_table.separation_from_pressure_m(f1 / ph.area)))
        else:
            hs = self.hs
            k1 = self._film_rate(h, f0)
            k2 = self._film_rate(h + 0.5 * hs * k1, fm)
            k3 = self._film_rate(h + 0.5 * hs * k2, fm)
            k4 = self._film_rate(h + hs * k3, f1)
            h = min(max(h + (hs / 6.0) * (k1 + 2.0 * (k2 + k3) + k4), ph.h_min), ph.h_max)
        if h != self.h:
            self.h = h
            self._set_film(h)
        self._rest = abs(self.f_c - f1) <= FILM_AT_REST * max(f1, 1.0)

    def step_end(self, friction_energy_J: float, dt_s: float) -> None:
        """The pressure at the period's end; the pack's heat from the period's friction energy (eq. 1)."""
        self.P = self.p_cmd + self.dp * self.lag[-1]
        self.power = friction_energy_J / dt_s
        th_ss = (self.power + self.k1 * self.oil + self.k2 * self.housing) / (self.k1 + self.k2)
        theta = th_ss + (self.theta - th_ss) * self.a_th
        if theta != self.theta:
            self.theta = theta
            self._set_theta(theta)
            self._set_film(self.h)

    # ------------------------------------------------------------------ truth
    def chamber_pressure(self) -> float:
        """The piston's pressure: the VFS pressure once full, the return spring's while filling."""
        if self.fill >= 1.0:
            return self.P
        spring = self.p_kiss * (0.8 + 0.2 * self.fill)
        return min(self.P, spring) if self.fill <= 0.0 else spring

    def apply_force(self) -> float:
        return self._force(self.P) if self.fill >= 1.0 else 0.0

