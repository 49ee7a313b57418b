/* A clutch-to-clutch gearbox as the TCU sees it (DESIGN 15; issue 29): its
 * gears (ratio, the elements closed), the torque each closed element holds
 * per newton metre of turbine torque, and per single-element shift the
 * paper's reduction (§2, Fig. 1): every element's slip as a linear function
 * of turbine and output speed, the on-coming and off-going element and the
 * reduced driveline model of DESIGN 10 and 14. The tables are generated from
 * a gearbox description by `wetclutch gearbox ... --header` (lut/
 * wc_<name>_gearbox.h); the library only reads them (const, flash).
 *
 * Gear numbers: 1..forward_gears forward, WC_GEARBOX_REVERSE (0) reverse.
 * Element numbers: 0..element_count-1 (bit e of a closed mask). */
#ifndef WC_GEARBOX_H
#define WC_GEARBOX_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_shift.h"

/* Bounds (no heap: the tables are fixed arrays). */
#define WC_GEARBOX_ELEMENTS_MAX 6u   /* shift elements (8HP: 5) */
#define WC_GEARBOX_GEARS_MAX 11u     /* reverse + up to 10 forward */
#define WC_GEARBOX_SHIFTS_MAX 64u    /* single-element shifts in the table (8HP: 36) */
#define WC_GEARBOX_REVERSE 0u

/* An element's slip in a shift's two-degree-of-freedom system (DESIGN 15):
 * slip = a w_t - b w_o, rad/s, the element's own (its plates' relative speed). */
typedef struct {
    float a;   /* rad/s of slip per rad/s of turbine speed */
    float b;   /* rad/s of slip per rad/s of output speed */
} wc_slip_map_t;

/* One single-element shift: one element opens (off-going), one closes
 * (on-coming), the others of the source gear stay closed. The reduced model
 * is normalised by the on-coming element's a (DESIGN 15): the controller's
 * slip w_t - output_ratio w_o is the on-coming element's own slip divided by
 * oncoming_slip_scale, and the element's torque is the controller's request
 * divided by it; likewise for the off-going element with offgoing_ratio. */
typedef struct {
    uint8_t source_gear;
    uint8_t target_gear;
    uint8_t oncoming;                          /* element number */
    uint8_t offgoing;
    wc_slip_map_t slip[WC_GEARBOX_ELEMENTS_MAX];  /* every element (held ones: 0, 0) */
    float output_ratio;                        /* b: the target gear's ratio */
    float offgoing_ratio;                      /* b1: the source gear's ratio */
    float oncoming_slip_scale;                 /* the on-coming element's a */
    float offgoing_slip_scale;                 /* the off-going element's a */
    float turbine_inertia_kg_m2;               /* the diagonal reduction for the on-coming element's slip */
    float output_inertia_kg_m2;
    float jerk_per_torque_rate;                /* (m/s^3) / (Nm/s) of the controller's torque */
} wc_gearbox_shift_t;

typedef struct {
    uint32_t element_count;                    /* 3 .. WC_GEARBOX_ELEMENTS_MAX */
    uint32_t closed_per_gear;                  /* elements closed in every gear (8HP: 3) */
    uint32_t forward_gears;                    /* 1 .. WC_GEARBOX_GEARS_MAX - 1 */
    bool has_reverse;
    float ratio[WC_GEARBOX_GEARS_MAX];         /* w_t / w_o per gear number (reverse < 0) */
    uint32_t closed_mask[WC_GEARBOX_GEARS_MAX];
    /* the torque element e holds in gear g per Nm of turbine torque (signed, statics of the gear sets) */
    float holding_torque_per_Nm[WC_GEARBOX_GEARS_MAX][WC_GEARBOX_ELEMENTS_MAX];
    uint32_t shift_count;
    wc_gearbox_shift_t shift[WC_GEARBOX_SHIFTS_MAX];
} wc_gearbox_t;

/* What wc_gearbox_check finds first (0 = valid). */
typedef enum {
    WC_GEARBOX_OK = 0,
    WC_GEARBOX_NULL,
    WC_GEARBOX_COUNTS,          /* element_count, closed_per_gear, forward_gears or shift_count out of bounds */
    WC_GEARBOX_GEAR_RATIO,      /* a ratio not finite, |ratio| not in [0.1, 20], reverse not negative, forward
                                 * not positive or not strictly decreasing from 1st to top */
    WC_GEARBOX_GEAR_ELEMENTS,   /* a gear not closing exactly closed_per_gear existing elements, or two gears alike */
    WC_GEARBOX_HOLDING_TORQUE,  /* not finite, |.| > 20, or nonzero for an open element */
    WC_GEARBOX_SHIFT_GEARS,     /* a shift's gears invalid, not a single-element change, or listed twice */
    WC_GEARBOX_SHIFT_ELEMENTS,  /* on-coming / off-going not the element that closes / opens */
    WC_GEARBOX_SHIFT_SLIPS,     /* a held element slips, the off-going one not at rest in the source gear or
                                 * the on-coming one not in the target gear, the scales not its a */
    WC_GEARBOX_SHIFT_MODEL,     /* ratios, inertias or the jerk factor out of range */
    WC_GEARBOX_ERRORS           /* number of codes */
} wc_gearbox_error_t;

wc_gearbox_error_t wc_gearbox_check(const wc_gearbox_t *gearbox);

/* The name of a wc_gearbox_error_t ("SHIFT_SLIPS"; "unknown" past the codes), for messages. */
const char *wc_gearbox_error_name(uint32_t error);

/* Why a shift request cannot be made (DESIGN 15; the values of a future DBC
 * signal): computed from the closed masks, not from the table. */
typedef enum {
    WC_GEARBOX_SHIFT_OK = 0,
    WC_GEARBOX_SHIFT_SAME_GEAR = 1,       /* current == target: no shift */
    WC_GEARBOX_SHIFT_NO_SUCH_GEAR = 2,    /* a gear number the box does not have */
    WC_GEARBOX_SHIFT_SWAP = 3,            /* more than one element would open and close: refused (a swap ties up
                                           * or flares; the integrator shifts through an intermediate gear) */
    WC_GEARBOX_SHIFT_DIRECTION = 4,       /* to or from reverse: not a shift under way (the vehicle stands) */
    WC_GEARBOX_SHIFT_NOT_IN_TABLE = 5,    /* a single-element change the table does not carry */
    WC_GEARBOX_SHIFT_NOT_CURRENT = 6,     /* the request's current gear is not the one the elements hold
                                           * (wc_transmission: the integrator and the TCU disagree) */
    WC_GEARBOX_SHIFT_BUSY = 7,            /* a shift runs, or the loop is in its safe state: no new one */
    WC_GEARBOX_SHIFT_NO_MODEL = 8         /* an element's equivalent clutch for this shift is outside the
                                           * calibration's limits (wc_transmission_equivalent: R_o |a| > 1 m,
                                           * or A_f > pi (R_o |a|)^2 for |a| < 1: the 8HP's 1<->7 skips) */
} wc_gearbox_shift_result_t;

/* The shift from current_gear to target_gear: WC_GEARBOX_SHIFT_OK and *shift
 * set to its table row, else the reason and *shift NULL. gearbox checked. */
wc_gearbox_shift_result_t wc_gearbox_find_shift(const wc_gearbox_t *gearbox, uint32_t current_gear,
                                                uint32_t target_gear, const wc_gearbox_shift_t **shift);

/* The four shift types of DESIGN 15, from the direction (an upshift goes
 * to a lower ratio) and the sign of the turbine torque (the engine pulling:
 * power-on; dragging: power-off). */
typedef enum {
    WC_SHIFT_TYPE_POWER_ON_UP = 0,     /* torque phase, then inertia phase (DESIGN 14) */
    WC_SHIFT_TYPE_POWER_OFF_UP = 1,    /* tip-out: inertia phase (the off-going element slips), hand-over at synchronism */
    WC_SHIFT_TYPE_POWER_ON_DOWN = 2,   /* kickdown: inertia phase (a controlled flare), torque phase at synchronism */
    WC_SHIFT_TYPE_POWER_OFF_DOWN = 3   /* coast: torque phase, then the on-coming element pulls the turbine up */
} wc_shift_type_t;

/* A downshift is power-on (a kickdown) only above this turbine torque: its
 * inertia phase is the engine's torque turning the turbine up (inertia-first,
 * wc_shift.h), and at less it cannot: 50 N m over the 8HP's 0.98 kg m^2 is
 * 51 rad/s^2, a 3->2's 98 rad/s in 1.9 s, inside the 3.2 s inertia timeout
 * (the drive cycle's light-throttle 3->2 at 0-5 N m timed out). Below it the
 * coast downshift's engine request raises the turbine at any driver torque
 * (DESIGN 15, beyond the paper). */
#define WC_GEARBOX_POWER_ON_DOWN_MIN_Nm 50.0f

/* The type of a shift of the table at this turbine torque; a torque of 0
 * counts as power-off (the engine at most drags), a downshift's up to
 * WC_GEARBOX_POWER_ON_DOWN_MIN_Nm; NaN: power-on (the type
 * whose torque phase comes first on an upshift and whose inertia phase is
 * held by the off-going element on a downshift: the element that has the
 * gear keeps it until the torque is known). */
wc_shift_type_t wc_gearbox_shift_type(const wc_gearbox_t *gearbox, const wc_gearbox_shift_t *shift,
                                      float turbine_torque_Nm);

/* The shift controller's calibration for one shift of the table (DESIGN
 * 10, 14, 15): base with its driveline model replaced by the row's reduced
 * one (turbine_ratio 1, output_ratio b, offgoing_ratio b1, the two inertias,
 * the jerk factor), the rest (phases, gains, fill, engine, adaptation) kept.
 * The controller's torque is the on-coming element's torque times
 * oncoming_slip_scale; the caller converts. Returns wc_shift_calibration_check
 * of the result. */
wc_shift_cal_error_t wc_gearbox_shift_calibration(const wc_shift_calibration_t *base, const wc_gearbox_shift_t *shift,
                                                  wc_shift_calibration_t *out);

/* An element's own slip in a shift, a w_t - b w_o (rad/s); NaN in, NaN out
 * (the caller's input rules decide what an invalid speed means). */
float wc_gearbox_element_slip_rad_s(const wc_gearbox_shift_t *shift, uint32_t element, float turbine_rad_s,
                                    float output_rad_s);

/* The torque a closed element is asked to hold in a gear (DESIGN 15: what
 * it must carry plus the margin, not the maximum): |holding_torque_per_Nm x
 * T_t| x margin_factor, at least floor_Nm. An open element or an invalid
 * gear: 0. A turbine torque that is not finite: WC_TORQUE_MAX_Nm (the
 * element holds as hard as it can: a closed element that slips is the
 * failure to avoid; its inverse then saturates at the solenoid's maximum). */
float wc_gearbox_holding_request_Nm(const wc_gearbox_t *gearbox, uint32_t gear, uint32_t element,
                                    float turbine_torque_Nm, float margin_factor, float floor_Nm);

#endif /* WC_GEARBOX_H */
