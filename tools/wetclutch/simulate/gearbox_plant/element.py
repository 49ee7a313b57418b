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

import bisect
import math

import numpy as np

from ...reference import model
from ..bench.physics import _Physics

FILM_AT_REST = 1e-7        # relative force mismatch under which a film under a held force counts as converged
_np_exp = np.exp           # bound once: the viscosity is evaluated per element every period


def _kinetic_term(name: str) -> property:
    """A kinetic coefficient made on demand (TrueElement._kinetic_terms), read like the attribute it was."""
    def get(self):
        if self._kinetic_stale:
            self._kinetic_terms()
        return getattr(self, name)
    return property(get)


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
        # The table as Python lists for _steady_separation_m (np.interp of one value costs ~10 us; this is
        # called in every substep of a releasing element)
        self._table_p_Pa = self._film_table.pressure_Pa.tolist()
        self._table_h_m = self._film_table.separation_m.tolist()
        self._table_p_min_Pa = self._film_table.pressure_min_Pa
        self._table_p_max_Pa = self._film_table.pressure_max_Pa
        # Constants of the per-substep code bound to the element (they were read through self._ph every call):
        # the same numbers, so the same arithmetic bit for bit. Products are kept in their original left-to-right
        # order (scale * static_factor * rn * mu2 is the prefix of the static capacity's product).
        self.film_on = ph.phi != 0.0           # the squeeze film integrated (phi == 0: the steady film at once)
        self.h_min, self.h_max = ph.h_min, ph.h_max
        self.area = ph.area
        self.p_idle = 0.8 * self.p_kiss        # the spring's preload pressure (empty piston)
        self.static_k = self.scale * ph.static_factor * ph.rn * ph.mu2
        self.coul_rn = self.scale * ph.rn
        self.mu1, self.dmu = ph.mu1, ph.dmu
        self.neg_r_eff, self.vs = -ph.r_eff, ph.vs
        self.r_over_vs = ph.r_eff / ph.vs
        self.inv_s_sqrt2, self.pc_area, self.pc_lin, self.hbar_k = ph.inv_s_sqrt2, ph.pc_area, ph.pc_lin, ph.hbar_k
        self.rate_k = ph.rate_k
        self.mv = tuple(float(m) for m in ph.mv)
        self.mu3_th2, self.th1 = ph.mu3_th2, ph.th1
        self.k1_oil, self.k2_housing, self.k12 = self.k1 * self.oil, self.k2 * self.housing, self.k1 + self.k2
        self.current = 0.0
        self.P = 0.0
        self.p_cmd = 0.0
        self.dp = 0.0
        self.fill = 0.0 if self.fill_on else 1.0
        self.h = ph.h_max
        self.theta = self.oil
        self.power = 0.0
        self._contact_h = math.nan
        self._contact_x = self._contact_ex = math.nan
        self._hbar_h = math.nan             # the h of _hbar (_kinetic_terms)
        self._kinetic_stale = True
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
        if f > 0.0:
            h = float(model.separation_from_pressure_m(self.cal, f / self.area))
            self.h = min(max(h, self.h_min), self.h_max)
        else:
            self.h = self.h_max
        self._set_film(self.h)
        self._rest = True

    def _set_theta(self, theta):
        ph = self._ph
        # _Physics.viscosity (eq. 2) on one float: numpy's exp as there (math.exp differs from it in the last
        # bit for some arguments), the rest in float arithmetic (the same IEEE operations as on numpy scalars)
        mv1, mv2, mv3, mv4 = self.mv
        self.mu_v = mv1 * float(_np_exp(mv2 * theta)) + mv3 * float(_np_exp(mv4 * theta))
        self.temp = 1.0 + self.mu3_th2 * (theta - self.th1)
        self.rate_mu = ph.rate_k / self.mu_v if ph.phi > 0.0 else 0.0
        self.visc_mu = self.visc_k * self.mu_v      # the viscous coefficient's numerator (in this order)
        self._kinetic_stale = True

    def _set_film(self, h):
        if h != self._contact_h:           # the contact depends on h alone (the temperature changes every period)
            self._contact_h = h
            # _Physics.contact(h)'s F_c, inlined (called in every substep of an engaging element); its h_bar in
            # _kinetic_terms
            x = h * self.inv_s_sqrt2
            ex = math.exp(-x * x)
            self.f_c = self.pc_area * (ex - h * self.pc_lin * math.erfc(x))
            self._contact_x, self._contact_ex = x, ex      # the next RK4's first stage starts at this h
        self.static = self.static_k * self.temp * self.f_c
        self._kinetic_stale = True

    def _set_open(self):
        """The fill changed: the viscous coefficient and the aeration factor are to be made again."""
        self._kinetic_stale = True

    def _kinetic_terms(self):
        """The kinetic torque's coefficients from the film, the temperature and the fill as they are now: h_bar
        (eq. 9), the Coulomb factor, the Stribeck slope factor, the viscous coefficient with the open clearance
        and the aeration factor's q = (1 - f) / w_a^2. Made when the mechanics next ask (kinetic_slope), not at
        every change of the film: a locked element's film moves every substep but its kinetic torque is not
        read. The same expressions from the same values as when they were made at each change (every change of
        h, theta or the fill marks them stale), so the same numbers."""
        h = self._contact_h
        if self._hbar_h != h:
            self._hbar = 0.5 * h * (1.0 + math.erf(self._contact_x)) + self.hbar_k * self._contact_ex
            self._hbar_h = h
        coul_k = self._coul_k = self.coul_rn * self.temp * self.f_c
        self._slope_k = -coul_k * self.dmu * self.r_over_vs         # -coul_k dmu (r_eff / v_s)
        open_share = 1.0 - self.fill
        self._visc_c = self.visc_mu / (self._hbar + open_share * self.open_gap)
        self._aer_q = open_share * self.inv_wa2
        self._kinetic_stale = False

    # the coefficients for a reader outside the mechanics (as attributes before they were made on demand)
    hbar = _kinetic_term("_hbar")
    coul_k = _kinetic_term("_coul_k")
    visc_c = _kinetic_term("_visc_c")
    aer_q = _kinetic_term("_aer_q")

    def _force(self, p):
        f = p * self.a_p - self.f_s
        return f if f > 0.0 else 0.0

    def _film_rate(self, h, f_app):
        x = h * self.inv_s_sqrt2
        ex = math.exp(-x * x)
        f_c = self.pc_area * (ex - h * self.pc_lin * math.erfc(x))
        slope2 = math.erfc(-x)
        hb = 0.5 * h * slope2 + self.hbar_k * ex
        return self.rate_mu * (f_c - f_app) * (hb * hb * hb / slope2)

    def _fill_rate(self, p):
        q = self.fill_gain * (p - self.p_kiss * (0.8 + 0.2 * self.fill))
        m = self.fill_max
        return m if q > m else -m if q < -m else q

    def _steady_separation_m(self, force_N):
        """The steady film's separation under force_N: FilmTable.separation_from_pressure_m (np.clip, then
        np.interp) for one value in plain Python, the same arithmetic as numpy's interp (its slope (y1 - y0) /
        (x1 - x0) times (x - x0) plus y0; a node's own value at a node), so the same number to the bit
        (tests/python/test_gearbox_plant_speed.py checks it against the table)."""
        p = force_N / self.area
        lo, hi = self._table_p_min_Pa, self._table_p_max_Pa
        p = lo if p < lo else hi if p > hi else p
        xs, ys = self._table_p_Pa, self._table_h_m
        if p <= xs[0]:
            return ys[0]
        if p >= xs[-1]:
            return ys[-1]
        k = bisect.bisect_right(xs, p) - 1          # xs[k] <= p < xs[k + 1]
        x0 = xs[k]
        if p == x0:
            return ys[k]
        return (ys[k + 1] - ys[k]) / (xs[k + 1] - x0) * (p - x0) + ys[k]

    # ------------------------------------------------------------------ the mechanics' view
    def kinetic(self, w_abs: float) -> float:
        """|T| while slipping at |slip| w_abs."""
        return self.kinetic_slope(w_abs)[0]

    def slope(self, w_abs: float) -> float:
        """d|T|/d|slip| (Stribeck + viscous with the aeration)."""
        return self.kinetic_slope(w_abs)[1]

    def kinetic_slope(self, w_abs: float) -> tuple[float, float]:
        """(kinetic(w_abs), slope(w_abs)) with one exponential: the mechanics ask for both every substep."""
        if self._kinetic_stale:
            self._kinetic_terms()
        x = self._aer_q * w_abs * w_abs
        e = math.exp(self.neg_r_eff * w_abs / self.vs)         # e^(-r_eff |w| / v_s)
        q = 1.0 + x
        visc_c = self._visc_c
        return (self._coul_k * (self.mu1 + self.dmu * e) + visc_c * w_abs / q,
                self._slope_k * e + visc_c * (1.0 - x) / (q * q))

    # ------------------------------------------------------------------ one period
    def step_begin(self, current_mA: float) -> None:
        i = float(current_mA)
        if not math.isfinite(i):
            raise ValueError(f"element {self.name}: current {current_mA!r} mA is not finite")
        self.current = min(max(i, self.i_min), self.i_max)
        self.p_cmd = self.gain * self.current
        self.dp = self.P - self.p_cmd
        # an empty piston whose pressure stays at or below the spring's preload all period (it moves from P to
        # p_cmd) and an open film at rest: every substep would leave it as it is (substep's first branches), so
        # the plant does not call it this period (plant.step)
        self._idle = self.fill_on and self.fill == 0.0 and self.film_on and self.h >= self.h_max and \
            max(self.P, self.p_cmd) <= self.p_idle

    def substep(self, j: int) -> None:
        """Advance the piston's fill and the film over substep j (the pressure exact within it); the film's
        torque, capacity and drag updated to its end. (_force and _fill_rate are inlined here, the hot path; the
        arithmetic is theirs.)"""
        if self._idle:
            return
        lag = self.lag
        p_cmd, dp = self.p_cmd, self.dp
        p0 = p_cmd + dp * lag[2 * j]
        pm = p_cmd + dp * lag[2 * j + 1]
        p1 = p_cmd + dp * lag[2 * j + 2]
        a_p, f_s = self.a_p, self.f_s
        fill = self.fill
        if self.fill_on and (fill < 1.0 or pm < self.p_kiss):
            full0 = fill >= 1.0
            q = self.fill_gain * (pm - self.p_kiss * (0.8 + 0.2 * fill))        # _fill_rate(pm)
            m = self.fill_max
            q = m if q > m else -m if q < -m else q
            new = min(max(fill + self.hs * q, 0.0), 1.0)
            if new != fill:
                self.fill = fill = new
                self._set_open()
            full1 = fill >= 1.0
            if full0:
                f0 = p0 * a_p - f_s
                f0 = f0 if f0 > 0.0 else 0.0
            else:
                f0 = 0.0
            if full1:
                fm = pm * a_p - f_s
                fm = fm if fm > 0.0 else 0.0
                f1 = p1 * a_p - f_s
                f1 = f1 if f1 > 0.0 else 0.0
            else:
                fm = f1 = 0.0
        else:
            f0 = p0 * a_p - f_s
            f0 = f0 if f0 > 0.0 else 0.0
            fm = pm * a_p - f_s
            fm = fm if fm > 0.0 else 0.0
            f1 = p1 * a_p - f_s
            f1 = f1 if f1 > 0.0 else 0.0
        h = self.h
        tol = FILM_AT_REST * (f1 if f1 > 1.0 else 1.0)         # FILM_AT_REST x max(f1, 1)
        if not self.film_on:
            h = self._steady_separation_m(f1)
        elif h >= self.h_max and f0 == 0.0 and f1 == 0.0:
            return
        elif self._rest and abs(f1 - f0) <= tol and abs(self.f_c - f1) <= tol:
            return
        elif fm <= self.f_c:
            h_ss = self._steady_separation_m(f1)
            h = h if h >= h_ss else h_ss
        else:
            hs = self.hs
            rate = self._film_rate
            if h == self._contact_h:
                # _film_rate(h, f0) from _set_film's contact at this h (the same x, e^(-x^2) and F_c(h): the
                # same expressions); only 1 + erf x = erfc(-x) is new
                x, ex = self._contact_x, self._contact_ex
                slope2 = math.erfc(-x)
                hb = 0.5 * h * slope2 + self.hbar_k * ex
                k1 = self.rate_mu * (self.f_c - f0) * (hb * hb * hb / slope2)
            else:
                k1 = rate(h, f0)
            k2 = rate(h + 0.5 * hs * k1, fm)
            k3 = rate(h + 0.5 * hs * k2, fm)
            k4 = rate(h + hs * k3, f1)
            h = min(max(h + (hs / 6.0) * (k1 + 2.0 * (k2 + k3) + k4), self.h_min), self.h_max)
        if h != self.h:
            self.h = h
            self._set_film(h)
        self._rest = abs(self.f_c - f1) <= tol

    def step_end(self, friction_energy_J: float, dt_s: float) -> None:
        """The pressure at the period's end; the pack's heat from the period's friction energy (eq. 1)."""
        self.P = self.p_cmd + self.dp * self.lag[-1]
        self.power = power = friction_energy_J / dt_s
        th_ss = (power + self.k1_oil + self.k2_housing) / self.k12
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

