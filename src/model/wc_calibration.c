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

const char *wc_cal_error_name(wc_cal_error_t error)
{
    switch (error) {
    case WC_CAL_OK: return "ok";
    case WC_CAL_NULL: return "calibration (NULL)";
    case WC_CAL_OUTER_RADIUS: return "outer_radius_m";
    case WC_CAL_INNER_RADIUS: return "inner_radius_m";
    case WC_CAL_FRICTION_AREA: return "friction_area_m2";
    case WC_CAL_PISTON_AREA: return "piston_area_m2";
    case WC_CAL_FRICTION_PAIRS: return "friction_pairs";
    case WC_CAL_OIL_CONDUCTANCE: return "oil_conductance_W_per_K";
    case WC_CAL_HOUSING_CONDUCTANCE: return "housing_conductance_W_per_K";
    case WC_CAL_HEAT_CAPACITY: return "heat_capacity_J_per_K";
    case WC_CAL_VISCOSITY_A1: return "viscosity_a1_Pa_s";
    case WC_CAL_VISCOSITY_B1: return "viscosity_b1_per_K";
    case WC_CAL_VISCOSITY_A2: return "viscosity_a2_Pa_s";
    case WC_CAL_VISCOSITY_B2: return "viscosity_b2_per_K";
    case WC_CAL_MU1: return "mu1";
    case WC_CAL_MU2: return "mu2";
    case WC_CAL_MU3: return "mu3";
    case WC_CAL_STRIBECK_SPEED: return "stribeck_speed_m_s";
    case WC_CAL_THETA1: return "theta1_degC";
    case WC_CAL_THETA2: return "theta2_K";
    case WC_CAL_VFS_GAIN: return "vfs_gain_Pa_per_mA";
    case WC_CAL_VFS_TIME_CONSTANT: return "vfs_time_constant_s";
    case WC_CAL_RETURN_SPRING_FORCE: return "return_spring_force_N";
    case WC_CAL_VFS_CURRENT_MIN: return "vfs_current_min_mA";
    case WC_CAL_VFS_CURRENT_MAX: return "vfs_current_max_mA";
    case WC_CAL_CONTROL_PERIOD: return "control_period_s";
    case WC_CAL_FILM_TABLE: return "film (table arrays, length or entries)";
    case WC_CAL_FILM_AXIS_NOT_MONOTONE: return "film.pressure_Pa (not strictly increasing)";
    default: return "unknown";
    }
}
