"""UpshiftPlant: the two-clutch driveline of the 1->2 upshift, stepped at the TCU's period (the package
docstring has the equations), and the initial turbine speed of a scenario."""
from __future__ import annotations

import math

import numpy as np

from ...reference import model
from ..bench.physics import _Physics
from .params import DT_S, GRAVITY, NOISE_BLOCK, RPM, SUBSTEPS, PlantParams


TRUTH_NAMES = (
    "t_s",                      # s, plant time (0 at construction)
    "turbine_speed_rpm", "output_speed_rpm",
    "gear1_speed_rpm",          # i1 w_o: the turbine speed 1st gear would have (Fig. 4)
    "gear2_speed_rpm",          # i2 w_o: the turbine speed 2nd gear would have
    "vehicle_speed_m_s",
    "slip_rad_s",               # true on-coming slip w_t - i2 w_o
    "offgoing_slip_rad_s",      # w_t - i1 w_o
    "clutch_torque_Nm",         # on-coming, signed (> 0 opposes positive slip: drives the output)
    "clutch_capacity_Nm",       # on-coming static capacity (friction_scale included)
    "offgoing_torque_Nm", "offgoing_capacity_Nm",
    "driveshaft_torque_Nm",     # T_s at the output shaft
    "turbine_torque_Nm",        # true T_t
    "current_mA",               # the current held over the step (clamped to the solenoid range)
    "pressure_cmd_Pa",          # K i
    "pressure_Pa",              # true piston pressure after the lag (ripple excluded)
    "apply_force_N",            # P A_p - F_s >= 0 (end of step, ripple excluded)
    "contact_force_N", "separation_m", "hbar_m",
    "theta_clutch_degC",        # true friction-surface temperature
    "vehicle_accel_m_s2",
    "oncoming_locked", "offgoing_locked",   # 0.0 / 1.0
    "friction_power_W",         # on-coming, mean over the step (the heat into eq. 1)
    "offgoing_power_W",         # off-going, mean over the step
    # the whole shift (issue 22)
    "engine_torque_Nm",         # actual engine (turbine) torque (= turbine_torque_Nm)
    "engine_request_Nm",        # the torque change requested this step (0 when none)
    "offgoing_current_mA",      # the off-going VFS current (scripted: the current of its equivalent pressure)
    "offgoing_pressure_Pa",     # the off-going piston pressure (scripted: the pressure giving its capacity)
    "fill_fraction",            # on-coming piston stroke / full stroke (1 without a fill)
    "output_torque_Nm",         # b T_c + b1 T_off: the gearbox output torque
    "vfs_pressure_Pa",          # on-coming VFS pressure after the lag (= pressure_Pa once filled)
)


class UpshiftPlant:
    """The 1->2 upshift plant; see the module docstring. One instance per shift."""

    def __init__(self, params: PlantParams, *, oil_degC: float, turbine_torque_Nm: float,
                 friction_scale: float | None = None, seed: int | None = None,
                 theta_clutch_degC: float | None = None, turbine_speed_rpm: float | None = None,
                 offgoing_current_mA: float | None = None, engine_ignores_request: bool = False,
                 offgoing_slip_sensor: bool | None = None):
        p = params
        cal = p.clutch_cal
        for name, v in (("oil_degC", oil_degC), ("turbine_torque_Nm", turbine_torque_Nm)):
            if not math.isfinite(float(v)):
                raise ValueError(f"{name} {v!r} is not finite")
        self.params = p
        self.dt_s = DT_S
        self.n_sub = SUBSTEPS
        self.hs = DT_S / SUBSTEPS
        self.oil_degC = float(oil_degC)
        self.housing_degC = self.oil_degC + p.housing_offset
        self.turbine_torque_Nm = float(turbine_torque_Nm)     # may be changed between steps
        self.friction_scale = p.friction_scale if friction_scale is None else float(friction_scale)
        if not self.friction_scale > 0:
            raise ValueError(f"friction_scale {friction_scale!r} must be > 0")
        seed = p.seed if seed is None else int(seed)
        self.rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, 0x12])))
        self._noise = None
        self._noise_k = NOISE_BLOCK
        # the off-going slip sensor's noise: its own generator, so the first one's draws stay as before
        self.rng_off = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, 0x13])))
        self._noise_off = None
        self._offgoing_sensor = (offgoing_current_mA is not None) if offgoing_slip_sensor is None \
            else bool(offgoing_slip_sensor)

        # The true clutch (bench physics constants).
        ph = _Physics(cal, DT_S, 1.0, 1)
        self._ph = ph
        self._phi = ph.phi
        self._film_table = model.FilmTable(cal, 4001) if ph.phi == 0.0 else None
        self.a_p, self.f_s = cal.piston_area, cal.return_spring_force
        self.i_min, self.i_max = cal.vfs_current_min, cal.vfs_current_max
        self.k1, self.k2, self.cap = cal.oil_conductance, cal.housing_conductance, cal.heat_capacity
        self.a_th = math.exp(-(self.k1 + self.k2) * DT_S / self.cap)
        self.visc_k = ph.rn * ph.area * ph.r_eff            # viscous torque = visc_k mu_v |w| / h_bar
        self.i1, self.i2, self.rf = p.ratio_1st, p.ratio_2nd, p.final_drive
        self.It, self.Io = p.turbine_inertia, p.output_inertia
        self.Iv = p.vehicle_mass * p.wheel_radius ** 2
        self.ks, self.cs = p.shaft_stiffness, p.shaft_damping
        g = math.atan(p.road_grade / 100.0)
        self.road_const = p.wheel_radius * p.vehicle_mass * GRAVITY * math.sin(g)
        self.road_roll = p.wheel_radius * p.vehicle_mass * GRAVITY * p.rolling_resistance * math.cos(g)
        self.road_drag = p.wheel_radius ** 3 * 0.5 * p.air_density * p.drag_area   # x w_w |w_w|
        self.m_on = 1.0 / self.It + self.i2 * self.i2 / self.Io      # slip "mobility" of each clutch
        self.m_off = 1.0 / self.It + self.i1 * self.i1 / self.Io
        self.lag = [math.exp(-j * 0.5 * self.hs / p.vfs_time_constant) for j in range(2 * SUBSTEPS + 1)]

        # The engine: a torque request (a change against the driver's torque) through a dead time and a lag.
        self.engine_ignores_request = bool(engine_ignores_request)
        self.engine_lag = [math.exp(-j * 0.5 * self.hs / p.engine_time_constant) for j in range(2 * SUBSTEPS + 1)]
        self._req_fifo = [0.0] * int(round(p.engine_delay / DT_S))
        self.engine_Nm = self.turbine_torque_Nm     # actual engine torque (the mechanics' T_t)
        self._tt = self.engine_Nm
        self.engine_request = 0.0
        # The on-coming fill: piston stroke fraction (1 = at the kiss point; always 1 without a fill).
        self.fill_on = p.fill_volume > 0.0
        self.fill = 0.0 if self.fill_on else 1.0
        self.p_kiss = self.f_s / self.a_p
        if self.fill_on:
            self.fill_rate = p.fill_flow_gain / p.fill_volume                      # 1/(s Pa)
            self.fill_rate_max = p.fill_flow_max / p.fill_volume if p.fill_flow_max > 0.0 else math.inf
        # The off-going clutch's own VFS: capacity per piston pressure above its spring's.
        oc = p.offgoing_cal
        self.a_off, self.f_s_off = oc.piston_area, oc.return_spring_force
        self.i_min_off, self.i_max_off = oc.vfs_current_min, oc.vfs_current_max
        mu_static = oc.static_friction_factor * oc.mu2 * (1.0 + oc.mu3 / oc.theta2 * (self.oil_degC - oc.theta1))
        self.off_cap_per_N = p.offgoing_friction_scale * mu_static * oc.friction_pairs * oc.effective_radius
        self.off_lag = [math.exp(-j * 0.5 * self.hs / p.offgoing_vfs_time_constant) for j in range(2 * SUBSTEPS + 1)]

        # Initial state: steady 1st gear, on-coming open (h at h_max), pressure 0.
        self.t = 0.0
        self.P = 0.0
        self.h = ph.h_max
        self.theta = self.oil_degC if theta_clutch_degC is None else float(theta_clutch_degC)
        self._set_theta(self.theta)
        self._set_film(self.h)
        w_t = (p.turbine_speed if turbine_speed_rpm is None else float(turbine_speed_rpm)) * RPM
        if not w_t > 0:
            raise ValueError(f"turbine_speed_rpm {turbine_speed_rpm!r} must be > 0")
        self.wo = w_t / self.i1
        self.wt = w_t
        self.ww = self.wo / self.rf
        t_on = self._on_kinetic(abs(self.wt - self.i2 * self.wo))
        tt = self.turbine_torque_Nm
        j_w = self.Iv + self.rf ** 2 * (self.Io + self.It * self.i1 ** 2)
        alpha = (self.rf * (self.i1 * tt - (self.i1 - self.i2) * t_on) - self._road(self.ww)) / j_w
        t_s = (self.Iv * alpha + self._road(self.ww)) / self.rf
        self.phi = t_s / self.ks
        t_off0 = tt - t_on - self.It * self.i1 * self.rf * alpha
        self.off_static = p.holding_factor * max(abs(tt), abs(t_off0), p.holding_min)
        if offgoing_current_mA is None:
            self.off_current = None
            self.P_off = self._off_equivalent_pressure(self.off_static)
        else:
            i_off = float(offgoing_current_mA)
            if not math.isfinite(i_off):
                raise ValueError(f"offgoing_current_mA {offgoing_current_mA!r} is not finite")
            self.off_current = min(max(i_off, self.i_min_off), self.i_max_off)
            self.P_off = p.offgoing_vfs_gain * self.off_current
            self.off_static = self._off_capacity(self.P_off)
        self.off_cap_now = self.off_static
        self.lock_on, self.lock_off = False, True
        self.dir_on, self.dir_off = 1.0, 1.0
        self.current = 0.0
        self.p_noise = 0.0
        self.power_on = self.power_off = 0.0
        self._rows: list = []
        self._draw_noise()
        self._truth = self._make_truth(self.off_static)
        self._rows.append(tuple(self._truth[c] for c in TRUTH_NAMES))

    # ----------------------------------------------------------------- clutch physics (scalar forms of _Physics)
    def _set_theta(self, theta):
        ph = self._ph
        self.mu_v = float(ph.viscosity(theta))
        self.temp = 1.0 + ph.mu3_th2 * (theta - ph.th1)
        self.rate_mu = ph.rate_k / self.mu_v if self._phi > 0.0 else 0.0

    def _set_film(self, h):
        """F_c, h_bar and the static capacity at separation h (eq. 9, 15; DESIGN 9)."""
        ph = self._ph
        self.f_c, self.hbar = ph.contact(h)
        self.on_static = self.friction_scale * ph.static_factor * ph.rn * ph.mu2 * self.temp * self.f_c
        self.coul_k = self.friction_scale * ph.rn * self.temp * self.f_c
        self.visc_c = self.visc_k * self.mu_v / self.hbar

    def _on_kinetic(self, w_abs):
        """|T| of the slipping on-coming clutch at |slip| w_abs (eq. 8, 18; Coulomb part scaled)."""
        ph = self._ph
        return self.coul_k * (ph.mu1 + ph.dmu * math.exp(-ph.r_eff * w_abs / ph.vs)) + self.visc_c * w_abs

    def _on_slope(self, w_abs):
        """d|T|/d|slip| of the slipping on-coming clutch at |slip| w_abs (Stribeck + viscous)."""
        ph = self._ph
        return -self.coul_k * ph.dmu * (ph.r_eff / ph.vs) * math.exp(-ph.r_eff * w_abs / ph.vs) + self.visc_c

    def _film_rate(self, h, f_app):
        ph = self._ph
        x = h * ph.inv_s_sqrt2
        ex = math.exp(-x * x)
        f_c = ph.pc_area * (ex - h * ph.pc_lin * math.erfc(x))
        slope2 = math.erfc(-x)
        hb = 0.5 * h * slope2 + ph.hbar_k * ex
        return self.rate_mu * (f_c - f_app) * (hb * hb * hb / slope2)

    def _force(self, P):
        f = P * self.a_p - self.f_s
        return f if f > 0.0 else 0.0

    def _road(self, ww):
        roll = self.road_roll * max(-1.0, min(1.0, ww * self.params.wheel_radius / 0.05))
        return self.road_const + roll + self.road_drag * ww * abs(ww)

    def _off_capacity(self, P):
        """Static capacity of the off-going clutch at piston pressure P (its own VFS)."""
        f = P * self.a_off - self.f_s_off
        return self.off_cap_per_N * f if f > 0.0 else 0.0

    def _off_equivalent_pressure(self, cap):
        """The off-going piston pressure that gives static capacity cap (its kiss pressure for 0)."""
        return (cap / self.off_cap_per_N + self.f_s_off) / self.a_off

    def _fill_rate(self, P):
        """d(fill)/dt at VFS pressure P and the present stroke: the flow in (out) against the return spring,
        the spring's pressure 0.8 .. 1 x F_s / A_p over the stroke, the flow limited to fill_flow_max."""
        q = self.fill_rate * (P - self.p_kiss * (0.8 + 0.2 * self.fill))
        m = self.fill_rate_max
        return m if q > m else -m if q < -m else q

    def _off_fraction(self, s):
        p = self.params
        if s is None or s <= p.release_start:
            return 1.0
        return max(0.0, 1.0 - (s - p.release_start) / p.release_time)

    # ----------------------------------------------------------------- mechanics
    def _torques(self, off_static, commit):
        """(T_on, T_off, T_s, T_road) at the current state; a locked clutch whose needed torque exceeds its
        static capacity breaks away (state changed only if commit)."""
        wt, wo = self.wt, self.wo
        i1, i2, It, Io = self.i1, self.i2, self.It, self.Io
        t_s = self.ks * self.phi + self.cs * (wo - self.rf * self.ww)
        tt = self._tt
        lock_on, lock_off = self.lock_on, self.lock_off
        off_kin = self.params.kinetic_ratio * off_static
        if lock_on:
            t_off = self._off_slipping(wt - i1 * wo) * off_kin
            need = ((tt - t_off) / It - i2 * (i1 * t_off - t_s) / Io) / self.m_on
            if abs(need) <= self.on_static:
                t_on = need
            else:
                d = 1.0 if need > 0 else -1.0
                t_on = d * self._on_kinetic(0.0)
                if commit:
                    self.lock_on, self.dir_on = False, d
        elif lock_off:
            s_on = wt - i2 * wo
            t_on = (1.0 if s_on > 0 else -1.0 if s_on < 0 else self.dir_on) * self._on_kinetic(abs(s_on))
            need = ((tt - t_on) / It - i1 * (i2 * t_on - t_s) / Io) / self.m_off
            if abs(need) <= off_static:
                t_off = need
            else:
                d = 1.0 if need > 0 else -1.0
                t_off = d * off_kin
                if commit:
                    self.lock_off, self.dir_off = False, d
        else:
            s_on = wt - i2 * wo
            t_on = (1.0 if s_on > 0 else -1.0 if s_on < 0 else self.dir_on) * self._on_kinetic(abs(s_on))
            t_off = self._off_slipping(wt - i1 * wo) * off_kin
        return t_on, t_off, t_s, self._road(self.ww)

    def _off_slipping(self, s):
        return 1.0 if s > 0 else -1.0 if s < 0 else self.dir_off

    def _try_lock(self, which, off_static, t_other):
        """A slipping clutch whose slip crossed zero: lock if the torque to hold it is within its capacity
        (the other clutch slipping with torque t_other); remove the remaining slip by an impulse."""
        i1, i2, It, Io = self.i1, self.i2, self.It, self.Io
        tt = self._tt
        t_s = self.ks * self.phi + self.cs * (self.wo - self.rf * self.ww)
        if which == "on":
            if self.lock_off:
                return
            need = ((tt - t_other) / It - i2 * (i1 * t_other - t_s) / Io) / self.m_on
            if abs(need) <= self.on_static:
                j = (self.wt - i2 * self.wo) / self.m_on
                self.wt -= j / It
                self.wo += i2 * j / Io
                self.lock_on = True
        else:
            if self.lock_on:
                return
            need = ((tt - t_other) / It - i1 * (i2 * t_other - t_s) / Io) / self.m_off
            if abs(need) <= off_static:
                j = (self.wt - i1 * self.wo) / self.m_off
                self.wt -= j / It
                self.wo += i1 * j / Io
                self.lock_off = True

    # ----------------------------------------------------------------- public
    def step(self, current_mA: float, shift_time_s: float | None, offgoing_current_mA: float | None = None,
             engine_request_Nm: float | None = None) -> None:
        """Advance one period (dt_s) with current_mA held; shift_time_s = time since the shift command at
        the start of the step (None before the command), which drives the off-going clutch's scripted release.

        offgoing_current_mA: the off-going clutch's VFS current held over the step (its capacity from its
        own lagged pressure); None: the scripted release (shift_time_s).
        engine_request_Nm: the requested engine torque CHANGE against the driver's torque turbine_torque_Nm
        (+ more, - less): the engine follows turbine_torque_Nm + request, within [engine_torque_min,
        engine_torque_max], after engine_delay and through engine_time_constant (ignored with
        engine_ignores_request); None: the engine torque is turbine_torque_Nm (no intervention).
        Both None: bit for bit the plant before issue 22."""
        i = float(current_mA)
        if not math.isfinite(i):
            raise ValueError(f"current_mA {current_mA!r} is not finite")
        i = min(max(i, self.i_min), self.i_max)
        p = self.params
        hs, n = self.hs, self.n_sub
        # engine: the actual torque over the step (exact first-order lag, the substeps' mid values)
        if engine_request_Nm is None:
            req = None
            self.engine_request = 0.0
        else:
            req = float(engine_request_Nm)
            if not math.isfinite(req):
                raise ValueError(f"engine_request_Nm {engine_request_Nm!r} is not finite")
            self.engine_request = req
        fifo = self._req_fifo
        if fifo:
            fifo.append(0.0 if req is None else req)
            applied = fifo.pop(0)
        else:
            applied = 0.0 if req is None else req
        if req is None:
            self.engine_Nm = self.turbine_torque_Nm
            e_tgt = e_d = None
            self._tt = self.engine_Nm
        else:
            e_tgt = self.turbine_torque_Nm + (0.0 if self.engine_ignores_request else applied)
            e_tgt = min(max(e_tgt, p.engine_torque_min), p.engine_torque_max)
            e_d = self.engine_Nm - e_tgt
        # off-going clutch: scripted, or its own VFS (exact first-order lag, the substeps' start values)
        if offgoing_current_mA is None:
            i_off = None
        else:
            i_off = float(offgoing_current_mA)
            if not math.isfinite(i_off):
                raise ValueError(f"offgoing_current_mA {offgoing_current_mA!r} is not finite")
            i_off = min(max(i_off, self.i_min_off), self.i_max_off)
            p_cmd_off = p.offgoing_vfs_gain * i_off
            dp_off = self.P_off - p_cmd_off
        p_cmd = p.vfs_gain * i
        dp = self.P - p_cmd
        ripple = self.p_noise
        lag = self.lag
        i1, i2, rf = self.i1, self.i2, self.rf
        It, Io, Iv = self.It, self.Io, self.Iv
        e_on = e_off = 0.0
        fill_on = self.fill_on
        for j in range(n):
            # film: one RK4 step over the substep, the pressure exact (first-order lag) within it
            if fill_on:
                # the piston stroke (explicit over the substep with the mid pressure); the plates get an
                # apply force only with the piston at the kiss point (fill complete)
                full0 = self.fill >= 1.0
                self.fill = min(max(self.fill + hs * self._fill_rate(p_cmd + dp * lag[2 * j + 1] + ripple),
                                    0.0), 1.0)
                full1 = self.fill >= 1.0
                f0 = self._force(p_cmd + dp * lag[2 * j] + ripple) if full0 else 0.0
                fm = self._force(p_cmd + dp * lag[2 * j + 1] + ripple) if full1 else 0.0
                f1 = self._force(p_cmd + dp * lag[2 * j + 2] + ripple) if full1 else 0.0
            else:
                f0 = self._force(p_cmd + dp * lag[2 * j] + ripple)
                fm = self._force(p_cmd + dp * lag[2 * j + 1] + ripple)
                f1 = self._force(p_cmd + dp * lag[2 * j + 2] + ripple)
            h = self.h
            if self._phi == 0.0:
                h = float(self._film_table.separation_from_pressure_m(f1 / self._ph.area))
            elif not (h >= self._ph.h_max and f0 == 0.0 and fm == 0.0 and f1 == 0.0):
                k1 = self._film_rate(h, f0)
                k2 = self._film_rate(h + 0.5 * hs * k1, fm)
                k3 = self._film_rate(h + 0.5 * hs * k2, fm)
                k4 = self._film_rate(h + hs * k3, f1)
                h = min(max(h + (hs / 6.0) * (k1 + 2.0 * (k2 + k3) + k4), self._ph.h_min), self._ph.h_max)
            # mechanics at the substep start (film at the start), semi-implicit Euler
            if i_off is None:
                off_static = self.off_static * self._off_fraction(None if shift_time_s is None
                                                                  else shift_time_s + j * hs)
            else:
                off_static = self._off_capacity(p_cmd_off + dp_off * self.off_lag[2 * j])
            if e_d is not None:
                self._tt = e_tgt + e_d * self.engine_lag[2 * j + 1]
            t_on, t_off, t_s, t_road = self._torques(off_static, True)
            s_on0 = self.wt - i2 * self.wo
            s_off0 = self.wt - i1 * self.wo
            tt = self._tt
            if not self.lock_on and not self.lock_off:
                # The on-coming friction linearly implicit in its slip: near lock the Stribeck slope of this
                # lining (mu1 > mu2 over v_s = 0.025 m/s) is about 230 Nm per rad/s, times the slip mobility
                # 1/I_t + i2^2/I_o = 100 1/(kg m^2): 2e4 1/s, far too stiff for an explicit substep.
                d = self._on_slope(abs(s_on0))
                if d > 0.0:
                    free = (tt - t_off) / It - i2 * (i1 * t_off - t_s) / Io - self.m_on * t_on
                    t_on += d * (hs * free / (1.0 + hs * self.m_on * d))
            self.wt += hs * (tt - t_on - t_off) / It
            self.wo += hs * (i2 * t_on + i1 * t_off - t_s) / Io
            self.ww += hs * (rf * t_s - t_road) / Iv
            if self.lock_on:      # keep the constraint exact against rounding
                jj = (self.wt - i2 * self.wo) / self.m_on
                self.wt -= jj / It
                self.wo += i2 * jj / Io
            elif self.lock_off:
                jj = (self.wt - i1 * self.wo) / self.m_off
                self.wt -= jj / It
                self.wo += i1 * jj / Io
            self.phi += hs * (self.wo - rf * self.ww)
            # friction work over the substep: the torque times the mean slip (exact for a linear slip change)
            if not self.lock_on:
                e_on += abs(t_on) * 0.5 * (abs(s_on0) + abs(self.wt - i2 * self.wo))
            if not self.lock_off:
                e_off += abs(t_off) * 0.5 * (abs(s_off0) + abs(self.wt - i1 * self.wo))
            if h != self.h:
                self.h = h
                self._set_film(h)
            # lock-up: a slipping clutch whose slip crossed zero
            if not self.lock_on:
                s = self.wt - i2 * self.wo
                if s != 0.0:
                    self.dir_on = 1.0 if s > 0 else -1.0
                if s * s_on0 <= 0.0 and s_on0 != 0.0:
                    self._try_lock("on", off_static, t_off)
            if not self.lock_off:
                s = self.wt - i1 * self.wo
                if s != 0.0:
                    self.dir_off = 1.0 if s > 0 else -1.0
                if s * s_off0 <= 0.0 and s_off0 != 0.0:
                    self._try_lock("off", off_static, t_on)
        # pressure lag (exact), heat into the pack (eq. 1, exact ZOH with the step's mean power)
        self.P = p_cmd + dp * lag[2 * n]
        self.current = i
        s_end = None if shift_time_s is None else shift_time_s + DT_S
        if i_off is None:
            self.off_current = None
            self.off_cap_now = self.off_static * self._off_fraction(s_end)
            self.P_off = self._off_equivalent_pressure(self.off_cap_now)
        else:
            self.off_current = i_off
            self.P_off = p_cmd_off + dp_off * self.off_lag[2 * n]
            self.off_cap_now = self._off_capacity(self.P_off)
        if e_d is not None:
            self.engine_Nm = e_tgt + e_d * self.engine_lag[2 * n]
            self._tt = self.engine_Nm
        self.power_on = e_on / n
        self.power_off = e_off / n
        th_ss = (self.power_on + self.k1 * self.oil_degC + self.k2 * self.housing_degC) / (self.k1 + self.k2)
        self.theta = th_ss + (self.theta - th_ss) * self.a_th
        self._set_theta(self.theta)
        self._set_film(self.h)
        self.t += DT_S
        self._draw_noise()
        self._truth = self._make_truth(self.off_cap_now)
        self._rows.append(tuple(self._truth[c] for c in TRUTH_NAMES))

    def _draw_noise(self):
        """Noise for the state just reached: slip, oil, housing, torque estimate, pressure ripple of the
        next step. Drawn in blocks (cheap, deterministic)."""
        if self._noise_k >= NOISE_BLOCK:
            self._noise = self.rng.standard_normal((NOISE_BLOCK, 5)).tolist()
            self._noise_off = self.rng_off.standard_normal(NOISE_BLOCK).tolist()
            self._noise_k = 0
        z = self._noise[self._noise_k]
        z_off = self._noise_off[self._noise_k]
        self._noise_k += 1
        p = self.params
        q = p.slip_resolution
        slip_rpm = (self.wt - self.i2 * self.wo) / RPM + p.slip_noise * z[0]
        tq = p.temperature_resolution
        self._sensors = {
            "slip_rpm": round(slip_rpm / q) * q,
            "oil_degC": round((self.oil_degC + p.temperature_noise * z[1]) / tq) * tq,
            "housing_degC": round((self.housing_degC + p.temperature_noise * z[2]) / tq) * tq,
            "turbine_torque_estimate_Nm": self.engine_Nm * (1.0 + p.torque_estimate_bias)
            + p.torque_estimate_noise * z[3],
        }
        if self._offgoing_sensor:
            off_rpm = (self.wt - self.i1 * self.wo) / RPM + p.slip_noise * z_off
            self._sensors["offgoing_slip_rpm"] = round(off_rpm / q) * q
        self.p_noise = p.pressure_noise * z[4]

    def _make_truth(self, off_static):
        t_on, t_off, t_s, t_road = self._torques(off_static, False)
        wo = self.wo
        return {
            "t_s": self.t,
            "turbine_speed_rpm": self.wt / RPM,
            "output_speed_rpm": wo / RPM,
            "gear1_speed_rpm": self.i1 * wo / RPM,
            "gear2_speed_rpm": self.i2 * wo / RPM,
            "vehicle_speed_m_s": self.ww * self.params.wheel_radius,
            "slip_rad_s": self.wt - self.i2 * wo,
            "offgoing_slip_rad_s": self.wt - self.i1 * wo,
            "clutch_torque_Nm": t_on,
            "clutch_capacity_Nm": self.on_static,
            "offgoing_torque_Nm": t_off,
            "offgoing_capacity_Nm": off_static,
            "driveshaft_torque_Nm": t_s,
            "turbine_torque_Nm": self.engine_Nm,
            "current_mA": self.current,
            "pressure_cmd_Pa": self.params.vfs_gain * self.current,
            "pressure_Pa": self._chamber_pressure(),
            "apply_force_N": self._force(self.P) if self.fill >= 1.0 else 0.0,
            "contact_force_N": self.f_c,
            "separation_m": self.h,
            "hbar_m": self.hbar,
            "theta_clutch_degC": self.theta,
            "vehicle_accel_m_s2": self.params.wheel_radius * (self.rf * t_s - t_road) / self.Iv,
            "oncoming_locked": float(self.lock_on),
            "offgoing_locked": float(self.lock_off),
            "friction_power_W": self.power_on,
            "offgoing_power_W": self.power_off,
            "engine_torque_Nm": self.engine_Nm,
            "engine_request_Nm": self.engine_request,
            "offgoing_current_mA": (self.P_off / self.params.offgoing_vfs_gain if self.off_current is None
                                    else self.off_current),
            "offgoing_pressure_Pa": self.P_off,
            "fill_fraction": self.fill,
            "output_torque_Nm": self.i2 * t_on + self.i1 * t_off,
            "vfs_pressure_Pa": self.P,
        }

    def _chamber_pressure(self):
        """The on-coming piston's pressure: the VFS pressure once filled; while filling the return spring's
        pressure at the stroke (at the stop: the VFS pressure up to the spring's)."""
        if self.fill >= 1.0:
            return self.P
        spring = self.p_kiss * (0.8 + 0.2 * self.fill)
        return min(self.P, spring) if self.fill <= 0.0 else spring

    def sensors(self) -> dict:
        """What the TCU receives this period (the state now): slip_rpm (noisy, 0.25 rpm steps), oil_degC,
        housing_degC (0.1 degC steps), turbine_torque_estimate_Nm (the actual engine torque, biased, noisy);
        with the off-going slip sensor (constructed with offgoing_current_mA, or offgoing_slip_sensor=True)
        also offgoing_slip_rpm (w_t - i1 w_o, as slip_rpm; its noise from a second generator, so the other
        channels are bit for bit those without it). Idempotent."""
        return dict(self._sensors)

    @property
    def truth(self) -> dict:
        """The true state now (after the last step): TRUTH_NAMES."""
        return dict(self._truth)

    def record(self) -> dict:
        """Every truth channel per period, the initial state first: {name: numpy array}."""
        arr = np.array(self._rows, dtype=float)
        return {c: arr[:, k].copy() for k, c in enumerate(TRUTH_NAMES)}


def initial_turbine_speed_rpm(params: PlantParams, *, oil_degC: float, turbine_torque_Nm: float,
                              speed_at_command_rpm: float | None = None, preroll_s: float | None = None,
                              **kwargs) -> float:
    """The turbine speed to start the plant at so that, after preroll_s of steady 1st gear (current 0),
    the turbine is at speed_at_command_rpm when the shift is commanded (defaults: the [scenario]
    turbine_speed and preroll_time). The 1st-gear acceleration is nearly constant: two corrections
    (the second only for the drag's and road load's drift) leave well under 0.1 rpm."""
    target = params.turbine_speed if speed_at_command_rpm is None else float(speed_at_command_rpm)
    n = int(round((params.preroll_time if preroll_s is None else float(preroll_s)) / DT_S))
    start = target
    for _ in range(2):
        pl = UpshiftPlant(params, oil_degC=oil_degC, turbine_torque_Nm=turbine_torque_Nm,
                          turbine_speed_rpm=start, **kwargs)
        off = kwargs.get("offgoing_current_mA")        # the whole shift: the TCU holds 1st gear
        for _ in range(n):
            pl.step(0.0, None, off)
        start -= pl.truth["turbine_speed_rpm"] - target
    return start
