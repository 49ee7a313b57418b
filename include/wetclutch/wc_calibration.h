/* Calibration of one clutch: the constants of the model (paper Table 1 plus
 * project defaults), generated into lut/ by `wetclutch lut`. Passed as const
 * and validated once by wc_calibration_check() (wc_clutch_init calls it). */
#ifndef WC_CALIBRATION_H
#define WC_CALIBRATION_H

#include <stdint.h>

/* h_bar(p_c) nodes for cubic Hermite interpolation (eq. 9, 15, 16). */
typedef struct {
    const float *pressure_Pa;     /* contact pressure p_c, strictly increasing */
    const float *hbar_m;          /* average film thickness h_bar at each node */
    const float *slope_m_per_Pa;  /* exact d h_bar / d p_c at each node */
    uint32_t length;              /* nodes, 2..WC_FILM_MAX_NODES */
} wc_film_table_t;

typedef struct {
    float outer_radius_m;              /* R_o */
    float inner_radius_m;              /* R_i */
    float friction_area_m2;            /* A_f, nominal lining contact area */
    float piston_area_m2;              /* A_p */
    uint32_t friction_pairs;           /* N_c */
    float oil_conductance_W_per_K;     /* k1 */
    float housing_conductance_W_per_K; /* k2 */
    float heat_capacity_J_per_K;       /* C of eq. 1 */
    float viscosity_a1_Pa_s;           /* mu_v1 of eq. 2 */
    float viscosity_b1_per_K;          /* mu_v2 */
    float viscosity_a2_Pa_s;           /* mu_v3 */
    float viscosity_b2_per_K;          /* mu_v4 */
    float mu1;                         /* eq. 18: mu_f at high speed, theta_1 */
    float mu2;                         /* eq. 18: mu_f at zero speed, theta_1 */
    float mu3;                         /* eq. 18: temperature coefficient */
    float stribeck_speed_m_s;          /* v_s */
    float theta1_degC;                 /* temperature normalization offset */
    float theta2_K;                    /* temperature normalization span */
    float vfs_gain_Pa_per_mA;          /* K: steady pressure per current */
    float vfs_time_constant_s;         /* tau of the VFS/pressure lag */
    float return_spring_force_N;       /* F_s */
    float vfs_current_min_mA;
    float vfs_current_max_mA;
    float control_period_s;            /* dt of one wc_clutch_step */
    /* Engagement edges (DESIGN section 9) */
    float film_squeeze_factor;         /* phi of the Reynolds squeeze film; 0: film state off (eq. 16, steady) */
    float static_friction_factor;      /* static capacity / (mu_f(0, theta) R_eff N_c F_c) */
    float lock_slip_rad_s;             /* |slip| below it for lock_dwell_periods: locked */
    float breakaway_slip_rad_s;        /* |slip| above it while locked: breakaway (> lock_slip_rad_s) */
    float holding_margin;              /* a locked clutch is held at (1 + margin) times the request's force */
    uint32_t lock_dwell_periods;       /* control periods inside the lock band before locking */
    /* The open element's drag (DESIGN 15): with the piston retracted (modelled P A_p at or below the return
     * spring's preload, 0.8 F_s; part-way between that and F_s) the viscous term shears the retracted stroke's
     * clearance too (that part of it), and the open pack's aeration lowers it */
    float open_clearance_m;            /* retracted piston's stroke per gap, x_s / N_c, added to h_bar; 0: off */
    float open_aeration_speed_rad_s;   /* w_a: open drag / (1 + (slip / w_a)^2); 0: off */
    wc_film_table_t film;
} wc_calibration_t;

/* Which field an invalid calibration fails on (0 = valid). A field's code:
 * NaN, infinite, or outside its limit (below); the relations between fields
 * have their own codes after WC_CAL_FILM_AXIS_NOT_MONOTONE, or the code of the
 * field they are checked with. wc_cal_error_name names the field(s). */
typedef enum {
    WC_CAL_OK = 0,
    WC_CAL_NULL,
    WC_CAL_OUTER_RADIUS,
    WC_CAL_INNER_RADIUS,        /* also: not below the outer radius */
    WC_CAL_FRICTION_AREA,
    WC_CAL_PISTON_AREA,
    WC_CAL_FRICTION_PAIRS,
    WC_CAL_OIL_CONDUCTANCE,
    WC_CAL_HOUSING_CONDUCTANCE,
    WC_CAL_HEAT_CAPACITY,
    WC_CAL_VISCOSITY_A1,
    WC_CAL_VISCOSITY_B1,
    WC_CAL_VISCOSITY_A2,
    WC_CAL_VISCOSITY_B2,
    WC_CAL_MU1,
    WC_CAL_MU2,
    WC_CAL_MU3,
    WC_CAL_STRIBECK_SPEED,
    WC_CAL_THETA1,
    WC_CAL_THETA2,
    WC_CAL_VFS_GAIN,
    WC_CAL_VFS_TIME_CONSTANT,
    WC_CAL_RETURN_SPRING_FORCE,
    WC_CAL_VFS_CURRENT_MIN,
    WC_CAL_VFS_CURRENT_MAX,     /* also: not above the minimum, a piston force K i_max A_p above
                                 * WC_FORCE_MAX_N, or not above the spring force F_s (cannot apply) */
    WC_CAL_CONTROL_PERIOD,
    WC_CAL_FILM_SQUEEZE_FACTOR, /* also: neither 0 (off) nor >= WC_CAL_LIMIT_FILM_SQUEEZE_FACTOR_MIN */
    WC_CAL_STATIC_FRICTION_FACTOR,
    WC_CAL_LOCK_SLIP,
    WC_CAL_BREAKAWAY_SLIP,      /* also: not above the lock band */
    WC_CAL_HOLDING_MARGIN,
    WC_CAL_LOCK_DWELL,
    WC_CAL_OPEN_CLEARANCE,
    WC_CAL_OPEN_AERATION_SPEED, /* neither 0 (off) nor in [WC_CAL_LIMIT_OPEN_AERATION_SPEED_MIN_rad_s, ..._MAX_rad_s] */
    WC_CAL_FILM_TABLE,          /* missing arrays, bad length, non-finite entry */
    WC_CAL_FILM_AXIS_NOT_MONOTONE,
    WC_CAL_CONDUCTANCE_SUM,     /* k1 + k2 below WC_CAL_LIMIT_CONDUCTANCE_SUM_MIN_W_per_K */
    WC_CAL_THERMAL_TIME_CONSTANT, /* C / (k1 + k2) outside [control period, WC_CAL_LIMIT_TIME_CONSTANT_MAX_s] */
    WC_CAL_VISCOSITY_RANGE,     /* mu_v (eq. 2) not in (0, WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s] on the domain */
    WC_CAL_FRICTION_DOMAIN,     /* mu_f (eq. 18) not in (0, WC_CAL_LIMIT_MU_MAX] on the domain */
    WC_CAL_FILM_RANGE,          /* h_bar outside [WC_CAL_LIMIT_FILM_HBAR_MIN_m, ..._MAX_m], or p_0 < 0 */
    WC_CAL_FILM_NOT_MONOTONE,   /* slope > 0, h_bar not strictly decreasing, or Fritsch-Carlson violated */
    WC_CAL_FILM_COVERAGE,       /* last node below the contact pressure at the maximum current */
    WC_CAL_ERRORS               /* number of codes, not an error */
} wc_cal_error_t;

/* Limits of wc_calibration_check (DESIGN section 8, "Calibration validity").
 * Together they prove, from the equations, that every output of every public
 * function is finite and physical on the model's domain: theta in
 * [WC_THETA_MIN_degC, WC_THETA_MAX_degC], |slip| <= WC_SLIP_MAX_rad_s, contact
 * force <= WC_FORCE_MAX_N (wc_config.h). tools/wetclutch/calibration/rules.py applies
 * the same rules with the same numbers (LIMITS; tests/python/
 * test_calibration_rules.py compares them with these). Each bound is far
 * outside any real clutch pack; its reason: */
/* R_o: a clutch disc, not a flywheel. R_eff < R_o, so the torque arm
 * R_eff N_c <= 64 m and the sliding speed R_eff |dw| <= 1047 m/s. */
#define WC_CAL_LIMIT_RADIUS_MAX_m 1.0f
/* A_p: with K i_max A_p <= WC_FORCE_MAX_N it bounds the piston, not the force. */
#define WC_CAL_LIMIT_PISTON_AREA_MAX_m2 1.0f
/* A_f <= pi R_o^2: the lining cannot be larger than the face of the disc. */
#define WC_CAL_LIMIT_PI 3.14159265f
/* N_c: 1..64 friction pairs (an AT pack has 2..10). */
#define WC_CAL_LIMIT_FRICTION_PAIRS_MAX 64u
/* k1, k2 <= 1e5 W/K (a pack has ~100 W/K): the steady temperature
 * (P + k1 th_oil + k2 th_housing) / (k1 + k2) stays far from overflow. */
#define WC_CAL_LIMIT_CONDUCTANCE_MAX_W_per_K 1e5f
/* k1 + k2 >= 1e-3 W/K: the division by k1 + k2 (eq. 1 at rest) stays finite
 * for the largest heat input (|T dw| <= ~2e19 W: 2e22 K before the envelope clamps). */
#define WC_CAL_LIMIT_CONDUCTANCE_SUM_MIN_W_per_K 1e-3f
/* C <= 1e7 J/K: 20 t of steel; a pack has ~300 J/K. */
#define WC_CAL_LIMIT_HEAT_CAPACITY_MAX_J_per_K 1e7f
/* C / (k1 + k2) <= 1e5 s (28 h): a slower observer never moves in a drive (its
 * decay factor rounds to 1 in float); the lower bound is the control period
 * (a thermal mode faster than one step is not resolved by the observer). */
#define WC_CAL_LIMIT_TIME_CONSTANT_MAX_s 1e5f
/* |b1|, |b2| <= 0.3 /K: b theta stays within +-75 on [-40, 250] degC, inside
 * [-87, 88] where the model's exponential (src/model/wc_exp.c) is valid. */
#define WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K 0.3f
/* mu_v <= 100 Pa s on the domain (the paper's oil: 3.6 Pa s at -40 degC): it
 * bounds the viscous torque R_eff N_c mu_v A_f v / h_bar. */
#define WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s 100.0f
/* mu1, mu2 in [1e-3, 1] and mu_f <= 1 on the domain (wet friction pairs:
 * 0.05..0.2). The lower limit keeps mu_f > 0 in float: the Stribeck blend
 * mu1 + (mu2 - mu1) e^-x rounds by ~1e-7, which would cancel a smaller
 * mu1 or mu2 to 0. */
#define WC_CAL_LIMIT_MU_MIN 1e-3f
#define WC_CAL_LIMIT_MU_MAX 1.0f
/* v_s in [1e-6, 100] m/s (the paper's 0.024 m/s): speed / v_s stays finite. */
#define WC_CAL_LIMIT_STRIBECK_SPEED_MIN_m_s 1e-6f
#define WC_CAL_LIMIT_STRIBECK_SPEED_MAX_m_s 100.0f
/* theta2 >= 1 K: the normalization span of eq. 18 (the paper's 70 K); a
 * smaller one makes mu3 (theta - theta1) / theta2 overflow for modest mu3. */
#define WC_CAL_LIMIT_THETA2_MIN_K 1.0f
/* K <= 1e6 Pa/mA (1 GPa at 1 A; the paper's 2300 Pa/mA). */
#define WC_CAL_LIMIT_VFS_GAIN_MAX_Pa_per_mA 1e6f
/* tau in [1e-4, 10] s (the paper's 0.06 s). */
#define WC_CAL_LIMIT_VFS_TIME_CONSTANT_MIN_s 1e-4f
#define WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s 10.0f
/* F_s <= 1e5 N, the largest contact force the model takes (WC_FORCE_MAX_N). */
#define WC_CAL_LIMIT_SPRING_FORCE_MAX_N 1e5f
/* i_min, i_max <= 1e4 mA (10 A; a VFS takes ~1 A). */
#define WC_CAL_LIMIT_CURRENT_MAX_mA 1e4f
/* control period in [1e-4, 0.1] s (the paper's TCU: 1 ms). */
#define WC_CAL_LIMIT_CONTROL_PERIOD_MIN_s 1e-4f
#define WC_CAL_LIMIT_CONTROL_PERIOD_MAX_s 0.1f
/* h_bar in [1e-9, 1e-3] m at every node: 1 nm (below it the viscous term
 * mu_v A_f v / h_bar is not a film any more, and it bounds that term) to 1 mm
 * (more than any clearance in a pack). The interpolant of a table that passes
 * the Fritsch-Carlson test stays between its nodes, so these bound it too
 * (in float within 20 % of the last node: tests/c/test_calibration.c). */
#define WC_CAL_LIMIT_FILM_HBAR_MIN_m 1e-9f
#define WC_CAL_LIMIT_FILM_HBAR_MAX_m 1e-3f
/* Fritsch-Carlson (1980): with Delta_k = (h_k+1 - h_k) / (p_k+1 - p_k) < 0,
 * alpha = s_k / Delta_k, beta = s_k+1 / Delta_k, alpha, beta >= 0 and
 * alpha^2 + beta^2 <= 9 make the cubic Hermite on [p_k, p_k+1] monotone. */
#define WC_CAL_LIMIT_FRITSCH_CARLSON 9.0f
/* Squeeze film (DESIGN section 9): phi = 0 switches the film state off; else
 * phi in [1e-4, 1]. phi <= 1: grooves and a permeable lining only let the oil
 * out faster than between smooth plates. The lower bound keeps phi itself
 * away from the denormals; the update is stable for any damping, even one
 * that underflows for a tiny pack or oil (the film then settles at once,
 * wc_film_advance_m). */
#define WC_CAL_LIMIT_FILM_SQUEEZE_FACTOR_MIN 1e-4f
#define WC_CAL_LIMIT_FILM_SQUEEZE_FACTOR_MAX 1.0f
/* Static capacity factor in [0.5, 2]: static over kinetic-at-zero-speed
 * friction of wet pairs is 1.0..1.3. */
#define WC_CAL_LIMIT_STATIC_FRICTION_FACTOR_MIN 0.5f
#define WC_CAL_LIMIT_STATIC_FRICTION_FACTOR_MAX 2.0f
/* Lock band (0, 10] rad/s (95 rpm) and breakaway band (lock band, 20] rad/s:
 * lock-up detection, not slip control. */
#define WC_CAL_LIMIT_LOCK_SLIP_MAX_rad_s 10.0f
#define WC_CAL_LIMIT_BREAKAWAY_SLIP_MAX_rad_s 20.0f
/* Holding margin in [0.05, 1]: up to twice the request's force; at least 5 %,
 * because half of it is the lock-up's torque hysteresis (wc_lockup.h): with
 * none, a locked clutch held at exactly its request would break away and
 * re-lock as the capacity drifts (a cooling pack). */
#define WC_CAL_LIMIT_HOLDING_MARGIN_MIN 0.05f
#define WC_CAL_LIMIT_HOLDING_MARGIN_MAX 1.0f
/* Lock dwell 1..255 periods: the firmware counts it in 8 bits. */
#define WC_CAL_LIMIT_LOCK_DWELL_MAX_periods 255u
/* The open element's drag (DESIGN 15). Clearance in [0, 5e-3] m per gap (0: off): a retracted piston's
 * stroke over the pack's gaps is 0.1..0.5 mm, 5 mm more than any pack's whole stroke; h_bar + the
 * clearance is finite and >= h_bar, so the viscous term only falls. Aeration speed 0 (off) or in
 * [1, 1e4] rad/s (measured open packs' drag peaks at 100..200 rad/s; the bounds leave room for the
 * equivalent clutch of a shift, w_a / |a|, wc_transmission.c): (slip / w_a)^2 <= (WC_SLIP_MAX_rad_s)^2
 * ~ 1.1e6, so the factor 1 / (1 + (slip / w_a)^2) lies in (0, 1]. */
#define WC_CAL_LIMIT_OPEN_CLEARANCE_MAX_m 5e-3f
#define WC_CAL_LIMIT_OPEN_AERATION_SPEED_MIN_rad_s 1.0f
#define WC_CAL_LIMIT_OPEN_AERATION_SPEED_MAX_rad_s 1e4f

/* Check every field against the limits above, and the relations between
 * fields that the equations need (DESIGN section 8): radii ordered, mu_v and
 * mu_f within their bounds on the whole temperature x speed domain, finite
 * thermal time constant, the piston can apply and stays below WC_FORCE_MAX_N,
 * the film table strictly monotone with a monotone positive Hermite
 * interpolant on every interval that reaches the contact pressure at the
 * maximum current. NaN and infinities fail every rule. Returns the first
 * failing check: each field against its range in declaration order, then the
 * relations (in the order of the codes after WC_CAL_FILM_AXIS_NOT_MONOTONE,
 * or the field they are reported on), then the film table. */
wc_cal_error_t wc_calibration_check(const wc_calibration_t *cal);

/* Name of the field for an error code ("outer_radius_m", ...), for logs. */
const char *wc_cal_error_name(wc_cal_error_t error);

#endif /* WC_CALIBRATION_H */
