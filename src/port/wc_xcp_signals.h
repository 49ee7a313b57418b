/* The measured signals' places in this program (generated from
 * tools/wetclutch/calibration/measurements.py into wc_xcp_signals.c): what
 * wc_tcu --xcp-layout prints for the A2L (`wetclutch a2l`). Host only: on a
 * target the A2L generator reads the same offsets from the target's build. */
#ifndef WC_XCP_SIGNALS_H
#define WC_XCP_SIGNALS_H

#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_xcp.h"

typedef enum {
    WC_XCP_SIGNAL_LOOP = 1,   /* offset inside wc_loop_t: the XCP region 1 */
    WC_XCP_SIGNAL_XCP = 2     /* offset inside wc_xcp_status_t: the XCP region 2 */
} wc_xcp_signal_region_t;

typedef struct {
    const char *name;
    wc_xcp_signal_region_t region;
    uint32_t offset;
    uint32_t size;
} wc_xcp_signal_t;

extern const wc_xcp_signal_t wc_xcp_signals[];
extern const size_t wc_xcp_signal_count;

#endif /* WC_XCP_SIGNALS_H */
