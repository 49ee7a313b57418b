"""The bench, simulated (DESIGN.md section 7): richer than the control model.

The paper's bench data are not public, so identification and the HIL replay
run against this simulator. It is deliberately richer than the control model
(DESIGN 2), in double precision, vectorized over experiments (NumPy), seeded:

- a TRUE parameter set (tools/calibrations/bench_true.toml, same schema as
  table1.toml) that differs from Table 1 by a few percent, plus the
  engagement edges Table 1 leaves out (squeeze factor, static friction);
- the squeeze film by the Reynolds force balance (DESIGN 9), per friction
  interface F_app = F_c(h) + F_h: the asperities carry F_c = A_f p_c(h)
  (eq. 15) at the nominal separation h (the state), the oil squeezed out
  through the Patir-Cheng gap h_bar(h) (eq. 9) the rest,
  F_h = phi 3 pi mu_v(theta) K / (2 h_bar^3) (-dh_bar/dt) with
  K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri) (parallel annular plates,
  film_constant_m4: 1.5344e-7 m^4) and phi the true calibration's
  film_squeeze_factor (grooves, permeable lining). So
  dh/dt = -(F_app - F_c(h)) 2 h_bar^3 / (3 pi phi mu_v K dh_bar/dh),
  dh_bar/dh = (1 + erf(h / (sqrt2 sigma))) / 2, mu_v at the true clutch
  temperature: fast from the open gap, slow near contact (equivalent first-
  order time constant 0.059 s at 40 degC and 1188 N, film_time_constant_s),
  faster when hot, slower under load. F_h < 0 (the film in tension) would
  need the plates to separate, which only the open clutch's film at h_max
  (model.film_domain) wants: h is kept in [h_min, h_max] (the open clutch
  rests at h_max, F_c(h_max) = 0.047 N). phi = 0 gives the paper's steady
  film (h = h_ss(F_app) at once). Torque by eq. 8 with the true parameters;
- the static capacity static_friction_factor mu_f(0, theta) R_eff N_c F_c
  (DESIGN 9; the factor from the true calibration);
- a linear actuator: first-order lag to the commanded apply force, measured
  by a load cell with noise;
- a speed-controlled motor (PI with feed-forward, torque limit, anti-windup)
  (or, for the breakaway, a torque ramp) driving a rotating inertia J through
  a torsionally elastic shaft to the clutch hub; stick (below the static
  capacity) and slip; after lock the shaft rings (paper Fig. 15);
- the clutch pack of eq. 1 with the true k1, k2, C (exact zero-order hold),
  oil and housing temperatures that drift (oil warmed by the heat it picks
  up, housing slowly towards the clutch), thermistors with a first-order lag;
- sensor noise on the speed encoder, load cell, torque sensor, thermistors.

Experiments (protocols; numbers in BenchConfig and the constants below):

engagement  paper Fig. 15. At t = 0 the shaft spins at the initial slip (750,
            500 or 250 rpm), clutch open (no force, film at h_max), clutch, oil
            and housing at 40 degC (engagement_750rpm, ...) or 80 degC
            (engagement_750rpm_80degC, ...); the motor holds the speed against
            the open-clutch drag. At t = 0.9 s (contact) the force command
            steps to 1188 N and the motor is switched off: the clutch brakes
            the inertia to lock. After lock the hub stands still and the torque
            sensor reads the shaft torque: the twist the shaft carried at lock
            rings down (20 Hz, damping ratio 0.3) to zero, because with the
            motor off the locked clutch has nothing else to hold. 2.5 s.
table2      the 184 experiments of Table 2 (section 3.2, Fig. 9): at rest,
            force on at 0.5 s (the film settles first), motor on at 2 s and a
            speed ramp to the initial slip by 4 s, hold for the loading period,
            ramp down over 20 s, motor off at zero speed, 1 s more.
thermal     Fig. 13: 1188 N throughout, oil at 50 degC, housing starting at
            42 degC; (a) small frequent steps (100..250 rpm, held 4..8 s, seeded),
            (b) one large step (60 -> 400 -> 60 rpm). 240 s each.
breakaway   the static capacity: at rest and locked, 903 / 1188 / 1613 N on at
            0.5 s (the film settles), clutch, oil and housing at 40 or 80 degC
            (breakaway_1188N_40degC, ...); from 2.0 s the motor, torque-
            controlled, ramps the shaft torque at 100 Nm/s until the clutch
            breaks away (shaft torque > static capacity); once the measured
            slip passes 20 rpm the motor is switched off, the clutch stops the
            inertia and locks again. 4.5 s (BREAKAWAY_DURATION_S). The measured
            torque peaks at the capacity while locked, then drops by 11 % (the
            kinetic friction at zero slip, 1/1.12 of it) and rises again with
            the slip (this lining's mu1 > 1.12 mu2). breakaway_index.csv lists
            the runs.

Measurements (CSV_COLUMNS): slip from the encoder (noise 0.5 rpm), load cell
(3 N), torque sensor (1 Nm; the shaft torque, i.e. the clutch torque while
slipping), clutch/oil/housing thermistors (0.15 s lag, 0.1 K).
torque_request_Nm is what the TCU would be asked for: the measured torque
through a 10 ms first-order filter, clipped at >= 0 (sent with Mode Open
before contact, TorqueControl from contact on; table2, thermal, breakaway:
from the force step on).

The simulation step is 1 ms. Every experiment writes a measurement CSV and,
by default for the engagement only, the candump -L log of the frames the TCU
receives (canlog.input_log / canlog.write_log, one period per ms); table2
and thermal CSVs are decimated to 10 ms unless the logs are asked for
(breakaway: 1 ms CSVs, logs if asked).

The film is integrated by classical RK4 in BenchConfig.film_substeps = 2
substeps of 0.5 ms per step, the actuator force exact within the step, the
viscosity held. Why 2 is enough: (1) stability: the largest
|d(dh/dt)/dh| met while the film moves is 520 1/s (table2 at 100 degC, 1613
N, during the force step; the engagement at 80 degC 350 1/s, the breakaway
at 80 degC 400 1/s), i.e. 0.26 per substep against RK4's real-axis limit
2.79; near contact it is 1/tau, and 2 substeps stay stable down to tau =
0.18 ms, below the settled film's 0.29 ms in the hottest oil the firmware
accepts (250 degC): the settled film cannot ring anywhere in the thermal
envelope; (2) accuracy:
against 32 substeps, 2 give engagement torques within 3.4e-5 Nm and contact
forces within 3e-4 N (1.5e-3 N in table2's hottest force step), and 4 change
the engagement torque by less than 3.4e-5 Nm (test_film_substeps_converged).
A step that leaves h and the actuator force unchanged to the last bit (the
film settled under a constant force) is not integrated again until the
command changes: the viscosity, the one input that still changes, does not
move an equilibrium. Cost (2 cores, NumPy; the first-order film before in
brackets): the table2 campaign 14.5-15.2 s (14.4-15.5 s), the thermal runs
51 s (62 s), the three 40 degC engagements 1.4 s (0.8 s: the film is
integrated for about a second of each), the six breakaway runs 2.9 s.

Noise: one generator per experiment, seeded from (seed, crc32(name)), drawn
in blocks of NOISE_BLOCK steps, so an experiment gives the same numbers alone
or in a batch and the files regenerate byte-identically for a given seed.

One module per concern, every name importable from here (``bench.simulate``, ``bench.run``):

experiments  the protocols' numbers, BenchConfig, Experiment, Result, the experiment lists, input checks
physics      the true clutch in closed form and the Reynolds squeeze film (_Physics), K, the film's time constant
simulation   simulate: a batch of experiments of one kind stepped together
campaign     run: an experiment set simulated and written (CSVs, CAN logs, index and viscosity files)
figures      engagement and breakaway figures of a run

A real bench's Vector ASC/BLF log is converted by wetclutch.hil.convert (``wetclutch convert``).
"""
from __future__ import annotations

from .campaign import INDEX_COLUMNS, INDEX_FILE, run, write_csv, write_index, write_log, write_viscosity
from .experiments import (BREAKAWAY_DURATION_S, BREAKAWAY_FORCES_N, BREAKAWAY_OFF_RPM, BREAKAWAY_RAMP_S,
                          BREAKAWAY_RATE_NM_S, BREAKAWAY_THETAS_DEGC, CAMPAIGN_EVERY, CAMPAIGN_FORCE_S,
                          CAMPAIGN_HOLD_S, CAMPAIGN_RAMP_DOWN_S, CAMPAIGN_RAMP_S, CAMPAIGN_TAIL_S, CSV_COLUMNS,
                          CSV_FORMATS, DEFAULT_SEED, DEFAULT_TRUE, ENGAGEMENT_CONTACT_S, ENGAGEMENT_DURATION_S,
                          ENGAGEMENT_FORCE_N, ENGAGEMENT_SLIPS_RPM, ENGAGEMENT_THETA0_DEGC, ENGAGEMENT_THETAS_DEGC,
                          EXPERIMENTS, NOISE_BLOCK, ROOT, RPM, TABLE2_COUNT, TABLE2_FORCES_N, TABLE2_LOADING_S,
                          TABLE2_SLIPS_RPM, TABLE2_THETA0_DEGC, THERMAL_DURATION_S, THERMAL_FORCE_N,
                          THERMAL_HOUSING0_DEGC, THERMAL_OIL0_DEGC, THETA_RANGE_DEGC, BenchConfig, BenchError,
                          Experiment, Result, breakaway_experiments, check_seed, engagement_experiments,
                          engagement_name, table2_experiments, thermal_experiments)
from .figures import breakaway_figures, engagement_figures
from .physics import _Physics, film_constant_m4, film_time_constant_s
from .simulation import TRUTH_NAMES, simulate

__all__ = [
    "BREAKAWAY_DURATION_S", "BREAKAWAY_FORCES_N", "BREAKAWAY_OFF_RPM", "BREAKAWAY_RAMP_S", "BREAKAWAY_RATE_NM_S",
    "BREAKAWAY_THETAS_DEGC", "CAMPAIGN_EVERY", "CAMPAIGN_FORCE_S", "CAMPAIGN_HOLD_S", "CAMPAIGN_RAMP_DOWN_S",
    "CAMPAIGN_RAMP_S", "CAMPAIGN_TAIL_S", "CSV_COLUMNS", "CSV_FORMATS", "DEFAULT_SEED", "DEFAULT_TRUE",
    "ENGAGEMENT_CONTACT_S", "ENGAGEMENT_DURATION_S", "ENGAGEMENT_FORCE_N", "ENGAGEMENT_SLIPS_RPM",
    "ENGAGEMENT_THETA0_DEGC", "ENGAGEMENT_THETAS_DEGC", "EXPERIMENTS", "INDEX_COLUMNS", "INDEX_FILE", "NOISE_BLOCK",
    "ROOT", "RPM", "TABLE2_COUNT", "TABLE2_FORCES_N", "TABLE2_LOADING_S", "TABLE2_SLIPS_RPM", "TABLE2_THETA0_DEGC",
    "THERMAL_DURATION_S", "THERMAL_FORCE_N", "THERMAL_HOUSING0_DEGC", "THERMAL_OIL0_DEGC", "THETA_RANGE_DEGC",
    "TRUTH_NAMES", "BenchConfig", "BenchError", "Experiment", "Result", "_Physics", "breakaway_experiments",
    "breakaway_figures", "check_seed", "engagement_experiments", "engagement_figures", "engagement_name",
    "film_constant_m4", "film_time_constant_s", "run", "simulate", "table2_experiments", "thermal_experiments",
    "write_csv", "write_index", "write_log", "write_viscosity",
]
