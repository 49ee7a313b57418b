"""The bench, simulated (DESIGN.md section 7): richer than the control model.

The paper's bench data are not public, so identification and the HIL replay
run against this simulator. It is deliberately richer than the control model
(DESIGN 2), in double precision, vectorized over experiments (NumPy), seeded:

- a TRUE parameter set (tools/calibrations/bench_true.toml, same schema as
  table1.toml) that differs from Table 1 by a few percent;
- squeeze-film dynamics: the nominal separation h approaches its steady state
  h_ss(F_app) (eq. 15/16 inverted through a dense double table) with a first-
  order time constant tau_film; the asperities carry F_c = A_f p_c(h) (at most
  F_app: the film carries no tension), the oil film the rest; h_bar(h) by
  eq. 9; torque by eq. 8 with the true parameters; open-clutch film clamped at
  h_max like the model (model.film_domain);
- a linear actuator: first-order lag to the commanded apply force, measured
  by a load cell with noise;
- a speed-controlled motor (PI with feed-forward, torque limit, anti-windup)
  driving a rotating inertia J through a torsionally elastic shaft to the
  clutch hub; stick (static capacity mu_f(0, theta) F_c R_eff N_c) and slip;
  after lock the shaft rings (paper Fig. 15);
- the clutch pack of eq. 1 with the true k1, k2, C (exact zero-order hold),
  oil and housing temperatures that drift (oil warmed by the heat it picks
  up, housing slowly towards the clutch), thermistors with a first-order lag;
- sensor noise on the speed encoder, load cell, torque sensor, thermistors.

Experiments (protocols; numbers in BenchConfig and the constants below):

engagement  paper Fig. 15. At t = 0 the shaft spins at the initial slip (750,
            500 or 250 rpm), clutch open (no force, film at h_max), clutch, oil
            and housing at 40 degC; the motor holds the speed against the open-
            clutch drag. At t = 0.9 s (contact) the force command steps to
            1188 N and the motor is switched off: the clutch brakes the inertia
            to lock. After lock the hub stands still and the torque sensor
            reads the shaft torque: the twist the shaft carried at lock rings
            down (20 Hz, damping ratio 0.3) to zero, because with the motor
            off the locked clutch has nothing else to hold. 2.5 s.
table2      the 184 experiments of Table 2 (section 3.2, Fig. 9): at rest,
            force on at 0.5 s (the film settles first), motor on at 2 s and a
            speed ramp to the initial slip by 4 s, hold for the loading period,
            ramp down over 20 s, motor off at zero speed, 1 s more.
thermal     Fig. 13: 1188 N throughout, oil at 50 degC, housing starting at
            42 degC; (a) small frequent steps (100..250 rpm, held 4..8 s, seeded),
            (b) one large step (60 -> 400 -> 60 rpm). 240 s each.

Measurements (CSV_COLUMNS): slip from the encoder (noise 0.5 rpm), load cell
(3 N), torque sensor (1 Nm; the shaft torque, i.e. the clutch torque while
slipping), clutch/oil/housing thermistors (0.15 s lag, 0.1 K).
torque_request_Nm is what the TCU would be asked for: the measured torque
through a 10 ms first-order filter, clipped at >= 0 (sent with Mode Open
before contact, TorqueControl from contact on).

The simulation step is 1 ms. Every experiment writes a measurement CSV and,
by default for the engagement only, the candump -L log of the frames the TCU
receives (canlog.input_log / canlog.write_log, one period per ms); table2
and thermal CSVs are decimated to 10 ms unless the logs are asked for.

Noise: one generator per experiment, seeded from (seed, crc32(name)), drawn
in blocks of NOISE_BLOCK steps, so an experiment gives the same numbers alone
or in a batch and the files regenerate byte-identically for a given seed.
"""
from __future__ import annotations

import math
import os
import re
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.linalg import expm
from scipy.special import erf, erfc

from . import atomic, calibration, canlog, model
from .calibration import Calibration

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_TRUE = ROOT / "tools" / "calibrations" / "bench_true.toml"
DEFAULT_SEED = 1
EXPERIMENTS = ("engagement", "table2", "thermal")
CSV_COLUMNS = ("t_s", "slip_rpm", "force_N", "torque_Nm", "theta_clutch_degC", "theta_oil_degC",
               "theta_housing_degC", "torque_request_Nm")
CSV_FORMATS = ("%.3f", "%.3f", "%.2f", "%.3f", "%.3f", "%.3f", "%.3f", "%.3f")
NOISE_BLOCK = 1000
CAMPAIGN_EVERY = 10        # table2 and thermal CSV rows every 10 ms unless logs are asked for
RPM = model.RAD_S_PER_RPM

# The engagement (paper Fig. 15, section 3.5).
ENGAGEMENT_SLIPS_RPM = (750.0, 500.0, 250.0)
ENGAGEMENT_FORCE_N = 1188.0          # 293.1 kPa on A_f
ENGAGEMENT_CONTACT_S = 0.9
ENGAGEMENT_DURATION_S = 2.5
ENGAGEMENT_THETA0_DEGC = 40.0        # oil, housing and clutch at the start (the paper does not say)

# The Table 2 campaign (section 3.2, Fig. 9).
TABLE2_FORCES_N = (903.0, 1076.0, 1350.0, 1613.0)
TABLE2_SLIPS_RPM = (100.0, 200.0, 300.0)
TABLE2_LOADING_S = (5.0, 10.0)
TABLE2_THETA0_DEGC = tuple(float(t) for t in range(10, 101, 10))
TABLE2_COUNT = 184
CAMPAIGN_FORCE_S = 0.5     # apply force stepped on (the film settles before rotation)
CAMPAIGN_RAMP_S = 2.0      # motor on, speed ramp from 0 ...
CAMPAIGN_HOLD_S = 4.0      # ... reached: loading period starts (as in Fig. 9)
CAMPAIGN_RAMP_DOWN_S = 20.0
CAMPAIGN_TAIL_S = 1.0      # recorded after the speed reference reaches 0

# The thermal identification runs (section 3.4, Fig. 13).
THERMAL_FORCE_N = 1188.0
THERMAL_OIL0_DEGC = 50.0
THERMAL_HOUSING0_DEGC = 42.0   # housing not yet warmed through: k1 and k2 separable
THERMAL_DURATION_S = 240.0


class BenchError(RuntimeError):
    """Bad input to the bench simulator (the message says which)."""


@dataclass(frozen=True)
class BenchConfig:
    """What the bench is made of beyond the clutch parameters (documented choices)."""

    dt_s: float = 1e-3
    # Rotating inertia: Fig. 15 brakes 750 rpm (78.5 rad/s) to lock about 1 s
    # after contact. J = (mean braking torque) t / dw: with this clutch the torque
    # peaks at about 152 Nm and averages about 120 Nm over the braking (viscous
    # part falling with the slip, Stribeck dip at the end), so J = 1.6 kg m^2
    # (a 150 Nm average would give the 2 kg m^2 of a first estimate).
    inertia_kg_m2: float = 1.6
    # Squeeze film, paper 2.5: "0.05 to 0.1 s". 0.055 s: the 750 rpm transient
    # then peaks at about 152 Nm total, 68 Nm viscous (paper: up to 180 / 54.6 Nm);
    # at 0.07 s the film lag holds the peak to 147 Nm.
    film_time_constant_s: float = 0.055
    actuator_time_constant_s: float = 0.015
    # Shaft from the inertia to the clutch hub (massless hub): after lock the
    # inertia rings on it (Fig. 15, "torsional stiffness of the shaft").
    shaft_frequency_Hz: float = 20.0
    shaft_damping_ratio: float = 0.3
    motor_torque_limit_Nm: float = 300.0    # 120 Nm motor through the torque-amplifier gear (3.1)
    speed_bandwidth_rad_s: float = 30.0     # PI: Kp = J wc, Ki = Kp wc / 4, plus J dw_ref/dt
    speed_noise_rpm: float = 0.5
    load_cell_noise_N: float = 3.0
    torque_noise_Nm: float = 1.0
    # The clutch thermistor sits in a side hole of the steel separator in liquid
    # metal paste (73 W/mK); the paper takes it as reading the friction surface
    # (3.1). 0.15 s: a bead thermistor in metal contact; oil/housing the same.
    thermistor_time_constant_s: float = 0.15
    thermistor_noise_K: float = 0.1
    request_filter_s: float = 0.010         # torque_request_Nm: measured torque, 10 ms first order, >= 0
    # Oil: 10 L/min of ATF (850 kg/m^3, 2000 J/kgK) = 283 W/K; the measured oil
    # temperature is the mean of inlet and outlet: it rises by k1 (th - th_oil) / 566 W/K,
    # mixed in with a 20 s lag.
    oil_flow_conductance_W_per_K: float = 566.0
    oil_time_constant_s: float = 20.0
    # Housing: a lumped steel mass heated by the pack through k2, losing heat to
    # its surroundings at the experiment's initial temperature.
    housing_heat_capacity_J_per_K: float = 8000.0
    housing_loss_W_per_K: float = 40.0
    # Break-away: the static capacity is the Coulomb torque at zero slip times
    # (1 + margin); the margin keeps a just-locked clutch from chattering.
    stiction_margin: float = 0.02
    film_table_nodes: int = 20001


@dataclass(frozen=True)
class Experiment:
    name: str
    kind: str
    force_N: float
    slip_rpm: float
    theta0_degC: float
    duration_s: float
    loading_s: float = 0.0
    housing0_degC: float | None = None
    speed_steps: tuple = ()          # thermal: ((t_s, rpm), ...) piecewise constant from t_s
    id: int = 0


@dataclass
class Result:
    experiment: Experiment
    t_s: np.ndarray
    measured: dict              # CSV_COLUMNS -> array
    truth: dict                 # hidden states (true temperatures, h, h_bar, torques, ...)
    mode: np.ndarray            # TorqueRequest Mode per row (canlog.MODE_*)
    every: int = 1              # rows are every `every` simulation steps


# --------------------------------------------------------------------------- experiments

def engagement_experiments(slips_rpm=ENGAGEMENT_SLIPS_RPM) -> list[Experiment]:
    out = []
    for i, slip in enumerate(slips_rpm):
        slip = _check_slip(slip)
        out.append(Experiment(name=f"engagement_{slip:g}rpm", kind="engagement", force_N=ENGAGEMENT_FORCE_N,
                              slip_rpm=slip, theta0_degC=ENGAGEMENT_THETA0_DEGC,
                              duration_s=ENGAGEMENT_DURATION_S, id=i + 1))
    return out


def table2_experiments() -> list[Experiment]:
    """The 184 experiments of Table 2 / section 3.2, in a fixed order."""
    out = []
    for theta0 in TABLE2_THETA0_DEGC:
        forces = TABLE2_FORCES_N if theta0 > 30.0 else TABLE2_FORCES_N[:1]     # only 903 N at <= 30 degC
        slips = TABLE2_SLIPS_RPM if theta0 > 10.0 else TABLE2_SLIPS_RPM[:2]    # only 100/200 rpm at 10 degC
        for force in forces:
            for slip in slips:
                for loading in TABLE2_LOADING_S:
                    i = len(out) + 1
                    duration = CAMPAIGN_HOLD_S + loading + CAMPAIGN_RAMP_DOWN_S + CAMPAIGN_TAIL_S
                    out.append(Experiment(
                        name=f"t2_{i:03d}_{force:.0f}N_{slip:.0f}rpm_{loading:.0f}s_{theta0:.0f}C", kind="table2",
                        force_N=force, slip_rpm=slip, theta0_degC=theta0, duration_s=duration, loading_s=loading,
                        id=i))
    if len(out) != TABLE2_COUNT:
        raise AssertionError(f"Table 2 campaign has {len(out)} experiments, the paper {TABLE2_COUNT}")
    return out


def thermal_experiments(seed: int) -> list[Experiment]:
    """Fig. 13: (a) small, frequent slip-speed steps; (b) one large step. Constant force."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(b"thermal_small_steps_profile")]))
    small = [(0.0, 150.0)]
    t = CAMPAIGN_HOLD_S
    while t < THERMAL_DURATION_S - 4.0:
        small.append((t, float(np.round(rng.uniform(100.0, 250.0), 0))))
        t += float(np.round(rng.uniform(4.0, 8.0), 1))
    large = [(0.0, 60.0), (30.0, 400.0), (120.0, 60.0)]
    common = dict(kind="thermal", force_N=THERMAL_FORCE_N, theta0_degC=THERMAL_OIL0_DEGC,
                  housing0_degC=THERMAL_HOUSING0_DEGC, duration_s=THERMAL_DURATION_S)
    return [Experiment(name="thermal_small_steps", slip_rpm=150.0, speed_steps=tuple(small), id=1, **common),
            Experiment(name="thermal_large_step", slip_rpm=60.0, speed_steps=tuple(large), id=2, **common)]


def _check_slip(slip) -> float:
    try:
        value = float(slip)
    except (TypeError, ValueError):
        raise BenchError(f"slip {slip!r} is not a number (rpm)") from None
    if not math.isfinite(value) or not 0.0 < value <= 3000.0:
        raise BenchError(f"slip {slip!r} rpm out of range: the bench runs 0 < slip <= 3000 rpm")
    return value


def check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        try:
            text = str(seed).strip()
            seed = int(text, 10)
        except (TypeError, ValueError):
            raise BenchError(f"seed {seed!r} is not a whole number >= 0") from None
    if seed < 0:
        raise BenchError(f"seed {seed} is negative: a whole number >= 0 is expected")
    return int(seed)


# --------------------------------------------------------------------------- the simulation

class _Profile:
    """Commands per step, vectorized over a batch of experiments of one kind."""

    def __init__(self, exps: list[Experiment], dt: float, n_steps: int):
        self.kind = exps[0].kind
        self.dt = dt
        self.force = np.array([e.force_N for e in exps])
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
        start = ENGAGEMENT_CONTACT_S if self.kind == "engagement" else CAMPAIGN_FORCE_S
        return self.force if t >= start - 1e-12 else np.zeros_like(self.force)

    def speed_ref(self, k: int, t: float):
        if self.kind == "engagement":
            return self.slip
        if self.kind == "thermal":
            return self.ref[k]
        up = np.clip((t - CAMPAIGN_RAMP_S) / (CAMPAIGN_HOLD_S - CAMPAIGN_RAMP_S), 0.0, 1.0)
        down = np.clip((self.t_down + CAMPAIGN_RAMP_DOWN_S - t) / CAMPAIGN_RAMP_DOWN_S, 0.0, 1.0)
        return self.slip * np.minimum(up, down)

    def motor_enabled(self, t: float) -> bool:
        if self.kind == "engagement":
            return t < ENGAGEMENT_CONTACT_S - 1e-12
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


class _Physics:
    """The true clutch in closed form (eq. 2, 8, 9, 15, 18), constants precomputed for the loop."""

    def __init__(self, cal: Calibration, stiction: float):
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
        self.stiction = 1.0 + stiction

    def clutch(self, h, f_app, w_abs, theta):
        """(|T|, |T_c|, |T_v|, F_c, h_bar, static capacity) for separation h, apply force, |slip|."""
        x = h * self.inv_s_sqrt2
        ex = np.exp(-x * x)
        p_c = self.pc_k * (ex - (h / self.s) * self.sqrt_pi_2 * erfc(x))
        f_c = np.minimum(self.area * p_c, np.maximum(f_app, 0.0))        # the film carries no tension
        hbar = 0.5 * h * (1.0 + erf(x)) + self.hbar_k * ex
        speed = self.r_eff * w_abs
        temp = 1.0 + self.mu3_th2 * (theta - self.th1)
        mv1, mv2, mv3, mv4 = self.mv
        coulomb = self.rn * (self.mu1 + self.dmu * np.exp(-speed / self.vs)) * temp * f_c
        viscous = self.rn * (mv1 * np.exp(mv2 * theta) + mv3 * np.exp(mv4 * theta)) * self.area * speed / hbar
        static = self.rn * self.mu2 * temp * f_c * self.stiction
        return coulomb + viscous, coulomb, viscous, f_c, hbar, static


TRUTH_NAMES = ("theta_degC", "theta_oil_degC", "theta_housing_degC", "slip_rpm", "motor_speed_rpm",
               "torque_Nm", "clutch_torque_Nm", "coulomb_Nm", "viscous_Nm", "static_capacity_Nm",
               "force_N", "contact_force_N", "separation_m", "separation_ss_m", "hbar_m", "power_W",
               "motor_torque_Nm", "locked")


def simulate(true_cal: Calibration, exps: list[Experiment], seed: int = DEFAULT_SEED,
             config: BenchConfig = BenchConfig(), every: int = 1) -> list[Result]:
    """Run a batch of experiments of one kind together; rows every `every` steps (1 ms each).

    Row k holds the measurements and true states at t = k dt; the step then
    advances every state to t + dt with its inputs held (exact first-order
    updates: actuator, film, eq. 1, oil, housing, thermistors, locked shaft).
    """
    if not exps:
        return []
    kinds = {e.kind for e in exps}
    if len(kinds) != 1:
        raise BenchError(f"one kind of experiment per batch, got {sorted(kinds)}")
    seed = check_seed(seed)
    cfg = config
    dt = cfg.dt_s
    n = len(exps)
    steps = np.array([int(round(e.duration_s / dt)) for e in exps])
    n_steps = int(steps.max())
    prof = _Profile(exps, dt, n_steps)
    film = model.FilmTable(true_cal, cfg.film_table_nodes)     # h_ss(F_app / A_f): eq. 15/16 inverted
    area = true_cal.friction_area
    phys = _Physics(true_cal, cfg.stiction_margin)
    gens = _noise_generators(exps, seed)

    k1, k2, cap = true_cal.oil_conductance, true_cal.housing_conductance, true_cal.heat_capacity
    J = cfg.inertia_kg_m2
    a_clutch = math.exp(-(k1 + k2) * dt / cap)
    a_act = math.exp(-dt / cfg.actuator_time_constant_s)
    a_film = math.exp(-dt / cfg.film_time_constant_s)
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
    if prof.kind == "engagement":
        w = prof.slip.copy()                 # spinning at the initial slip, clutch open
        locked = np.zeros(n, dtype=bool)
        integ = phys.clutch(h, f_app, w, theta)[0]     # speed loop preloaded with the open-clutch drag
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
        t_clutch, coulomb, viscous, f_c, hbar, t_static = phys.clutch(h, f_app, np.abs(hub), theta)
        shaft_locked = k_shaft * twist + c_shaft * w
        if any_locked:
            breakaway = locked & (np.abs(shaft_locked) > t_static)
            if breakaway.any():
                locked = locked & ~breakaway
                hub = np.where(locked, 0.0, w)
                t_clutch, coulomb, viscous, f_c, hbar, t_static = phys.clutch(h, f_app, np.abs(hub), theta)
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

        # Motor: PI speed control with feed-forward, torque limit, conditional integration.
        ref = prof.speed_ref(k, t)
        enabled = prof.motor_enabled(t) & ~motor_off
        err = ref - speed_meas * RPM
        raw = J * (prof.speed_ref(k + 1, t + dt) - ref) / dt + kp * err + integ
        torque_motor = np.minimum(np.maximum(raw, -t_lim), t_lim)
        integrate = enabled & ((raw == torque_motor) | (np.sign(err) != np.sign(raw)))
        integ = integ + (ki * dt) * err * integrate
        off_zero = prof.off_at_zero(t)
        motor_off |= enabled & off_zero & (speed_meas <= 0.0)
        torque_motor = torque_motor * (enabled & ~motor_off)

        h_target = film.separation_from_pressure_m(f_app / area)
        if k % every == 0:
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
        h = h_target + (h - h_target) * a_film
        f_cmd = prof.force_command(t)
        f_app = f_cmd + (f_app - f_cmd) * a_act

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


# --------------------------------------------------------------------------- files

def _prepare_dir(out_dir) -> Path:
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".wetclutch-bench-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise BenchError(f"{out}: cannot write to the output directory: {e.strerror or e}") from None
    return out


def write_csv(path: Path, result: Result) -> None:
    """The measurement CSV: CSV_COLUMNS, rounded to CSV_FORMATS (no '-0.000')."""
    cols = [np.round(result.measured[c], int(f[2])) + 0.0 for c, f in zip(CSV_COLUMNS, CSV_FORMATS)]
    fmt = ",".join(CSV_FORMATS)
    lines = [",".join(CSV_COLUMNS)]
    lines += [fmt % tuple(row) for row in np.column_stack(cols).tolist()]
    atomic.write_text(path, "\n".join(lines) + "\n")


def write_log(path: Path, result: Result) -> int:
    """The frames the TCU receives (candump -L, 1 ms): TorqueRequest (Mode Open before
    contact, TorqueControl from contact on), BenchMeasurement, ClutchSensors."""
    if result.every != 1:
        raise BenchError(f"{path}: a CAN log needs every 1 ms step (rows every {result.every} steps)")
    m = result.measured
    msgs = canlog.input_log(result.t_s, m["slip_rpm"], m["theta_oil_degC"], m["theta_housing_degC"],
                            m["torque_request_Nm"], mode=result.mode,
                            bench={"load_cell_N": m["force_N"], "torque_Nm": m["torque_Nm"],
                                   "thermistor_degC": m["theta_clutch_degC"]})
    with atomic.atomic_path(path) as tmp:
        canlog.write_log(tmp, msgs)
    return len(msgs)


def write_index(path: Path, cal: Calibration, results: list[Result]) -> None:
    lines = ["id,force_N,pressure_kPa,slip_rpm,loading_s,theta0_degC,file"]
    for r in results:
        e = r.experiment
        lines.append(f"{e.id},{e.force_N:.1f},{e.force_N / cal.friction_area * 1e-3:.1f},{e.slip_rpm:.0f},"
                     f"{e.loading_s:.0f},{e.theta0_degC:.0f},{e.name}.csv")
    atomic.write_text(path, "\n".join(lines) + "\n")


def write_viscosity(path: Path, cal: Calibration, seed: int, noise: float = 0.01) -> None:
    """Viscosity points for the eq. 2 fit: the true curve with ~1% (1 sigma) noise, 10..120 degC."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(b"viscosity")]))
    theta = np.arange(10.0, 121.0, 10.0)
    mu = model.viscosity_Pa_s(cal, theta) * (1.0 + noise * rng.standard_normal(theta.size))
    atomic.write_text(path, "theta_degC,viscosity_Pa_s\n" + "".join(f"{t:.0f},{m:.6e}\n" for t, m in zip(theta, mu)))


def run(kind: str, out_dir, true_path=DEFAULT_TRUE, seed=DEFAULT_SEED, slips_rpm=None, logs: bool | None = None,
        every: int | None = None, config: BenchConfig = BenchConfig(), experiments=None) -> dict:
    """Generate one experiment set into out_dir. Returns {'files': [...], 'results': [...]}.

    Defaults: the engagement writes CSV and log at 1 ms; table2 and thermal write
    CSVs decimated to 10 ms (table2 also index.csv and viscosity.csv) and CAN logs
    (with 1 ms CSVs) only if asked: 184 x 35 s at 1 ms would be about 19 million
    frames (0.8 GB, an hour of encoding), the thermal runs 1.4 million.
    """
    if kind not in EXPERIMENTS:
        raise BenchError(f"unknown experiment {kind!r}: expected one of {', '.join(EXPERIMENTS)}")
    seed = check_seed(seed)
    if slips_rpm is not None and kind != "engagement":
        raise BenchError(f"--slip applies to the engagement only, not to {kind}")
    true_cal = calibration.load(true_path)
    if experiments is None:
        if kind == "engagement":
            experiments = engagement_experiments(ENGAGEMENT_SLIPS_RPM if slips_rpm is None else slips_rpm)
        elif kind == "table2":
            experiments = table2_experiments()
        else:
            experiments = thermal_experiments(seed)
    if logs is None:
        logs = kind == "engagement"
    if every is None:
        every = 1 if logs or kind == "engagement" else CAMPAIGN_EVERY
    if logs and every != 1:
        raise BenchError("CAN logs need the 1 ms rows: use every=1 with logs")
    out = _prepare_dir(out_dir)
    results = simulate(true_cal, experiments, seed, config, every)
    files = []
    with atomic.Staged():   # all files or none (a full disk leaves no truncated CSV)
        for r in results:
            path = out / f"{r.experiment.name}.csv"
            write_csv(path, r)
            files.append(path)
            if logs:
                path = out / f"{r.experiment.name}.log"
                write_log(path, r)
                files.append(path)
        if kind == "table2":
            path = out / "index.csv"
            write_index(path, true_cal, results)
            files.append(path)
            path = out / "viscosity.csv"
            write_viscosity(path, true_cal, seed)
            files.append(path)
    return {"files": files, "results": results}


def engagement_figures(result: Result, contact_force_N: float = 50.0, locked_rpm: float = 10.0) -> dict:
    """Fig. 15 figures of an engagement from the truth and the measurements."""
    tr, t = result.truth, result.t_s
    contact = np.flatnonzero(tr["force_N"] > contact_force_N)
    t_contact = float(t[contact[0]])
    lock = np.flatnonzero((t > t_contact) & (tr["locked"] > 0.5))
    t_lock = float(t[lock[0]]) if lock.size else float("nan")
    slipping = (t >= t_contact) & (tr["locked"] < 0.5)
    return {
        "t_contact_s": t_contact,
        "t_lock_s": t_lock,
        "peak_torque_Nm": float(np.max(tr["torque_Nm"][slipping])),
        "peak_torque_measured_Nm": float(np.max(result.measured["torque_Nm"][t >= t_contact])),
        "peak_viscous_Nm": float(np.max(tr["viscous_Nm"][(t >= t_contact) & (t < t_contact + 0.3)])),
        "theta_at_lock_degC": float(tr["theta_degC"][lock[0]]) if lock.size else float("nan"),
    }


# --------------------------------------------------------------------------- log conversion

# Lines of a Vector ASC log that are not events: the header, comments, the trigger block's bounds.
_ASC_HEADER = re.compile(r"(date\s|base\s|(no\s+)?internal\s+events\s+logged|begin\s+triggerblock|end\s+triggerblock"
                         r"|//)", re.IGNORECASE)
# what python-can's ASCReader parses as a frame (anything else it skips without a word)
_ASC_PARSED = re.compile(r"\d+\.\d+\s+(\d+\s+(\w+\s+(Tx|Rx)|ErrorFrame)|CANFD)", re.ASCII | re.IGNORECASE)
# events other than frames, skipped and counted: a channel's keyword event ("1 Statistic: ..."), another bus's
# or the logger's event in capitals ("CAN 1 Status:...", "SV: ...", "J1939TP ...", "LIN ..."), markers
_ASC_OTHER_EVENT = re.compile(r"\d+\.\d+\s+(\d+\s+[A-Za-z]\w*:|[A-Z][A-Z0-9]+:?(\s|$)|[Ll]og trigger event"
                              r"|[Pp]retrigger)", re.ASCII)
_ASC_START = re.compile(r"\d+\.\d+\s+start of measurement", re.IGNORECASE)


class _CountingLines:
    """A text file iterated line by line for python-can's ASCReader, remembering the line number and
    checking each line: python-can skips a line it does not understand without a word, so the first line
    that is not a header line, a comment, a frame (parsed by python-can: a broken one is its ValueError)
    or a known kind of other event (_ASC_OTHER_EVENT, counted in .events) is kept in .bad as
    (line, reason), for convert_log to raise once it knows whether the file held any frame at all."""

    def __init__(self, f):
        self.f = f
        self.line = 0
        self.events = 0
        self.bad = None

    def __iter__(self):
        return self

    def __next__(self):
        line = next(self.f)
        self.line += 1
        text = line.strip()
        if not text or _ASC_HEADER.match(text) or _ASC_PARSED.match(text) or _ASC_START.match(text):
            return line
        if _ASC_OTHER_EVENT.match(text):
            self.events += 1
            return line
        if self.bad is None:
            binary = any(ch < " " and ch != "\t" for ch in text) or "\x7f" in text
            self.bad = (self.line, "binary data" if binary else
                        f"not a Vector ASC line (header, comment, frame or event): {text[:60]!r}")
        return line

    def close(self):
        self.f.close()


def convert_log(in_path, out_path, channel: str = "vcan0") -> dict:
    """Vector ASC or BLF (python-can readers) -> candump -L (canlog.write_log), written atomically.

    Classic CAN data frames are written with the file's timestamps, in the file's order. Error
    frames, remote frames and CAN FD frames (the DBC is classic CAN) are skipped and counted, and so
    are an ASC file's other events (statistics, chip status, ...). A malformed file raises LogError
    naming the file (and for ASC the line: a broken frame, or a line that is neither header,
    comment, frame nor a known kind of event, see _CountingLines); nothing is written then. A frame
    earlier than the one before it is copied as is and listed in 'out_of_order' as (where,
    timestamp, previous timestamp), where being 'line N' (ASC) or 'frame N' (BLF), for the caller
    to warn about.
    """
    import can
    import struct
    import zlib as _zlib

    from .errors import LogError

    in_path, out_path = Path(in_path), Path(out_path)
    suffix = in_path.suffix.lower()
    if suffix not in (".asc", ".blf"):
        raise LogError(f"{in_path}: unsupported log format {in_path.suffix or '(no suffix)'!r}:"
                       " expected a Vector .asc or .blf file")
    if not in_path.is_file():
        raise LogError(f"{in_path}: {'not a file' if in_path.exists() else 'no such log file'}")
    messages: list = []
    skipped = {"error": 0, "remote": 0, "fd": 0, "event": 0}
    out_of_order: list = []
    lines = None
    try:
        if suffix == ".asc":
            f = open(in_path, encoding="latin-1", newline=None)
            lines = _CountingLines(f)
            reader = can.ASCReader(lines)
        else:
            reader = can.BLFReader(str(in_path))
        with reader:
            for k, msg in enumerate(reader, start=1):
                where = f"line {lines.line}" if lines is not None else f"frame {k}"
                if msg.is_error_frame:
                    skipped["error"] += 1
                elif msg.is_remote_frame:
                    skipped["remote"] += 1
                elif msg.is_fd or len(msg.data) > 8:
                    skipped["fd"] += 1
                elif len(msg.data) != msg.dlc:
                    raise LogError(f"{in_path}: {where}: {len(msg.data)} data bytes, DLC says {msg.dlc}")
                else:
                    stamp = float(msg.timestamp)
                    if not math.isfinite(stamp):
                        raise LogError(f"{in_path}: {where}: timestamp {stamp} is not finite")
                    if messages and stamp < messages[-1][0]:
                        out_of_order.append((where, stamp, messages[-1][0]))
                    messages.append((stamp, msg))
    except LogError:
        if lines is not None and lines.bad:   # an earlier line python-can skipped is the first problem
            raise LogError(f"{in_path}: line {lines.bad[0]}: {lines.bad[1]}") from None
        raise
    except OSError as e:
        raise LogError(f"{in_path}: cannot read: {e.strerror or e}") from None
    except (ValueError, IndexError, KeyError, struct.error, _zlib.error, EOFError, can.CanError,
            can.io.blf.BLFParseError) as e:
        if lines is not None and lines.bad:
            raise LogError(f"{in_path}: line {lines.bad[0]}: {lines.bad[1]}") from None
        where = f": line {lines.line}" if lines is not None else ""
        raise LogError(f"{in_path}{where}: not a valid Vector {suffix[1:].upper()} log ({type(e).__name__}: {e})") from None
    bad = lines.bad if lines is not None else None
    if not messages:
        raise LogError(f"{in_path}: no CAN data frames found (not a Vector {suffix[1:].upper()} log?"
                       + (f" line {bad[0]}: {bad[1]}" if bad else "") + ")")
    if bad:
        raise LogError(f"{in_path}: line {bad[0]}: {bad[1]}")
    if lines is not None:
        skipped["event"] = lines.events
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with atomic.atomic_path(out_path) as tmp:
        canlog.write_log(tmp, messages, channel=channel)
    return {"frames": len(messages), "skipped": skipped, "span_s": messages[-1][0] - messages[0][0],
            "out_of_order": out_of_order}
