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
    wc_film_table_t film;
} wc_calibration_t;

/* Which field an invalid calibration fails on (0 = valid). */
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
    WC_CAL_VFS_CURRENT_MAX,     /* also: not above the minimum, or a piston force above WC_FORCE_MAX_N */
    WC_CAL_CONTROL_PERIOD,
    WC_CAL_FILM_TABLE,          /* missing arrays, bad length, non-finite entry */
    WC_CAL_FILM_AXIS_NOT_MONOTONE,
    WC_CAL_ERRORS               /* number of codes, not an error */
} wc_cal_error_t;

/* Check every field: finite, positive where the physics needs it, film axis
 * strictly increasing. Returns the first failing field. */
wc_cal_error_t wc_calibration_check(const wc_calibration_t *cal);

/* Name of the field for an error code ("outer_radius_m", ...), for logs. */
const char *wc_cal_error_name(wc_cal_error_t error);

#endif /* WC_CALIBRATION_H */
