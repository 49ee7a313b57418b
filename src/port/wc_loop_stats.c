#include "wc_loop_stats.h"

#include "wetclutch/wc_config.h"

/* Indexed by wc_loop_reject_t, in its order: a reason added without a name fails to compile. */
const char *const wc_loop_reject_names[WC_REJECT_REASONS] = {"crc", "counter", "short", "unknown_id", "format",
                                                             "implausible", "overflow", "sync"};
WC_STATIC_ASSERT(sizeof wc_loop_reject_names / sizeof wc_loop_reject_names[0] == WC_REJECT_REASONS,
                 reject_names_cover_every_reason);

void wc_loop_stats_json_members(FILE *out, const wc_loop_counters_t *k, uint64_t tx_errors, uint32_t rx_dropped)
{
    fprintf(out, "  \"frames_in\": %u,\n  \"frames_used\": %u,\n  \"frames_out\": %u,\n  \"tx_errors\": %llu,\n"
                 "  \"rx_dropped_by_kernel\": %u,\n",
            k->frames_in, k->frames_used, k->frames_out, (unsigned long long)tx_errors, rx_dropped);
    fprintf(out, "  \"rejected\": {");
    for (int r = 0; r < WC_REJECT_REASONS; ++r) {
        fprintf(out, "%s\"%s\": %u", r ? ", " : "", wc_loop_reject_names[r], k->rejected[r]);
    }
    fprintf(out, "},\n  \"sensor_timeouts\": %u,\n  \"request_timeouts\": %u,\n  \"safe_steps\": %u,\n"
                 "  \"steps\": %u,\n  \"deadline_misses\": %u,\n  \"bus_errors\": %u,\n",
            k->sensor_timeouts, k->request_timeouts, k->safe_steps, k->steps, k->deadline_misses, k->bus_errors);
}
