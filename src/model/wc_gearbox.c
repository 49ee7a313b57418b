#include "wetclutch/wc_gearbox.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wc_internal.h"

/* The checks' tolerances: the generated tables hold 6 significant digits
 * (tools/wetclutch/gearbox/table.py), so a slip that is zero in exact
 * arithmetic is within a few 1e-6 of the speeds' scale. */
#define SLIP_ZERO_TOLERANCE 1e-4f    /* rad/s of slip per rad/s of turbine speed */
#define RATIO_MIN 0.1f
#define RATIO_MAX 20.0f
#define HOLDING_MAX 20.0f            /* Nm per Nm of turbine torque */

static bool finite_in(float value, float lo, float hi) { return (value >= lo) && (value <= hi); }  /* false for NaN */
/* Exactly zero (also true for NaN: callers check finiteness first). */
static bool is_zero(float value) { return !(value < 0.0f) && !(value > 0.0f); }
/* Equal within the table's rounding (the scale is the same number as its a in the generated table). */
static bool same(float x, float y) { return fabsf(x - y) <= SLIP_ZERO_TOLERANCE * fabsf(y); }

/* Bits set in a closed mask (bounded: WC_GEARBOX_ELEMENTS_MAX bits looked at). */
static uint32_t elements_in(uint32_t mask)
{
    uint32_t n = 0u;
    for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) { n += (mask >> e) & 1u; }
    return n;
}

/* The element number of a one-bit mask (WC_GEARBOX_ELEMENTS_MAX if not one bit). */
static uint32_t element_of(uint32_t mask)
{
    if (elements_in(mask) != 1u) { return WC_GEARBOX_ELEMENTS_MAX; }
    uint32_t e = 0u;
    while ((e < WC_GEARBOX_ELEMENTS_MAX) && (((mask >> e) & 1u) == 0u)) { ++e; }
    return e;
}

static bool gear_exists(const wc_gearbox_t *g, uint32_t gear)
{
    return (gear == WC_GEARBOX_REVERSE) ? g->has_reverse : (gear <= g->forward_gears);
}

static wc_gearbox_error_t check_gears(const wc_gearbox_t *g)
{
    const uint32_t all = (1u << g->element_count) - 1u;
    for (uint32_t gear = 0u; gear <= g->forward_gears; ++gear) {
        if (!gear_exists(g, gear)) { continue; }
        const float r = g->ratio[gear];
        const bool sign_ok = (gear == WC_GEARBOX_REVERSE) ? (r < 0.0f) : (r > 0.0f);
        if (!sign_ok || !finite_in(fabsf(r), RATIO_MIN, RATIO_MAX)) { return WC_GEARBOX_GEAR_RATIO; }
        if ((gear >= 2u) && !(r < g->ratio[gear - 1u])) { return WC_GEARBOX_GEAR_RATIO; }  /* DESIGN 15: 1st lowest */
        const uint32_t mask = g->closed_mask[gear];
        if (((mask & ~all) != 0u) || (elements_in(mask) != g->closed_per_gear)) { return WC_GEARBOX_GEAR_ELEMENTS; }
        for (uint32_t other = 0u; other < gear; ++other) {
            if (gear_exists(g, other) && (g->closed_mask[other] == mask)) { return WC_GEARBOX_GEAR_ELEMENTS; }
        }
        for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
            const float h = g->holding_torque_per_Nm[gear][e];
            const bool closed = ((mask >> e) & 1u) != 0u;
            if (!finite_in(fabsf(h), 0.0f, HOLDING_MAX) || (!closed && !is_zero(h))) { return WC_GEARBOX_HOLDING_TORQUE; }
        }
    }
    return WC_GEARBOX_OK;
}

/* A slip that must be zero at turbine speed 1 and output speed w_o (rad/s per rad/s). */
static bool at_rest(wc_slip_map_t s, float output_per_turbine)
{
    return fabsf(s.a - s.b * output_per_turbine) <= SLIP_ZERO_TOLERANCE * (1.0f + fabsf(s.a));
}

static wc_gearbox_error_t check_shift(const wc_gearbox_t *g, uint32_t i)
{
    const wc_gearbox_shift_t *s = &g->shift[i];
    const uint32_t from = s->source_gear;
    const uint32_t to = s->target_gear;
    if ((from == to) || (from == WC_GEARBOX_REVERSE) || (to == WC_GEARBOX_REVERSE) || !gear_exists(g, from) ||
        !gear_exists(g, to)) {
        return WC_GEARBOX_SHIFT_GEARS;
    }
    const uint32_t opens = g->closed_mask[from] & ~g->closed_mask[to];
    const uint32_t closes = g->closed_mask[to] & ~g->closed_mask[from];
    if ((elements_in(opens) != 1u) || (elements_in(closes) != 1u)) { return WC_GEARBOX_SHIFT_GEARS; }
    for (uint32_t j = 0u; j < i; ++j) {
        if ((g->shift[j].source_gear == from) && (g->shift[j].target_gear == to)) { return WC_GEARBOX_SHIFT_GEARS; }
    }
    if ((s->offgoing != element_of(opens)) || (s->oncoming != element_of(closes))) { return WC_GEARBOX_SHIFT_ELEMENTS; }
    const uint32_t held = g->closed_mask[from] & g->closed_mask[to];
    for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
        const wc_slip_map_t m = s->slip[e];
        if (!finite_in(fabsf(m.a), 0.0f, RATIO_MAX) || !finite_in(fabsf(m.b), 0.0f, RATIO_MAX)) {
            return WC_GEARBOX_SHIFT_SLIPS;
        }
        if ((((held >> e) & 1u) != 0u) && (!is_zero(m.a) || !is_zero(m.b))) { return WC_GEARBOX_SHIFT_SLIPS; }
    }
    /* the off-going element is at rest in the source gear, the on-coming one in the target gear */
    const wc_slip_map_t off = s->slip[s->offgoing];
    const wc_slip_map_t on = s->slip[s->oncoming];
    if (!at_rest(off, 1.0f / g->ratio[from]) || !at_rest(on, 1.0f / g->ratio[to]) ||
        !same(s->oncoming_slip_scale, on.a) || !same(s->offgoing_slip_scale, off.a) || (fabsf(on.a) < RATIO_MIN) ||
        (fabsf(off.a) < RATIO_MIN)) {
        return WC_GEARBOX_SHIFT_SLIPS;
    }
    /* the reduced model, in wc_shift_calibration_check's ranges (DESIGN 10) */
    if (!finite_in(s->output_ratio, 0.05f, RATIO_MAX) || !finite_in(s->offgoing_ratio, 0.05f, RATIO_MAX) ||
        !finite_in(s->turbine_inertia_kg_m2, 1e-4f, 100.0f) || !finite_in(s->output_inertia_kg_m2, 1e-4f, 1e5f) ||
        !finite_in(s->jerk_per_torque_rate, 0.0f, 1.0f)) {
        return WC_GEARBOX_SHIFT_MODEL;
    }
    return WC_GEARBOX_OK;
}

wc_gearbox_error_t wc_gearbox_check(const wc_gearbox_t *gearbox)
{
    if (gearbox == NULL) { return WC_GEARBOX_NULL; }
    const wc_gearbox_t *g = gearbox;
    if ((g->element_count < 3u) || (g->element_count > WC_GEARBOX_ELEMENTS_MAX) || (g->closed_per_gear < 1u) ||
        (g->closed_per_gear >= g->element_count) || (g->forward_gears < 1u) ||
        (g->forward_gears >= WC_GEARBOX_GEARS_MAX) || (g->shift_count > WC_GEARBOX_SHIFTS_MAX)) {
        return WC_GEARBOX_COUNTS;
    }
    const wc_gearbox_error_t gears = check_gears(g);
    if (gears != WC_GEARBOX_OK) { return gears; }
    for (uint32_t i = 0u; i < g->shift_count; ++i) {
        const wc_gearbox_error_t e = check_shift(g, i);
        if (e != WC_GEARBOX_OK) { return e; }
    }
    return WC_GEARBOX_OK;
}

wc_gearbox_shift_result_t wc_gearbox_find_shift(const wc_gearbox_t *gearbox, uint32_t current_gear,
                                                uint32_t target_gear, const wc_gearbox_shift_t **shift)
{
    WC_ASSERT((gearbox != NULL) && (shift != NULL));
    if (shift != NULL) { *shift = NULL; }
    if ((gearbox == NULL) || (shift == NULL)) { return WC_GEARBOX_SHIFT_NO_SUCH_GEAR; }
    const wc_gearbox_t *g = gearbox;
    if ((current_gear >= WC_GEARBOX_GEARS_MAX) || (target_gear >= WC_GEARBOX_GEARS_MAX) ||
        !gear_exists(g, current_gear) || !gear_exists(g, target_gear)) {
        return WC_GEARBOX_SHIFT_NO_SUCH_GEAR;
    }
    if (current_gear == target_gear) { return WC_GEARBOX_SHIFT_SAME_GEAR; }
    if ((current_gear == WC_GEARBOX_REVERSE) || (target_gear == WC_GEARBOX_REVERSE)) { return WC_GEARBOX_SHIFT_DIRECTION; }
    const uint32_t opens = g->closed_mask[current_gear] & ~g->closed_mask[target_gear];
    const uint32_t closes = g->closed_mask[target_gear] & ~g->closed_mask[current_gear];
    if ((elements_in(opens) != 1u) || (elements_in(closes) != 1u)) { return WC_GEARBOX_SHIFT_SWAP; }
    for (uint32_t i = 0u; (i < g->shift_count) && (i < WC_GEARBOX_SHIFTS_MAX); ++i) {
        if ((g->shift[i].source_gear == current_gear) && (g->shift[i].target_gear == target_gear)) {
            *shift = &g->shift[i];
            return WC_GEARBOX_SHIFT_OK;
        }
    }
    return WC_GEARBOX_SHIFT_NOT_IN_TABLE;
}

float wc_gearbox_element_slip_rad_s(const wc_gearbox_shift_t *shift, uint32_t element, float turbine_rad_s,
                                    float output_rad_s)
{
    WC_ASSERT(shift != NULL);
    if ((shift == NULL) || (element >= WC_GEARBOX_ELEMENTS_MAX)) { return NAN; }
    const wc_slip_map_t m = shift->slip[element];
    return m.a * turbine_rad_s - m.b * output_rad_s;  /* DESIGN 15: linear in the two speeds */
}

float wc_gearbox_holding_request_Nm(const wc_gearbox_t *gearbox, uint32_t gear, uint32_t element,
                                    float turbine_torque_Nm, float margin_factor, float floor_Nm)
{
    WC_ASSERT(gearbox != NULL);
    if ((gearbox == NULL) || (gear >= WC_GEARBOX_GEARS_MAX) || (element >= WC_GEARBOX_ELEMENTS_MAX) ||
        !gear_exists(gearbox, gear) || (((gearbox->closed_mask[gear] >> element) & 1u) == 0u)) {
        return 0.0f;
    }
    if (!isfinite(turbine_torque_Nm) || !isfinite(margin_factor) || !isfinite(floor_Nm)) { return WC_TORQUE_MAX_Nm; }
    const float need_Nm = fabsf(gearbox->holding_torque_per_Nm[gear][element] * turbine_torque_Nm) * fabsf(margin_factor);
    const float floor_abs_Nm = fabsf(floor_Nm);
    const float request_Nm = (need_Nm > floor_abs_Nm) ? need_Nm : floor_abs_Nm;
    return (request_Nm < WC_TORQUE_MAX_Nm) ? request_Nm : WC_TORQUE_MAX_Nm;
}

wc_shift_type_t wc_gearbox_shift_type(const wc_gearbox_t *gearbox, const wc_gearbox_shift_t *shift,
                                      float turbine_torque_Nm)
{
    WC_ASSERT((gearbox != NULL) && (shift != NULL));
    /* DESIGN 15: an upshift goes to the lower ratio (the check keeps forward ratios decreasing) */
    const bool up = (gearbox == NULL) || (shift == NULL) || (shift->target_gear > shift->source_gear);
    /* false for NaN: power-on; a downshift needs the engine's torque for its inertia phase (wc_gearbox.h) */
    const float power_on_min_Nm = up ? 0.0f : WC_GEARBOX_POWER_ON_DOWN_MIN_Nm;
    const bool power_off = turbine_torque_Nm <= power_on_min_Nm;
    if (up) { return power_off ? WC_SHIFT_TYPE_POWER_OFF_UP : WC_SHIFT_TYPE_POWER_ON_UP; }
    return power_off ? WC_SHIFT_TYPE_POWER_OFF_DOWN : WC_SHIFT_TYPE_POWER_ON_DOWN;
}

wc_shift_cal_error_t wc_gearbox_shift_calibration(const wc_shift_calibration_t *base, const wc_gearbox_shift_t *shift,
                                                  wc_shift_calibration_t *out)
{
    WC_ASSERT((base != NULL) && (shift != NULL) && (out != NULL));
    if ((base == NULL) || (shift == NULL) || (out == NULL)) { return WC_SHIFT_CAL_NULL; }
    *out = *base;
    /* DESIGN 15: the paper's reduction (§2, Fig. 1) of this shift, normalised by the on-coming element's a */
    out->turbine_ratio = 1.0f;
    out->output_ratio = shift->output_ratio;
    out->offgoing_ratio = shift->offgoing_ratio;
    out->turbine_inertia_kg_m2 = shift->turbine_inertia_kg_m2;
    out->output_inertia_kg_m2 = shift->output_inertia_kg_m2;
    out->jerk_per_torque_rate = shift->jerk_per_torque_rate;
    return wc_shift_calibration_check(out);
}

/* wc_gearbox_error_t's names, in its order. */
static const char *const error_names[] = {
    "OK", "NULL", "COUNTS", "GEAR_RATIO", "GEAR_ELEMENTS", "HOLDING_TORQUE", "SHIFT_GEARS", "SHIFT_ELEMENTS",
    "SHIFT_SLIPS", "SHIFT_MODEL",
};
WC_STATIC_ASSERT(sizeof error_names / sizeof error_names[0] == (size_t)WC_GEARBOX_ERRORS, error_name_per_code);

const char *wc_gearbox_error_name(uint32_t error)
{
    return (error < (uint32_t)WC_GEARBOX_ERRORS) ? error_names[error] : "unknown";
}
