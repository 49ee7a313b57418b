"""The bench simulation: a batch of experiments of one kind stepped together at 1 ms (simulate)."""
from __future__ import annotations

import math
import zlib

import numpy as np
from scipy.linalg import expm

from ...calibration import Calibration
from ...reference import model
from ...util import canlog
from .experiments import (BREAKAWAY_OFF_RPM, BREAKAWAY_RAMP_S, BREAKAWAY_RATE_NM_S, CAMPAIGN_FORCE_S,
                          CAMPAIGN_HOLD_S, CAMPAIGN_RAMP_DOWN_S, CAMPAIGN_RAMP_S, CSV_COLUMNS, DEFAULT_SEED,
                          ENGAGEMENT_CONTACT_S, NOISE_BLOCK, RPM, BenchConfig, BenchError, Experiment, Result,
                          check_seed)
from .physics import _Physics


# --------------------------------------------------------------------------- the simulation

class _Profile:
    """Commands per step, vectorized over a batch of experiments of one kind."""

    def __init__(self, exps: list[Experiment], dt: float, n_steps: int):
        self.kind = exps[0].kind
        self.dt = dt
        self.force = np.array([e.force_N for e in exps])
        self.no_force = np.zeros(len(exps))
        self.slip = np.array([e.slip_rpm for e in exps]) * RPM
        self.t_down = np.array([CAMPAIGN_HOLD_S + e.loading_s for e in exps])
        self.never = np.zeros(len(exps), dtype=bool)
        if self.kind == "thermal":
            t_grid = np.arange(n_steps + 1) * dt
            self.ref = np.empty((n_steps + 1, len(exps)))
            for j, e in enumerate(exps):
                times = np.array([s[0] for s in e.speed_steps])
                levels = np.array([s[1] for s in e.speed_steps]) * RPM
                idx = np.searchsorted(times, t_grid + 1e-12, side="right") - 1
                ramp = np.clip((t_grid - CAMPAIGN_RAMP_S) / (CAMPAIGN_HOLD_S - CAMPAIGN_RAMP_S), 0.0, 1.0)
                self.ref[:, j] = levels[idx] * np.where(t_grid < CAMPAIGN_HOLD_S, ramp, 1.0)

    def force_command(self, t: float):
        """The commanded force: one of two fixed arrays (so `is` tells an unchanged command)."""
        start = ENGAGEMENT_CONTACT_S if self.kind == "engagement" else CAMPAIGN_FORCE_S
        return self.force if t >= start - 1e-12 else self.no_force

    def speed_ref(self, k: int, t: float):
        if self.kind in ("engagement", "breakaway"):     # breakaway: torque-controlled, the reference unused
            return self.slip
        if self.kind == "thermal":
            return self.ref[k]
        up = np.clip((t - CAMPAIGN_RAMP_S) / (CAMPAIGN_HOLD_S - CAMPAIGN_RAMP_S), 0.0, 1.0)
        down = np.clip((self.t_down + CAMPAIGN_RAMP_DOWN_S - t) / CAMPAIGN_RAMP_DOWN_S, 0.0, 1.0)
        return self.slip * np.minimum(up, down)

    def torque_command(self, t: float) -> float:
        """Breakaway: the motor's torque ramp (torque control, no speed loop)."""
        return BREAKAWAY_RATE_NM_S * max(t - BREAKAWAY_RAMP_S, 0.0)

    def motor_enabled(self, t: float) -> bool:
        if self.kind == "engagement":
            return t < ENGAGEMENT_CONTACT_S - 1e-12
        if self.kind == "breakaway":
            return t >= BREAKAWAY_RAMP_S - 1e-12
        return t >= CAMPAIGN_RAMP_S - 1e-12

    def off_at_zero(self, t: float):
        """Campaign: the motor is switched off when the speed reaches zero in the ramp-down (3.2)."""
        if self.kind != "table2":
            return self.never
        return t >= self.t_down

    def mode(self, t: float):
        start = ENGAGEMENT_CONTACT_S if self.kind == "engagement" else CAMPAIGN_FORCE_S
        return canlog.MODE_TORQUE_CONTROL if t >= start - 1e-12 else canlog.MODE_OPEN


def _noise_generators(exps, seed):
    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, zlib.crc32(e.name.encode())])))
            for e in exps]


TRUTH_NAMES = ("theta_degC", "theta_oil_degC", "theta_housing_degC", "slip_rpm", "motor_speed_rpm",
               "torque_Nm", "clutch_torque_Nm", "coulomb_Nm", "viscous_Nm", "static_capacity_Nm",
               "force_N", "contact_force_N", "separation_m", "separation_ss_m", "hbar_m", "power_W",
               "motor_torque_Nm", "locked")


def simulate(true_cal: Calibration, exps: list[Experiment], seed: int = DEFAULT_SEED,
             config: BenchConfig = BenchConfig(), every: int = 1) -> list[Result]:
    """Run a batch of experiments of one kind together; rows every `every` steps (1 ms each).

    Row k holds the measurements and true states at t = k dt; the step then
    advances every state to t + dt with its inputs held (exact first-order
    updates: actuator, eq. 1, oil, housing, thermistors, locked shaft; the
    squeeze film by RK4 substeps, _Physics.film_step).
    """
    if not exps:
        return []
    kinds = {e.kind for e in exps}
    if len(kinds) != 1:
        raise BenchError(f"one kind of experiment per batch, got {sorted(kinds)}")
    seed = check_seed(seed)
    cfg = config
    if isinstance(cfg.film_substeps, bool) or not isinstance(cfg.film_substeps, int) or cfg.film_substeps < 1:
        raise BenchError(f"film_substeps {cfg.film_substeps!r}: a whole number >= 1 is expected")
    dt = cfg.dt_s
    n = len(exps)
    steps = np.array([int(round(e.duration_s / dt)) for e in exps])
    n_steps = int(steps.max())
    prof = _Profile(exps, dt, n_steps)
    film = model.FilmTable(true_cal, cfg.film_table_nodes)     # h_ss(F_app / A_f): eq. 15/16 inverted
    area = true_cal.friction_area
    phys = _Physics(true_cal, dt, cfg.actuator_time_constant_s, cfg.film_substeps)
    gens = _noise_generators(exps, seed)

    k1, k2, cap = true_cal.oil_conductance, true_cal.housing_conductance, true_cal.heat_capacity
    J = cfg.inertia_kg_m2
    a_clutch = math.exp(-(k1 + k2) * dt / cap)
    a_act = math.exp(-dt / cfg.actuator_time_constant_s)
    a_thermistor = math.exp(-dt / cfg.thermistor_time_constant_s)
    a_request = math.exp(-dt / cfg.request_filter_s)
    g_oil = k1 / cfg.oil_flow_conductance_W_per_K
    a_oil = math.exp(-(1.0 + g_oil) * dt / cfg.oil_time_constant_s)
    g_loss = cfg.housing_loss_W_per_K
    a_house = math.exp(-(k2 + g_loss) * dt / cfg.housing_heat_capacity_J_per_K)
    wn = 2.0 * math.pi * cfg.shaft_frequency_Hz
    k_shaft = J * wn * wn
    c_shaft = 2.0 * cfg.shaft_damping_ratio * J * wn
    # Exact zero-order-hold discretization of the locked inertia on the shaft:
    # x = [twist, inertia speed], J w' = T_motor - k twist - c w.
    aug = np.zeros((3, 3))
    aug[:2, :2] = [[0.0, 1.0], [-k_shaft / J, -c_shaft / J]]
    aug[1, 2] = 1.0 / J
    ead = expm(aug * dt)
    (a00, a01), (a10, a11) = ead[:2, :2]
    b0, b1 = ead[:2, 2]
    kp = J * cfg.speed_bandwidth_rad_s
    ki = kp * cfg.speed_bandwidth_rad_s / 4.0
    t_lim = cfg.motor_torque_limit_Nm
    sig = np.array([cfg.speed_noise_rpm, cfg.load_cell_noise_N, cfg.torque_noise_Nm,
                    cfg.thermistor_noise_K, cfg.thermistor_noise_K, cfg.thermistor_noise_K])

    # Initial state.
    theta0 = np.array([e.theta0_degC for e in exps])
    theta = theta0.copy()
    oil = theta0.copy()
    house = np.array([e.theta0_degC if e.housing0_degC is None else e.housing0_degC for e in exps])
    m_theta, m_oil, m_house = theta.copy(), oil.copy(), house.copy()       # thermistor states
    f_app = np.zeros(n)
    h = film.separation_from_pressure_m(f_app / area)
    film_settled = np.zeros(n, dtype=bool)   # the last step left h and F_app unchanged (see the film update)
    film_cmd = np.zeros(n)                   # the force command of that step
    all_settled = False
    if prof.kind == "engagement":
        w = prof.slip.copy()                 # spinning at the initial slip, clutch open
        locked = np.zeros(n, dtype=bool)
        integ = phys.clutch(h, w, theta)[0]  # speed loop preloaded with the open-clutch drag
    else:
        w = np.zeros(n)                      # at rest, clutch held by its own static friction
        locked = np.ones(n, dtype=bool)
        integ = np.zeros(n)
    twist = np.zeros(n)
    motor_off = np.zeros(n, dtype=bool)      # latched off (campaign: at zero speed)
    request = None

    rows = (n_steps + every - 1) // every
    meas = {c: np.empty((rows, n)) for c in CSV_COLUMNS}
    truth = {c: np.empty((rows, n)) for c in TRUTH_NAMES}
    modes = np.empty(rows, dtype=int)
    t_rows = np.empty(rows)
    noise = None

    for k in range(n_steps):
        t = k * dt
        if k % NOISE_BLOCK == 0:
            noise = np.stack([g.standard_normal((NOISE_BLOCK, sig.size)) for g in gens], axis=2) * sig[None, :, None]
        nz = noise[k % NOISE_BLOCK]

        # Clutch at time t from the film state; stick -> slip when the shaft
        # torque of a locked clutch exceeds the static capacity. (Branches on
        # "any locked" only skip work: both give the same numbers.)
        any_locked = bool(locked.any())
        hub = np.where(locked, 0.0, w) if any_locked else w
        t_clutch, coulomb, viscous, f_c, hbar, t_static = phys.clutch(h, np.abs(hub), theta)
        shaft_locked = k_shaft * twist + c_shaft * w
        if any_locked:
            breakaway = locked & (np.abs(shaft_locked) > t_static)
            if breakaway.any():
                locked = locked & ~breakaway
                hub = np.where(locked, 0.0, w)
                t_clutch, coulomb, viscous, f_c, hbar, t_static = phys.clutch(h, np.abs(hub), theta)
        direction = np.sign(w)
        still = direction == 0.0
        if still.any():      # at rest: the direction the shaft pushes (break-away)
            direction = np.where(still, np.where(shaft_locked < 0.0, -1.0, 1.0), direction)
        signed_clutch = direction * t_clutch
        if any_locked:
            shaft = np.where(locked, shaft_locked, signed_clutch)
            power = np.where(locked, 0.0, t_clutch * np.abs(w))
        else:
            shaft = signed_clutch
            power = t_clutch * np.abs(w)

        # Sensors.
        slip_meas = hub * (1.0 / RPM) + nz[0]
        speed_meas = w * (1.0 / RPM) + nz[0]          # the motor's speed loop sees the inertia
        torque_meas = shaft + nz[2]
        request = np.maximum(torque_meas, 0.0) if request is None else torque_meas + (request - torque_meas) * a_request

        enabled = prof.motor_enabled(t) & ~motor_off
        off_zero = prof.off_at_zero(t)
        if prof.kind == "breakaway":
            # Torque control: the ramp until the measured slip passes BREAKAWAY_OFF_RPM, then off.
            torque_motor = np.full(n, min(prof.torque_command(t), t_lim))
            motor_off |= enabled & (np.abs(slip_meas) > BREAKAWAY_OFF_RPM)
        else:
            # Motor: PI speed control with feed-forward, torque limit, conditional integration.
            ref = prof.speed_ref(k, t)
            err = ref - speed_meas * RPM
            raw = J * (prof.speed_ref(k + 1, t + dt) - ref) / dt + kp * err + integ
            torque_motor = np.minimum(np.maximum(raw, -t_lim), t_lim)
            integrate = enabled & ((raw == torque_motor) | (np.sign(err) != np.sign(raw)))
            integ = integ + (ki * dt) * err * integrate
            motor_off |= enabled & off_zero & (speed_meas <= 0.0)
        torque_motor = torque_motor * (enabled & ~motor_off)

        if k % every == 0:
            h_target = film.separation_from_pressure_m(f_app / area)     # the steady film under F_app
            r = k // every
            t_rows[r] = t
            modes[r] = prof.mode(t)
            meas["t_s"][r] = t
            meas["slip_rpm"][r] = slip_meas
            meas["force_N"][r] = f_app + nz[1]
            meas["torque_Nm"][r] = torque_meas
            meas["theta_clutch_degC"][r] = m_theta + nz[3]
            meas["theta_oil_degC"][r] = m_oil + nz[4]
            meas["theta_housing_degC"][r] = m_house + nz[5]
            meas["torque_request_Nm"][r] = np.maximum(request, 0.0)
            slipping = ~locked
            for c, v in (("theta_degC", theta), ("theta_oil_degC", oil), ("theta_housing_degC", house),
                         ("slip_rpm", hub / RPM), ("motor_speed_rpm", w / RPM), ("torque_Nm", shaft),
                         ("clutch_torque_Nm", signed_clutch * slipping), ("coulomb_Nm", direction * coulomb * slipping),
                         ("viscous_Nm", direction * viscous * slipping), ("static_capacity_Nm", t_static),
                         ("force_N", f_app), ("contact_force_N", f_c), ("separation_m", h),
                         ("separation_ss_m", h_target), ("hbar_m", hbar), ("power_W", power),
                         ("motor_torque_Nm", torque_motor), ("locked", locked)):
                truth[c][r] = v

        # Advance to t + dt, inputs held over the step.
        th_ss = (power + k1 * oil + k2 * house) / (k1 + k2)                    # eq. 1, exact ZOH
        oil_ss = (theta0 + g_oil * theta) / (1.0 + g_oil)
        house_ss = (k2 * theta + g_loss * theta0) / (k2 + g_loss)
        m_theta = theta + (m_theta - theta) * a_thermistor
        m_oil = oil + (m_oil - oil) * a_thermistor
        m_house = house + (m_house - house) * a_thermistor
        theta = th_ss + (theta - th_ss) * a_clutch
        oil = oil_ss + (oil - oil_ss) * a_oil
        house = house_ss + (house - house_ss) * a_house
        f_cmd = prof.force_command(t)
        f_app_next = f_cmd + (f_app - f_cmd) * a_act
        if phys.phi == 0.0:
            # film state off (calibration: film_squeeze_factor 0): the paper's steady film, F_c = F_app
            h = film.separation_from_pressure_m(f_app_next / area)
        elif not (all_settled and f_cmd is film_cmd):
            # The squeeze film. A step that left both h and the actuator force unchanged to the last bit
            # found the film at its equilibrium F_c(h) = F_app, which the viscosity (the one input that
            # still changes) does not move (F_h = 0 there): the film is not integrated again until the
            # force command changes, so the runs at constant force cost nothing more once settled. Per
            # experiment, so a run gives the same numbers alone or in a batch. (When all are settled
            # under the same command, nothing changes: not even the checks are repeated.)
            active = ~(film_settled & (f_cmd == film_cmd))
            if active.all():
                h_next = phys.film_step(h, f_app, f_cmd, theta)
            elif active.any():
                idx = np.flatnonzero(active)
                h_next = h.copy()
                h_next[idx] = phys.film_step(h[idx], f_app[idx], f_cmd[idx], theta[idx])
            else:
                h_next = h
            film_settled = (h_next == h) & (f_app_next == f_app)
            all_settled = bool(film_settled.all())
            film_cmd = f_cmd
            h = h_next
        f_app = f_app_next

        # Mechanics: slipping inertia (rigid to the hub), or locked inertia on the shaft.
        w_slip = w + dt * (torque_motor - signed_clutch) / J
        crossed = w_slip * direction <= 0.0
        if any_locked:
            crossed &= ~locked
        if not any_locked and not crossed.any():
            w = w_slip
            continue
        switch_off = crossed & off_zero & enabled
        motor_off |= switch_off
        lock_now = crossed & (np.abs(torque_motor * ~motor_off) <= t_static)
        # On locking, the shaft still carries the torque the clutch transmitted (at
        # most the static capacity: the hub slides the rest off within the step).
        lock_twist = direction * np.minimum(t_clutch, t_static) / k_shaft
        new_twist = np.where(locked, a00 * twist + a01 * w + b0 * torque_motor, np.where(lock_now, lock_twist, twist))
        w = np.where(locked, a10 * twist + a11 * w + b1 * torque_motor, np.where(lock_now, 0.0, w_slip))
        twist = new_twist
        locked = locked | lock_now

    results = []
    for j, e in enumerate(exps):
        m = int(math.ceil(steps[j] / every))
        results.append(Result(e, t_rows[:m].copy(), {c: meas[c][:m, j].copy() for c in CSV_COLUMNS},
                              {c: truth[c][:m, j].copy() for c in TRUTH_NAMES}, modes[:m].copy(), every))
    return results
