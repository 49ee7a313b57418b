#include "wetclutch/wc_calibration.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"

static bool positive(float x) { return isfinite(x) && (x > 0.0f); }
static bool nonnegative(float x) { return isfinite(x) && (x >= 0.0f); }

static wc_cal_error_t check_film(const wc_film_table_t *t)
{
    if ((t->pressure_Pa == NULL) || (t->hbar_m == NULL) || (t->slope_m_per_Pa == NULL) ||
        (t->length < 2u) || (t->length > WC_FILM_MAX_NODES)) {
        return WC_CAL_FILM_TABLE;
    }
    for (uint32_t i = 0u; i < t->length; ++i) { /* bounded by WC_FILM_MAX_NODES */
        if (!nonnegative(t->pressure_Pa[i]) || !positive(t->hbar_m[i]) || !isfinite(t->slope_m_per_Pa[i]) ||
            (t->slope_m_per_Pa[i] > 0.0f)) { /* h_bar falls as p_c rises */
            return WC_CAL_FILM_TABLE;
        }
        if ((i > 0u) && !(t->pressure_Pa[i] > t->pressure_Pa[i - 1u])) {
            return WC_CAL_FILM_AXIS_NOT_MONOTONE;
        }
    }
    return WC_CAL_OK;
}

wc_cal_error_t wc_calibration_check(const wc_calibration_t *cal)
{
    if (cal == NULL) { return WC_CAL_NULL; }
    if (!positive(cal->outer_radius_m)) { return WC_CAL_OUTER_RADIUS; }
    if (!positive(cal->inner_radius_m) || !(cal->inner_radius_m < cal->outer_radius_m)) { return WC_CAL_INNER_RADIUS; }
    if (!positive(cal->friction_area_m2)) { return WC_CAL_FRICTION_AREA; }
    if (!positive(cal->piston_area_m2)) { return WC_CAL_PISTON_AREA; }
    if ((cal->friction_pairs == 0u) || (cal->friction_pairs > 64u)) { return WC_CAL_FRICTION_PAIRS; }
    if (!positive(cal->oil_conductance_W_per_K)) { return WC_CAL_OIL_CONDUCTANCE; }
    if (!nonnegative(cal->housing_conductance_W_per_K)) { return WC_CAL_HOUSING_CONDUCTANCE; }
    if (!positive(cal->heat_capacity_J_per_K)) { return WC_CAL_HEAT_CAPACITY; }
    if (!nonnegative(cal->viscosity_a1_Pa_s)) { return WC_CAL_VISCOSITY_A1; }
    if (!isfinite(cal->viscosity_b1_per_K)) { return WC_CAL_VISCOSITY_B1; }
    if (!nonnegative(cal->viscosity_a2_Pa_s)) { return WC_CAL_VISCOSITY_A2; }
    if (!isfinite(cal->viscosity_b2_per_K)) { return WC_CAL_VISCOSITY_B2; }
    if (!positive(cal->mu1)) { return WC_CAL_MU1; }
    if (!positive(cal->mu2)) { return WC_CAL_MU2; }
    if (!isfinite(cal->mu3)) { return WC_CAL_MU3; }
    if (!positive(cal->stribeck_speed_m_s)) { return WC_CAL_STRIBECK_SPEED; }
    if (!isfinite(cal->theta1_degC)) { return WC_CAL_THETA1; }
    if (!positive(cal->theta2_K)) { return WC_CAL_THETA2; }
    if (!positive(cal->vfs_gain_Pa_per_mA)) { return WC_CAL_VFS_GAIN; }
    if (!positive(cal->vfs_time_constant_s)) { return WC_CAL_VFS_TIME_CONSTANT; }
    if (!nonnegative(cal->return_spring_force_N)) { return WC_CAL_RETURN_SPRING_FORCE; }
    if (!nonnegative(cal->vfs_current_min_mA)) { return WC_CAL_VFS_CURRENT_MIN; }
    if (!positive(cal->vfs_current_max_mA) || !(cal->vfs_current_max_mA > cal->vfs_current_min_mA)) {
        return WC_CAL_VFS_CURRENT_MAX;
    }
    /* The inverse's iteration bound assumes the force range stays below
     * WC_FORCE_MAX_N (2^WC_INVERSE_MAX_ITERATIONS halvings reach the tolerance). */
    if (!(cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 <= WC_FORCE_MAX_N)) {
        return WC_CAL_VFS_CURRENT_MAX;
    }
    if (!positive(cal->control_period_s)) { return WC_CAL_CONTROL_PERIOD; }
    return check_film(&cal->film);
}

/* Indexed by wc_cal_error_t, in its order: a code added without a name fails to compile. */
static const char *const cal_error_names[] = {
    "ok",
    "calibration (NULL)",
    "outer_radius_m",
    "inner_radius_m",
    "friction_area_m2",
    "piston_area_m2",
    "friction_pairs",
    "oil_conductance_W_per_K",
    "housing_conductance_W_per_K",
    "heat_capacity_J_per_K",
    "viscosity_a1_Pa_s",
    "viscosity_b1_per_K",
    "viscosity_a2_Pa_s",
    "viscosity_b2_per_K",
    "mu1",
    "mu2",
    "mu3",
    "stribeck_speed_m_s",
    "theta1_degC",
    "theta2_K",
    "vfs_gain_Pa_per_mA",
    "vfs_time_constant_s",
    "return_spring_force_N",
    "vfs_current_min_mA",
    "vfs_current_max_mA",
    "control_period_s",
    "film (table arrays, length or entries)",
    "film.pressure_Pa (not strictly increasing)",
};
WC_STATIC_ASSERT(sizeof cal_error_names / sizeof cal_error_names[0] == (size_t)WC_CAL_ERRORS,
                 cal_error_names_cover_every_code);

const char *wc_cal_error_name(wc_cal_error_t error)
{
    return ((unsigned)error < (unsigned)WC_CAL_ERRORS) ? cal_error_names[error] : "unknown";
}
