/* Status bits returned by every computing function of the library. Zero is
 * success; several bits may be set at once. Outputs are always finite and
 * physical whatever the status. */
#ifndef WC_STATUS_H
#define WC_STATUS_H

#include <stdint.h>

typedef uint32_t wc_status_t;

#define WC_STATUS_OK               0u
#define WC_STATUS_BELOW_DRAG       (1u << 0)  /* request below the drag at zero force: force 0 */
#define WC_STATUS_SATURATED        (1u << 1)  /* request above the capacity at maximum current */
#define WC_STATUS_CURRENT_CLAMPED  (1u << 2)  /* VFS current clamped to the solenoid range */
#define WC_STATUS_SLIP_INVALID     (1u << 3)  /* slip speed NaN, infinite or out of range */
#define WC_STATUS_THETA_INVALID    (1u << 4)  /* a temperature NaN, infinite or out of range */
#define WC_STATUS_FORCE_INVALID    (1u << 5)  /* contact force NaN, infinite, negative or too large */
#define WC_STATUS_TORQUE_INVALID   (1u << 6)  /* torque request NaN, infinite, negative or too large */
#define WC_STATUS_POWER_INVALID    (1u << 7)  /* heat input NaN, infinite or negative */
#define WC_STATUS_OVER_TEMPERATURE (1u << 8)  /* temperature estimate above WC_THETA_OVER_degC (hysteresis) */
#define WC_STATUS_NOT_INITIALISED  (1u << 9)  /* NULL or uninitialised instance (asserts off): zero outputs */
#define WC_STATUS_LOCKED           (1u << 10) /* clutch locked: static friction holds it (DESIGN 9); not an error */

/* Any of the input-rejection bits. */
#define WC_STATUS_INPUT_INVALID \
    (WC_STATUS_SLIP_INVALID | WC_STATUS_THETA_INVALID | WC_STATUS_FORCE_INVALID | \
     WC_STATUS_TORQUE_INVALID | WC_STATUS_POWER_INVALID)

#endif /* WC_STATUS_H */
