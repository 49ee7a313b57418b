/* The frame loop's counters as JSON, one home for wc_tcu --stats-json and
 * wc_replay --stats-json (the HIL report reads either). Host only (stdio). */
#ifndef WC_LOOP_STATS_H
#define WC_LOOP_STATS_H

#include <stdint.h>
#include <stdio.h>

#include "wetclutch_can/wc_loop.h"

/* The name of each wc_loop_reject_t reason, in its order. */
extern const char *const wc_loop_reject_names[WC_REJECT_REASONS];

/* The counters as the members of a JSON object (each line "  \"name\": value,"),
 * the caller writing the braces and what follows the last comma. */
void wc_loop_stats_json_members(FILE *out, const wc_loop_counters_t *k, uint64_t tx_errors, uint32_t rx_dropped);

#endif /* WC_LOOP_STATS_H */
