/* Helpers shared by the library's modules; not part of the public API. */
#ifndef WC_INTERNAL_H
#define WC_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wetclutch/wc_model.h"

static inline bool wc_in_range(float x, float lo, float hi)
{
    /* false for NaN: every comparison with NaN is false */
    return (x >= lo) && (x <= hi);
}

static inline bool wc_slip_valid(float slip_rad_s)
{
    return wc_in_range(slip_rad_s, -WC_SLIP_MAX_rad_s, WC_SLIP_MAX_rad_s);
}

static inline bool wc_theta_valid(float theta_degC)
{
    return wc_in_range(theta_degC, WC_THETA_MIN_degC, WC_THETA_MAX_degC);
}

/* The model's terms of the pack's radii (eq. 3's R_eff, the squeeze film's
 * damping, DESIGN 9) from cal, and model->cal = cal; the rest of the model
 * kept. wc_model_init's last step; alone, for a checked calibration that
 * differs from the model's own in the radii and the film factor only (an
 * element's equivalent clutch, wc_transmission.c): no check, no expf. */
void wc_model_set_geometry(wc_model_t *model, const wc_calibration_t *cal);

/* One exact ZOH step of eq. 1 for validated inputs (wc_thermal_step checks
 * them; wc_clutch_step's are checked on entry), kept in the thermal envelope
 * (DESIGN section 8): the estimate stays where the maps are valid, and a heat
 * input so large that the sum is not a number is a hot clutch, not an
 * invalid one. */
static inline float wc_thermal_advance(const wc_model_t *model, float theta_degC, float power_W,
                                       float theta_oil_degC, float theta_housing_degC)
{
    const wc_calibration_t *cal = model->cal;
    const float k1 = cal->oil_conductance_W_per_K;
    const float k2 = cal->housing_conductance_W_per_K;
    /* eq. 1 at rest: C dtheta/dt = 0 */
    const float steady_degC = (power_W + k1 * theta_oil_degC + k2 * theta_housing_degC) / (k1 + k2);
    /* eq. 1 exact ZOH step; the decay factor was computed at init */
    const float next_degC = steady_degC + (theta_degC - steady_degC) * model->thermal_decay;
    return (next_degC < WC_THETA_MIN_degC) ? WC_THETA_MIN_degC
         : ((next_degC <= WC_THETA_MAX_degC) ? next_degC : WC_THETA_MAX_degC);
}

/* The hydraulics of wc_hydraulics.h for the inputs the clutch step produces
 * (a force in [0, F_max], a finite pressure, a current in the solenoid's
 * range, a finite reached pressure): the public functions limit any input,
 * these skip that on the hot path. */
static inline float wc_piston_pressure_at(const wc_calibration_t *cal, float force_N)
{
    return (force_N + cal->return_spring_force_N) / cal->piston_area_m2;  /* P = (F_app + F_s) / A_p */
}

static inline float wc_contact_force_at(const wc_calibration_t *cal, float pressure_Pa)
{
    const float force_N = pressure_Pa * cal->piston_area_m2 - cal->return_spring_force_N;
    return (force_N > 0.0f) ? force_N : 0.0f;  /* the spring holds the pack open */
}

static inline float wc_vfs_lag_at(const wc_model_t *model, float pressure_reached_Pa, float current_mA)
{
    /* tau dP/dt = K i - P, exact for i held over the period */
    const float target_Pa = model->cal->vfs_gain_Pa_per_mA * current_mA;
    return target_Pa + (pressure_reached_Pa - target_Pa) * model->vfs_decay;
}

/* The temperature factor of eq. 18, 1 + mu3 (theta - theta1) / theta2: also
 * the static capacity's (DESIGN 9, mu_f(0, theta) = mu2 times it). */
static inline float wc_friction_temperature_factor(const wc_calibration_t *cal, float theta_degC)
{
    return 1.0f + cal->mu3 * (theta_degC - cal->theta1_degC) / cal->theta2_K;
}

/* eq. 18 without the input clamping of wc_friction_coefficient, for the
 * temperature factor of a theta in [WC_THETA_MIN_degC, WC_THETA_MAX_degC]
 * (src/model/wc_friction.c). */
float wc_friction_at(const wc_calibration_t *cal, float speed_m_s, float temperature_factor);

/* e^x within 2 ulp of expf on [-87, 88], in about a third of newlib's
 * instructions (src/model/wc_exp.c; tests/c/test_exp.c). */
float wc_exp(float x);

#endif /* WC_INTERNAL_H */
