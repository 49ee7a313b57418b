"""Double-precision reference of the control model (DESIGN.md section 2).

Independent of the firmware: NumPy/SciPy in float64, vectorized, with the
film thickness solved exactly (no table). FilmTable, beside the exact form, is
the tabulated h_bar(p_c) for many samples (bench simulator, identification),
tested against it. Equation numbers are the paper's.
Units: SI, temperatures in degC, slip speed in rpm at the interfaces.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.special import erf, erfc

from .calibration import Calibration

RAD_S_PER_RPM = 2.0 * math.pi / 60.0

# Status bits shared with the firmware (include/wetclutch/wc_status.h).
STATUS_BELOW_DRAG = 1 << 0        # request below the drag at zero force: force 0
STATUS_SATURATED = 1 << 1         # request above the capacity at maximum current
STATUS_CURRENT_CLAMPED = 1 << 2   # current clamped to the solenoid range
STATUS_SLIP_INVALID = 1 << 3      # slip speed NaN, infinite or out of range
STATUS_THETA_INVALID = 1 << 4     # a temperature NaN, infinite or out of range
STATUS_FORCE_INVALID = 1 << 5     # contact force NaN, infinite, negative or too large
STATUS_TORQUE_INVALID = 1 << 6    # torque request NaN, infinite, negative or too large
STATUS_POWER_INVALID = 1 << 7     # heat input NaN, infinite or negative
STATUS_OVER_TEMPERATURE = 1 << 8  # estimate above THETA_OVER_DEGC (hysteresis THETA_OVER_HYSTERESIS_K)
STATUS_NOT_INITIALISED = 1 << 9   # NULL or uninitialised instance (C only)
STATUS_LOCKED = 1 << 10           # clutch locked: static friction holds it (DESIGN 9); not an error
# Thermal envelope (include/wetclutch/wc_config.h, DESIGN section 8).
THETA_MIN_DEGC, THETA_MAX_DEGC = -40.0, 250.0
THETA_OVER_DEGC, THETA_OVER_HYSTERESIS_K = 200.0, 10.0
STATUS_INPUT_INVALID = (STATUS_SLIP_INVALID | STATUS_THETA_INVALID | STATUS_FORCE_INVALID | STATUS_TORQUE_INVALID
                        | STATUS_POWER_INVALID)

# The firmware's input ranges (include/wetclutch/wc_config.h; temperatures: THETA_MIN_DEGC, THETA_MAX_DEGC above),
# checked in float32 as the firmware does (reference.py).
SLIP_MAX_RAD_S = 1047.2           # WC_SLIP_MAX_rad_s: 10000 rpm
FORCE_MAX_N = 1.0e5
TORQUE_MAX_NM = 1.0e5


def viscosity_Pa_s(cal: Calibration, theta_degC):
    """mu_v(theta), eq. 2."""
    th = np.asarray(theta_degC, dtype=float)
    return cal.mv1 * np.exp(cal.mv2 * th) + cal.mv3 * np.exp(cal.mv4 * th)


def viscosity_slope_Pa_s_per_K(cal: Calibration, theta_degC):
    """d mu_v / d theta, from eq. 2."""
    th = np.asarray(theta_degC, dtype=float)
    return cal.mv1 * cal.mv2 * np.exp(cal.mv2 * th) + cal.mv3 * cal.mv4 * np.exp(cal.mv4 * th)


def friction_coefficient(cal: Calibration, speed_m_s, theta_degC):
    """mu_f(v, theta), eq. 18 (Stribeck exponential x linear temperature)."""
    v = np.abs(np.asarray(speed_m_s, dtype=float))
    th = np.asarray(theta_degC, dtype=float)
    stribeck = cal.mu1 + (cal.mu2 - cal.mu1) * np.exp(-v / cal.stribeck_speed)
    return stribeck * (1.0 + cal.mu3 * (th - cal.theta1) / cal.theta2)


def contact_pressure_Pa(cal: Calibration, separation_m):
    """p_c(h), eq. 15 (Greenwood-Williamson with eq. 11-14)."""
    h = np.asarray(separation_m, dtype=float)
    s = cal.roughness_rms
    x = h / (math.sqrt(2.0) * s)
    k = math.sqrt(math.pi / 2.0) * cal.youngs_modulus * cal.roughness_parameter
    return k * (np.exp(-x * x) - (h / s) * math.sqrt(math.pi / 2.0) * erfc(x))


def film_thickness_m(cal: Calibration, separation_m):
    """h_bar(h), eq. 9 (Patir-Cheng average film thickness)."""
    h = np.asarray(separation_m, dtype=float)
    s = cal.roughness_rms
    x = h / (math.sqrt(2.0) * s)
    return h / 2.0 * (1.0 + erf(x)) + s / math.sqrt(2.0 * math.pi) * np.exp(-x * x)


def film_slope_m_per_Pa(cal: Calibration, separation_m):
    """d h_bar / d p_c = (d h_bar/dh) / (d p_c/dh), exact, from eq. 9 and 15.

    d h_bar/dh = (1 + erf x)/2 and d p_c/dh = -(pi/2) E N beta erfc x.
    """
    h = np.asarray(separation_m, dtype=float)
    x = h / (math.sqrt(2.0) * cal.roughness_rms)
    enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
    return -(1.0 + erf(x)) / (math.pi * enb * erfc(x))


def separation_from_pressure_m(cal: Calibration, pressure_Pa):
    """Inverse of eq. 15 by vectorized bisection (p_c is strictly decreasing in h)."""
    p = np.asarray(pressure_Pa, dtype=float)
    s = cal.roughness_rms
    lo = np.full(p.shape, -60.0 * s)
    hi = np.full(p.shape, 60.0 * s)
    for _ in range(64):  # 120 sigma / 2^64 < 1e-22 m: exact in double
        mid = 0.5 * (lo + hi)
        above = contact_pressure_Pa(cal, mid) > p
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return 0.5 * (lo + hi)


def film_domain(cal: Calibration):
    """(separation_min_m, separation_max_m, pressure_min_Pa, pressure_max_Pa) of the modelled film.

    Outside it the film is clamped (eq. 16 steady state): below pressure_min
    (an open clutch) h_bar = h_bar(separation_max); above pressure_max the table end.
    """
    cached = cal.__dict__.get("_film_domain")   # a Calibration is immutable: computed once per object
    if cached is not None:
        return cached
    h_max = cal.separation_max_sigma * cal.roughness_rms
    p_max = cal.contact_pressure_max
    h_min = float(separation_from_pressure_m(cal, np.array([p_max]))[0])
    p_min = float(contact_pressure_Pa(cal, h_max))
    object.__setattr__(cal, "_film_domain", (h_min, h_max, p_min, p_max))
    return h_min, h_max, p_min, p_max


def hbar_from_pressure_m(cal: Calibration, pressure_Pa):
    """h_bar(p_c) exactly (eq. 9 at the h solving eq. 15), clamped to the film domain."""
    _, _, p_min, p_max = film_domain(cal)
    p = np.clip(np.asarray(pressure_Pa, dtype=float), p_min, p_max)
    return film_thickness_m(cal, separation_from_pressure_m(cal, p))


class FilmTable:
    """The fast form of separation_from_pressure_m and hbar_from_pressure_m for many samples.

    A dense table of the exact closed forms (eq. 9 and 15) at `nodes` separations uniform from the
    film domain's h_max down to h_min (so p_c increases along it), read by linear interpolation in p_c;
    the pressure is clamped to the film domain as in hbar_from_pressure_m. No per-sample bisection.
    Used by the bench simulator (20001 nodes) and the identification (4001 nodes); checked against
    the exact form in tests/python/test_model_film.py.
    """

    def __init__(self, cal: Calibration, nodes: int):
        h_min, h_max, self.pressure_min_Pa, self.pressure_max_Pa = film_domain(cal)
        self.separation_m = np.linspace(h_max, h_min, nodes)
        self.pressure_Pa = contact_pressure_Pa(cal, self.separation_m)      # increasing
        self.hbar_m = film_thickness_m(cal, self.separation_m)

    def _clamped(self, pressure_Pa):
        return np.clip(np.asarray(pressure_Pa, dtype=float), self.pressure_min_Pa, self.pressure_max_Pa)

    def separation_from_pressure_m(self, pressure_Pa):
        """Steady-state nominal separation h(p_c) (eq. 15 inverted), clamped to the film domain."""
        return np.interp(self._clamped(pressure_Pa), self.pressure_Pa, self.separation_m)

    def hbar_from_pressure_m(self, pressure_Pa):
        """h_bar(p_c) (eq. 9 at the h solving eq. 15), clamped to the film domain."""
        return np.interp(self._clamped(pressure_Pa), self.pressure_Pa, self.hbar_m)


# --------------------------------------------------------------------------- engagement edges (DESIGN 9)

def reynolds_factor_m4(cal: Calibration) -> float:
    """K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri): Reynolds' squeeze film between annular plates.
    Narrow annuli cancel: with s = (Ro - Ri)/(Ro + Ri) < 0.01 the series 8 m^4 s^3 (4/3 + 4/45 s^2 + 44/945 s^4)
    (m = (Ro + Ri)/2, from ln(Ro/Ri) = 2 atanh s), truncated at about 2e-14 relative there."""
    ro, ri = cal.outer_radius, cal.inner_radius
    s = (ro - ri) / (ro + ri)
    if s < 0.01:
        m = 0.5 * (ro + ri)
        return 8.0 * m**4 * s**3 * (4.0 / 3.0 + s * s * (4.0 / 45.0 + s * s * 44.0 / 945.0))
    return ro**4 - ri**4 - (ro**2 - ri**2) ** 2 / math.log(ro / ri)


def film_damping_N_s_m2(cal: Calibration, theta_degC, squeeze_factor: float | None = None):
    """D = 3 pi phi mu_v(theta) K / 2: F_h = D (-dh_bar/dt) / h_bar^3 (DESIGN 9)."""
    phi = cal.film_squeeze_factor if squeeze_factor is None else squeeze_factor
    return 1.5 * math.pi * phi * reynolds_factor_m4(cal) * viscosity_Pa_s(cal, theta_degC)


def separation_from_hbar_m(cal: Calibration, hbar_m):
    """Inverse of eq. 9 by vectorized bisection (h_bar strictly increases with h)."""
    hb = np.asarray(hbar_m, dtype=float)
    s = cal.roughness_rms
    if hb.ndim == 0:   # one film (the per-step reference): the same bisection in scalar arithmetic, 50x faster
        lo, hi = -60.0 * s, max(60.0 * s, 2.0 * float(hb))
        k = 1.0 / (math.sqrt(2.0) * s)
        c = s / math.sqrt(2.0 * math.pi)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            x = mid * k
            if 0.5 * mid * (1.0 + math.erf(x)) + c * math.exp(-x * x) < float(hb):
                lo = mid
            else:
                hi = mid
        return np.float64(0.5 * (lo + hi))
    lo = np.full(hb.shape, -60.0 * s)
    hi = np.full(hb.shape, np.maximum(60.0 * s, 2.0 * hb))
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        below = film_thickness_m(cal, mid) < hb
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def film_contact_pressure_Pa(cal: Calibration, hbar_m):
    """(p_c, dp_c/dh_bar) of the asperities at film h_bar (eq. 9, 15), on the film domain: 0 at or above the
    open-clutch film, the domain's last pressure at or below its thinnest film (wc_film_pressure_Pa)."""
    h_min, h_max, _, p_max = film_domain(cal)
    hb = np.asarray(hbar_m, dtype=float)
    h = np.clip(separation_from_hbar_m(cal, hb), h_min, h_max)
    x = h / (math.sqrt(2.0) * cal.roughness_rms)
    enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
    slope = -(math.pi / 2.0) * enb * erfc(x) / (0.5 * (1.0 + erf(x)))       # (dp_c/dh) / (dh_bar/dh)
    p = np.where(hb >= film_thickness_m(cal, h_max), 0.0, contact_pressure_Pa(cal, h))
    return p, slope


def film_advance_m(cal: Calibration, hbar_m: float, apply_force_N: float, theta_degC: float,
                   squeeze_factor: float | None = None, dt_s: float | None = None) -> float:
    """One control period of the squeeze film, the firmware's scheme (wc_film_advance_m) in double with the
    exact eq. 9/15 (no table) and the exact dp_c/dh_bar where the firmware takes its table's secant: in
    u = 1/h_bar^2, D du/dt = 2 (F_app - F_c), linearly implicit in F_c, never past the settled film."""
    dt = cal.period if dt_s is None else dt_s
    area = cal.friction_area
    settled = float(hbar_from_pressure_m(cal, apply_force_N / area))
    p, slope = film_contact_pressure_Pa(cal, hbar_m)
    squeeze = apply_force_N - area * float(p)
    damping = float(film_damping_N_s_m2(cal, theta_degC, squeeze_factor))
    u = 1.0 / hbar_m**2
    u_next = u + 2.0 * dt * squeeze / (damping - dt * area * float(slope) * hbar_m**3)
    u_settled = 1.0 / settled**2
    closing = u_settled > u
    if not (u_next < u_settled if closing else u_next > u_settled):
        return settled
    return 1.0 / math.sqrt(u_next) if (u_next > u if closing else u_next < u) else hbar_m


class FilmDynamics:
    """The squeeze-film state (DESIGN 9) of many runs at once, in double: the firmware's update
    (film_advance_m) vectorized over runs, with eq. 9/15 on a dense table in h (linear interpolation,
    `nodes` separations over the film domain) instead of the exact closed forms. For the identification
    and the plant-family study, where a run is thousands of steps and a fit hundreds of runs."""

    def __init__(self, cal: Calibration, nodes: int = 4001):
        h_min, h_max, _, _ = film_domain(cal)
        h = np.linspace(h_max, h_min, nodes)
        self.cal = cal
        self.hbar_m = film_thickness_m(cal, h)                 # decreasing along the table
        self.pressure_Pa = contact_pressure_Pa(cal, h)         # increasing
        x = h / (math.sqrt(2.0) * cal.roughness_rms)
        enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
        self.slope_Pa_per_m = -(math.pi / 2.0) * enb * erfc(x) / (0.5 * (1.0 + erf(x)))   # dp_c/dh_bar
        self.reynolds_m4 = reynolds_factor_m4(cal)

    def contact_pressure_Pa(self, hbar_m):
        """(p_c, dp_c/dh_bar) at film h_bar: 0 at or above the open film (wc_film_pressure_Pa)."""
        hb = np.asarray(hbar_m, dtype=float)
        p = np.interp(-hb, -self.hbar_m, self.pressure_Pa)
        slope = np.interp(-hb, -self.hbar_m, self.slope_Pa_per_m)
        return np.where(hb >= self.hbar_m[0], 0.0, p), slope

    def settled_m(self, force_N):
        """The steady film under an apply force (eq. 16), clamped to the table."""
        return np.interp(np.asarray(force_N, dtype=float) / self.cal.friction_area, self.pressure_Pa, self.hbar_m)

    def advance_m(self, hbar_m, force_N, damping_N_s_m2, dt_s):
        """film_advance_m for arrays (same scheme: linearly implicit in u = 1/h_bar^2, never past settled)."""
        area = self.cal.friction_area
        settled = self.settled_m(force_N)
        p, slope = self.contact_pressure_Pa(hbar_m)
        squeeze = force_N - area * p
        u = 1.0 / hbar_m**2
        with np.errstate(divide="ignore", invalid="ignore"):
            u_next = u + 2.0 * dt_s * squeeze / (damping_N_s_m2 - dt_s * area * slope * hbar_m**3)
        u_settled = 1.0 / settled**2
        closing = u_settled > u
        short = np.where(closing, u_next < u_settled, u_next > u_settled)
        forward = np.where(closing, u_next > u, u_next < u)
        with np.errstate(invalid="ignore"):
            moved = np.where(forward, 1.0 / np.sqrt(np.where(u_next > 0, u_next, 1.0)), hbar_m)
        return np.where(short, moved, settled)

    def run(self, force_N, theta_degC, squeeze_factor: float, dt_s: float | None = None, substeps: int = 1):
        """Film h_bar and asperity force F_c per row (steps x runs), each row the state the torque of that
        step uses (before its update, as wc_clutch_step); starts settled under the first row's force.
        squeeze_factor 0: the steady film (eq. 16). substeps > 1 divides each period (the continuous law)."""
        force = np.atleast_2d(np.asarray(force_N, dtype=float).T).T
        theta = np.broadcast_to(np.atleast_2d(np.asarray(theta_degC, dtype=float).T).T, force.shape)
        if squeeze_factor <= 0.0:
            hbar = self.settled_m(force)
            return hbar, force.copy()
        dt = (self.cal.period if dt_s is None else dt_s) / substeps
        damping = 1.5 * math.pi * squeeze_factor * self.reynolds_m4 * viscosity_Pa_s(self.cal, theta)
        out = np.empty(force.shape)
        h = self.settled_m(force[0])
        for k in range(force.shape[0]):
            out[k] = h
            for _ in range(substeps):
                h = self.advance_m(h, force[k], damping[k], dt)
        return out, self.cal.friction_area * self.contact_pressure_Pa(out)[0]


def torque_at_film_Nm(cal: Calibration, slip_rpm, theta_degC, contact_force_N, hbar_m):
    """Eq. 5-8 for a contact force and the film it stands on, signed with the slip (arrays)."""
    return torque_parts(cal, slip_rpm, theta_degC, contact_force_N, hbar_m=hbar_m)["torque_Nm"]


def static_capacity_Nm(cal: Calibration, theta_degC, contact_force_N):
    """Static capacity: static factor mu_f(0, theta) R_eff N_c F_c (DESIGN 9; eq. 18 at v = 0)."""
    return (cal.static_friction_factor * friction_coefficient(cal, 0.0, theta_degC)
            * cal.effective_radius * cal.friction_pairs * np.asarray(contact_force_N, dtype=float))


class Lockup:
    """The firmware's lock-up state machine (wc_lockup.c): slipping <-> locked (DESIGN 9)."""

    def __init__(self, cal: Calibration):
        self.cal = cal
        self.locked = False
        self.direction = 1.0
        self.dwell = 0

    def update(self, slip_rad_s: float, required_Nm: float, capacity_Nm: float) -> bool:
        cal = self.cal
        holds = abs(required_Nm) < capacity_Nm
        locks = abs(required_Nm) * (1.0 + 0.5 * cal.holding_margin) < capacity_Nm   # torque hysteresis
        if self.locked:
            if not (abs(slip_rad_s) <= cal.breakaway_slip) or not holds:
                self.locked, self.dwell = False, 0
                if abs(slip_rad_s) >= cal.lock_slip:   # the slip that broke away sets the direction
                    self.direction = -1.0 if slip_rad_s < 0.0 else 1.0
            return self.locked
        if abs(slip_rad_s) < cal.lock_slip and locks:
            self.dwell = min(self.dwell + 1, 255)
            self.locked = self.dwell >= cal.lock_dwell
        else:
            self.dwell = 0
            if abs(slip_rad_s) >= cal.lock_slip:
                self.direction = -1.0 if slip_rad_s < 0.0 else 1.0
        return self.locked

    def torque_Nm(self, required_Nm: float, capacity_Nm: float) -> float:
        """What a locked clutch transmits: the required torque in the lock direction, at most the capacity."""
        along = self.direction * required_Nm
        return self.direction * (min(along, max(capacity_Nm, 0.0)) if along > 0.0 else 0.0)


def torque_parts(cal: Calibration, slip_rpm, theta_degC, force_N, hbar_m=None):
    """Eq. 3-8: dict of total/coulomb/viscous torque (Nm), h_bar (m), mu_f.

    hbar_m: the film the contact force stands on; default the steady film of eq. 16 (the squeeze-film
    state of DESIGN 9 passes its own).

    Torques carry the sign of the slip speed (slip >= 0 counts as positive):
    the torque transmitted through the slipping clutch, which acts against
    the slip on the faster member. At zero slip the Coulomb part is the
    static capacity mu_f(0, theta) F_c R_eff N_c and the viscous part is 0.
    """
    slip = np.asarray(slip_rpm, dtype=float)
    force = np.asarray(force_N, dtype=float)
    theta = np.asarray(theta_degC, dtype=float)
    sign = np.where(slip < 0.0, -1.0, 1.0)
    speed = cal.effective_radius * np.abs(slip) * RAD_S_PER_RPM          # eq. 4
    mu_f = friction_coefficient(cal, speed, theta)                       # eq. 18
    hbar = (hbar_from_pressure_m(cal, force / cal.friction_area)          # eq. 9, 15, 16
            if hbar_m is None else np.asarray(hbar_m, dtype=float))
    rn = cal.effective_radius * cal.friction_pairs
    coulomb = rn * mu_f * force                                          # eq. 6
    viscous = rn * viscosity_Pa_s(cal, theta) * cal.friction_area * speed / hbar  # eq. 7
    return {
        "torque_Nm": sign * (coulomb + viscous),                         # eq. 5, 8
        "coulomb_Nm": sign * coulomb,
        "viscous_Nm": sign * viscous,
        "hbar_m": hbar,
        "mu_f": mu_f,
    }


def force_max_N(cal: Calibration) -> float:
    """Contact force at the solenoid's maximum current: K i_max A_p - F_s."""
    return max(cal.vfs_gain * cal.vfs_current_max * cal.piston_area - cal.return_spring_force, 0.0)


def inverse(cal: Calibration, slip_rpm, theta_degC, torque_Nm):
    """Torque request (magnitude, Nm) -> contact force -> piston pressure -> VFS current.

    Returns a dict: force_N, pressure_Pa, current_mA, status (bits above).
    Solves |T(F)| = request exactly. Where the film is clamped (p_c below the
    table's first node) T is linear in F and is solved directly; elsewhere the
    unknown is the nominal separation h, with F = A_f p_c(h) and h_bar(h) in
    closed form (eq. 9, 15), by vectorized bisection in double precision.
    """
    slip = np.abs(np.asarray(slip_rpm, dtype=float))
    theta = np.asarray(theta_degC, dtype=float)
    req = np.asarray(torque_Nm, dtype=float)
    slip, theta, req = np.broadcast_arrays(slip, theta, req)
    f_max = force_max_N(cal)
    _, h_max, p_min, _ = film_domain(cal)

    speed = cal.effective_radius * slip * RAD_S_PER_RPM
    arm = cal.effective_radius * cal.friction_pairs
    coulomb_per_N = arm * friction_coefficient(cal, speed, theta)              # eq. 6, 18
    viscous_m = arm * viscosity_Pa_s(cal, theta) * cal.friction_area * speed   # eq. 7 times h_bar

    def torque_at(force):
        return coulomb_per_N * force + viscous_m / hbar_from_pressure_m(cal, force / cal.friction_area)

    drag = torque_at(np.zeros(req.shape))
    cap = torque_at(np.full(req.shape, f_max))
    # Clamped-film region, 0 <= F <= A_f p_min: T = c F + V / h_bar(h_max).
    f_knee = min(cal.friction_area * p_min, f_max)
    hbar_open = float(film_thickness_m(cal, h_max))
    force_linear = (req - viscous_m / hbar_open) / coulomb_per_N
    # Beyond it: bisection on h, T(h) strictly decreasing in h.
    lo = np.full(req.shape, float(separation_from_pressure_m(cal, np.array([f_max / cal.friction_area]))[0]))
    hi = np.full(req.shape, h_max)
    for _ in range(100):  # 40 um / 2^100: exact in double
        mid = 0.5 * (lo + hi)
        t_mid = coulomb_per_N * cal.friction_area * contact_pressure_Pa(cal, mid) + viscous_m / film_thickness_m(cal, mid)
        high = t_mid > req
        lo = np.where(high, mid, lo)
        hi = np.where(high, hi, mid)
    force_curve = cal.friction_area * contact_pressure_Pa(cal, 0.5 * (lo + hi))
    force = np.where(req <= torque_at(np.full(req.shape, f_knee)), force_linear, force_curve)

    status = np.zeros(req.shape, dtype=int)
    below = req <= drag
    above = req > cap
    force = np.where(below, 0.0, np.where(above, f_max, force))
    status |= np.where(below, STATUS_BELOW_DRAG, 0)
    status |= np.where(above, STATUS_SATURATED, 0)
    pressure = (force + cal.return_spring_force) / cal.piston_area   # F_app = P A_p - F_s
    current = pressure / cal.vfs_gain                                 # P = K i
    clamped = (current < cal.vfs_current_min) | (current > cal.vfs_current_max)
    current = np.clip(current, cal.vfs_current_min, cal.vfs_current_max)
    status |= np.where(clamped, STATUS_CURRENT_CLAMPED, 0)
    return {"force_N": force, "pressure_Pa": pressure, "current_mA": current, "status": status}


def thermal_decay(cal: Calibration, dt_s: float) -> float:
    """a = exp(-(k1 + k2) dt / C): the exact ZOH discretization of eq. 1."""
    return math.exp(-(cal.oil_conductance + cal.housing_conductance) * dt_s / cal.heat_capacity)


def thermal_steady_degC(cal: Calibration, power_W, theta_oil_degC, theta_housing_degC):
    """Steady-state temperature of eq. 1 for constant inputs."""
    k1, k2 = cal.oil_conductance, cal.housing_conductance
    return (np.asarray(power_W) + k1 * np.asarray(theta_oil_degC)
            + k2 * np.asarray(theta_housing_degC)) / (k1 + k2)


def thermal_observer(cal: Calibration, slip_rpm, torque_Nm, theta_oil_degC, theta_housing_degC,
                     theta_start_degC=None, held=None):
    """Eq. 1 over a series of control periods, exact for inputs held over each period.

    Row k's inputs are held from step k to k+1. Returns theta[k], the estimate
    before row k is applied; theta[0] is theta_start (default: first oil temperature).
    Heat input P = |T dw| (W). held: rows whose input is rejected (the firmware's
    wc_thermal_step leaves its state untouched there); default none.
    """
    slip = np.asarray(slip_rpm, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):   # only in held rows, whose result is not used
        power = np.abs(np.asarray(torque_Nm, dtype=float) * slip * RAD_S_PER_RPM)
        steady = thermal_steady_degC(cal, power, theta_oil_degC, theta_housing_degC)
    a = thermal_decay(cal, cal.period)
    out = np.empty(slip.shape)
    theta = float(np.asarray(theta_oil_degC, dtype=float).flat[0]) if theta_start_degC is None else theta_start_degC
    hold = np.zeros(slip.shape, bool) if held is None else np.asarray(held, bool)
    for k in range(slip.size):
        out[k] = theta
        if not hold[k]:
            theta = steady[k] + (theta - steady[k]) * a
    return out


# The clutch modes, numbered as the DBC's TorqueRequest.Mode and the C enum wc_clutch_mode_t.
MODE_OPEN, MODE_TORQUE, MODE_LOCKED = 0, 1, 2


def holding_inverse(cal: Calibration, theta_degC: float, torque_Nm: float) -> dict:
    """The inverse for a locked clutch (DESIGN 9): the force whose static capacity holds the request with the
    holding margin, at most the force at the maximum current (STATUS_SATURATED)."""
    per_N = float(static_capacity_Nm(cal, theta_degC, 1.0))
    force = torque_Nm * (1.0 + cal.holding_margin) / per_N
    if not force <= force_max_N(cal):   # the maximum current itself (wc_inverse_holding)
        return {"force_N": force_max_N(cal), "pressure_Pa": cal.vfs_gain * cal.vfs_current_max,
                "current_mA": cal.vfs_current_max, "status": STATUS_SATURATED}
    status = 0
    pressure = (force + cal.return_spring_force) / cal.piston_area
    current = pressure / cal.vfs_gain
    if current < cal.vfs_current_min or current > cal.vfs_current_max:
        status |= STATUS_CURRENT_CLAMPED
    return {"force_N": force, "pressure_Pa": pressure, "current_mA": min(max(current, cal.vfs_current_min),
                                                                           cal.vfs_current_max), "status": status}


CLUTCH_OUTPUTS = ("current_mA", "pressure_command_Pa", "pressure_model_Pa", "force_command_N", "theta_degC",
                  "torque_Nm", "mu_f", "hbar_m", "contact_force_N", "static_capacity_Nm", "status")
LEAD_TIME_MAX_S = 10.0   # WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s: a longer lag-compensation time counts as off


class ClutchReference:
    """The firmware's wc_clutch_step in double precision, one period per step() (clutch_steps runs it over
    arrays). Per step: inverse at theta (a locked clutch: holding_inverse; the open/locked modes: the
    solenoid's minimum/maximum current) -> current, led ahead of the squeeze film and the VFS lag when
    lag_compensation_time_s > 0 (DESIGN 9: lead_film, lead_lag); VFS lag (exact, tau) -> reached pressure ->
    apply force F = max(P A_p - F_s, 0) -> contact force (F, or with the squeeze-film state on, the asperity
    force at the film state, which then advances under F: film_advance_m) -> model torque; lock-up (Lockup)
    against the static capacity with the required torque (the measured torque on a bench, else
    carried_torque_Nm when given, else the request, in the lock direction); while locked the held torque
    (Lockup.torque_Nm), no heat and STATUS_LOCKED; observer advanced with |T dw| and kept in
    [THETA_MIN_DEGC, THETA_MAX_DEGC], STATUS_OVER_TEMPERATURE above THETA_OVER_DEGC until it falls
    THETA_OVER_HYSTERESIS_K below. theta_from_oil: the model takes the oil temperature (thermal-blind).
    The inputs are taken as valid (the frame loop's reference, replay.py, holds invalid ones)."""

    def __init__(self, cal: Calibration, theta_start_degC: float):
        self.cal = cal
        self.a_th = thermal_decay(cal, cal.period)
        self.a_vfs = math.exp(-cal.period / cal.vfs_time_constant)
        self.theta = float(theta_start_degC)
        self.pressure = cal.vfs_gain * cal.vfs_current_min
        self.film_on = cal.film_squeeze_factor > 0.0
        self.hbar = float(hbar_from_pressure_m(cal, max(self.pressure * cal.piston_area - cal.return_spring_force,
                                                        0.0) / cal.friction_area))
        self.lockup = Lockup(cal)
        self.over = False

    def _lead_film(self, theta: float, time_s: float, force_cmd: float, current: float) -> float:
        """DESIGN 9: the apply force that squeezes the film state towards the wanted force's film with time
        constant time_s, never below the wanted force, at most F_max; its current (wc_clutch.c lead_film)."""
        cal = self.cal
        if not self.film_on or not time_s <= LEAD_TIME_MAX_S:
            return current
        target = float(hbar_from_pressure_m(cal, force_cmd / cal.friction_area))
        if not self.hbar > target:
            return current
        contact = cal.friction_area * float(film_contact_pressure_Pa(cal, self.hbar)[0])
        squeeze = float(film_damping_N_s_m2(cal, theta)) * (self.hbar - target) / (time_s * self.hbar ** 3)
        force = contact + squeeze
        if not force > force_cmd:
            return current
        force = min(force, force_max_N(cal))
        pressure = (force + cal.return_spring_force) / cal.piston_area
        return min(max(pressure / cal.vfs_gain, cal.vfs_current_min), cal.vfs_current_max)

    def _lead_lag(self, time_s: float, current: float) -> tuple[float, int]:
        """DESIGN 9: K i = P + (P* - P) (1 - e^(-dt/t)) / (1 - e^(-dt/tau)), clamped (wc_clutch.c lead_lag)."""
        cal = self.cal
        if not time_s <= LEAD_TIME_MAX_S:
            return current, 0
        wanted = cal.vfs_gain * current
        gain = (1.0 - math.exp(-cal.period / time_s)) / (1.0 - self.a_vfs)
        led = (self.pressure + (wanted - self.pressure) * gain) / cal.vfs_gain
        if led > cal.vfs_current_max:
            return cal.vfs_current_max, STATUS_CURRENT_CLAMPED
        if led < cal.vfs_current_min:
            return cal.vfs_current_min, STATUS_CURRENT_CLAMPED
        return led, 0

    def step(self, slip_rpm: float, oil_degC: float, housing_degC: float, request_Nm: float, mode: int,
             bench_force_N: float = math.nan, bench_torque_Nm: float = math.nan, lag_compensation_time_s: float = 0.0,
             theta_from_oil: bool = False, carried_torque_Nm: float = 0.0) -> dict:
        cal = self.cal
        lockup = self.lockup
        theta_model = oil_degC if theta_from_oil else self.theta
        if mode == MODE_TORQUE:
            inv = (holding_inverse(cal, theta_model, request_Nm) if lockup.locked
                   else inverse(cal, slip_rpm, theta_model, request_Nm))
            current, force_cmd, status = float(inv["current_mA"]), float(inv["force_N"]), int(inv["status"])
        else:
            current = cal.vfs_current_max if mode == MODE_LOCKED else cal.vfs_current_min
            force_cmd = max(cal.vfs_gain * current * cal.piston_area - cal.return_spring_force, 0.0)
            status = 0
        lead = mode == MODE_TORQUE and lag_compensation_time_s > 0.0
        if lead:
            current = self._lead_film(theta_model, lag_compensation_time_s, force_cmd, current)
        target = cal.vfs_gain * current
        if lead:
            current, clamped = self._lead_lag(lag_compensation_time_s, current)
            status |= clamped
        self.pressure = cal.vfs_gain * current + (self.pressure - cal.vfs_gain * current) * self.a_vfs
        pressure = self.pressure
        force = max(pressure * cal.piston_area - cal.return_spring_force, 0.0)
        if not math.isnan(bench_force_N):
            force = bench_force_N
        # inside the lock band the torque keeps the lock direction (the slip's sign there is noise)
        in_band = abs(slip_rpm) * RAD_S_PER_RPM < cal.lock_slip
        if self.film_on:
            contact = cal.friction_area * float(film_contact_pressure_Pa(cal, self.hbar)[0])
            parts = torque_parts(cal, abs(slip_rpm), theta_model, contact, hbar_m=self.hbar)
            self.hbar = film_advance_m(cal, self.hbar, force, theta_model)
        else:
            contact = force
            parts = torque_parts(cal, abs(slip_rpm), theta_model, force)
        torque = float(parts["torque_Nm"]) * (lockup.direction if in_band else (-1.0 if slip_rpm < 0.0 else 1.0))
        capacity = float(static_capacity_Nm(cal, theta_model, contact))
        bench_torque = not math.isnan(bench_torque_Nm)
        carried = 0.0 < carried_torque_Nm <= TORQUE_MAX_NM   # else the request (wc_clutch_step)
        required = bench_torque_Nm if bench_torque else lockup.direction * (carried_torque_Nm if carried else request_Nm)
        slip_rad_s = slip_rpm * RAD_S_PER_RPM
        if lockup.update(slip_rad_s, required, capacity):
            torque = lockup.torque_Nm(required, capacity)
            status |= STATUS_LOCKED
            power = 0.0
        else:
            power = abs((bench_torque_Nm if bench_torque else torque) * slip_rad_s)
        theta_used = theta_model
        steady = float(thermal_steady_degC(cal, power, oil_degC, housing_degC))
        theta = steady + (self.theta - steady) * self.a_th
        self.theta = min(max(theta, THETA_MIN_DEGC), THETA_MAX_DEGC)      # thermal envelope
        if self.theta > THETA_OVER_DEGC:
            self.over = True
        elif self.theta < THETA_OVER_DEGC - THETA_OVER_HYSTERESIS_K:
            self.over = False
        if self.over:
            status |= STATUS_OVER_TEMPERATURE
        return {"current_mA": current, "pressure_command_Pa": target, "pressure_model_Pa": pressure,
                "force_command_N": force_cmd, "theta_degC": theta_used, "torque_Nm": torque,
                "mu_f": float(parts["mu_f"]), "hbar_m": float(parts["hbar_m"]), "contact_force_N": contact,
                "static_capacity_Nm": capacity, "status": status}


def clutch_steps(cal: Calibration, slip_rpm, theta_oil_degC, theta_housing_degC, torque_request_Nm,
                 mode=None, theta_start_degC=None, bench_force_N=None, bench_torque_Nm=None):
    """The firmware's wc_clutch_step, composed in double precision, one row per period (ClutchReference).
    Returns a dict of arrays; theta_degC[k] is the estimate used in step k (before its update). On a bench
    (rows where bench_force_N / bench_torque_Nm are given and not NaN) the torque model uses the measured force
    and the observer's heat input the measured torque."""
    slip = np.asarray(slip_rpm, dtype=float)
    n = slip.size
    oil = np.broadcast_to(np.asarray(theta_oil_degC, dtype=float), (n,))
    housing = np.broadcast_to(np.asarray(theta_housing_degC, dtype=float), (n,))
    request = np.broadcast_to(np.asarray(torque_request_Nm, dtype=float), (n,))
    modes = np.broadcast_to(np.asarray(MODE_TORQUE if mode is None else mode), (n,))
    def optional(x):
        return np.broadcast_to(np.asarray(np.nan if x is None else x, dtype=float), (n,))
    measured, measured_torque = optional(bench_force_N), optional(bench_torque_Nm)
    ref = ClutchReference(cal, float(oil[0]) if theta_start_degC is None else float(theta_start_degC))
    out = {k: np.empty(n) for k in CLUTCH_OUTPUTS}
    for k in range(n):
        row = ref.step(float(slip[k]), float(oil[k]), float(housing[k]), float(request[k]), int(modes[k]),
                       float(measured[k]), float(measured_torque[k]))
        for key in CLUTCH_OUTPUTS:
            out[key][k] = row[key]
    out["status"] = out["status"].astype(int)
    return out
