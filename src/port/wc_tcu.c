/* wc_tcu: the TCU program. Runs the portable frame loop (wc_loop) of one
 * clutch on a SocketCAN interface.
 *   --clock timer  steps at absolute deadlines a fixed period apart (a periodic
 *                  timerfd on CLOCK_MONOTONIC polled with the socket), counts misses
 *   --clock frame  one step per received ClutchSensors frame, so that replaying
 *                  one log twice gives byte-identical output frames
 * On exit (SIGINT, SIGTERM, --steps reached, or --idle-exit seconds without a
 * frame after the first one) it
 * prints frames in/out, rejects by reason, timeouts, deadline misses and the
 * step-time max and percentiles, and optionally writes them as JSON.
 *   --uds          the diagnostic server (ISO-TP + UDS + fault memory,
 *                  wc_tcu_diag.h), stepped after the step's control frames;
 *                  an ECUReset restarts the loop at the end of its step */
#define _GNU_SOURCE
#include <errno.h>
#include <getopt.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/timerfd.h>
#include <unistd.h>
#include <stdbool.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "wetclutch/wc_config.h"
#include "wetclutch_can/wc_loop.h"
#include "wetclutch_can/wc_gearbox_image.h"
#include "wetclutch_can/wc_xcp.h"
#include "wc_socketcan.h"
#include "wc_adapt_file.h"
#include "wc_cal_image_file.h"
#include "wc_loop_stats.h"
#include "wc_tcu_calibrations.h"
#include "wc_tcu_gearbox.h"
#include "wc_xcp_signals.h"
#include "wc_tcu_diag.h"

/* Step-time histogram: 1 us bins up to 50 ms, one overflow bin; the max is kept exactly. */
#define HIST_BIN_NS 1000
#define HIST_BINS 50000

typedef struct {
    uint64_t bins[HIST_BINS + 1];
    uint64_t count;
    int64_t max_ns;
} step_times_t;

typedef struct {
    const char *iface;
    const char *calibration;
    const char *shift;        /* --shift NAME: shift control on (NULL: off) */
    const char *adaptation_file;  /* --adaptation-file FILE: the learned values' image (DESIGN 12) */
    const char *calibration_image;  /* --calibration-image FILE: the whole calibration (wc_cal_image.h) */
    int compiled_in_given;    /* --calibration, --shift, --sensor-timeout or --request-timeout given */
    const char *stats_json;
    int64_t period_ns;
    int frame_clock;
    uint64_t max_steps;       /* 0: unlimited */
    double idle_exit_s;       /* 0: never */
    double theta_start_degC;
    unsigned sensor_timeout, request_timeout;
    int bench;                /* --bench: BenchMeasurement used (and passed by the kernel filter) */
    int realtime;             /* --realtime: SCHED_FIFO + mlockall where permitted */
    int xcp;                  /* --xcp: the XCP on CAN slave (wc_xcp.h) on the same interface */
    int uds;                  /* --uds: the diagnostic server (wc_tcu_diag.h) on the same interface */
    const char *secret_file;  /* --secret-file: the device secret of SecurityAccess */
    const char *dtc_file;     /* --dtc-file: the fault memory's image */
    const char *serial;       /* --serial: DID 0xF18C */
    unsigned security_delay_ms;  /* --security-delay-ms */
    unsigned dtc_aging_cycles;   /* --dtc-aging-cycles */
    unsigned uds_frames_per_step;  /* --uds-frames-per-step */
    wc_tcu_gearbox_options_t gearbox;  /* --gearbox and its options: the transmission (DESIGN 15) */
} options_t;

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static int64_t now_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void record(step_times_t *h, int64_t ns)
{
    const int64_t bin = ns / HIST_BIN_NS;
    h->bins[(bin < HIST_BINS) ? bin : HIST_BINS]++;
    h->count++;
    if (ns > h->max_ns) { h->max_ns = ns; }
}

static double percentile_us(const step_times_t *h, double p)
{
    if (h->count == 0) { return 0.0; }
    const uint64_t rank = (uint64_t)(p / 100.0 * (double)(h->count - 1)) + 1;
    uint64_t seen = 0;
    for (int i = 0; i <= HIST_BINS; ++i) {
        seen += h->bins[i];
        if (seen >= rank) { return (i == HIST_BINS) ? (double)h->max_ns / 1000.0 : (i + 0.5) * HIST_BIN_NS / 1000.0; }
    }
    return (double)h->max_ns / 1000.0;
}

static void usage(FILE *out)
{
    fprintf(out,
            "usage: wc_tcu [options]\n"
            "  -i, --iface NAME          SocketCAN interface (default vcan0)\n"
            "  -c, --clock timer|frame   timer: fixed period, absolute deadlines (default);\n"
            "                            frame: one step per ClutchSensors frame (deterministic replay)\n"
            "  -p, --period-us N         step period for --clock timer (default: the calibration's, 1000)\n"
            "  -k, --calibration NAME    compiled-in calibration (default table1; --help lists them)\n"
            "  -s, --shift NAME          shift control (TorqueRequest Mode 3, ShiftCommand) with this compiled-in\n"
            "                            shift calibration (--help lists them); default off\n"
            "      --calibration-image FILE  the whole calibration (clutch, shift control, loop timeouts and E2E)\n"
            "                            from an image file (`wetclutch cal-image`); a refused image: one line, exit 2;\n"
            "                            not with --calibration, --shift, --sensor-timeout, --request-timeout\n"
            "      --adaptation-file FILE  with --shift: the clutch's learned values (DESIGN 12), read at start\n"
            "                            (missing or invalid: the calibration's values) and written atomically\n"
            "                            whenever a shift changes them\n"
            "  -n, --steps N             stop after N steps (default: run until SIGINT/SIGTERM)\n"
            "  -I, --idle-exit S         stop once no frame has arrived for S seconds (timed from the first frame)\n"
            "  -t, --theta-start DEGC    initial clutch temperature estimate (default 40)\n"
            "      --sensor-timeout N    ClutchSensors timeout in periods (default 10)\n"
            "      --request-timeout N   TorqueRequest timeout in periods (default 10)\n"
            "  -b, --bench               use BenchMeasurement (0x130: load cell, torque sensor) as the\n"
            "                            paper's validation does; off: the frame is filtered out\n"
            "      --realtime            SCHED_FIFO priority 50 and mlockall, where permitted (reported)\n");
    fputs(WC_TCU_GEARBOX_USAGE
          "                        (not with --xcp, --uds, --bench, --adaptation-file: not there yet)\n", out);
    fprintf(out,
            "      --xcp                 XCP on CAN slave (XcpCommand 0x7F0 / XcpResponse 0x7F1): calibration page\n"
            "                            and DAQ for a calibration tool (README: Calibration over XCP)\n"
            "      --uds                 UDS diagnostics over ISO-TP (UdsPhysicalRequest 0x7E1, UdsFunctionalRequest\n"
            "                            0x7DF, UdsResponse 0x7E9): identity, DIDs, DTCs, SecurityAccess, adaptation\n"
            "                            reset routine, ECUReset (soft: the loop restarts in its safe state); after\n"
            "                            the step's control frames, one frame a step by default\n"
            "      --secret-file FILE    with --uds (required) or --xcp: the device secret (16..1024 bytes); the key\n"
            "                            of a seed is HMAC-SHA256(secret, seed), its first 16 bytes (UDS) or 6 bytes\n"
            "                            (XCP GET_SEED/UNLOCK: CAL/PAG locked until then; without it XCP is open)\n"
            "      --dtc-file FILE       with --uds: the fault memory's image, read at start (missing: empty;\n"
            "                            corrupt: empty and DTC 0x062F00) and written atomically on change and at exit\n"
            "      --serial TEXT         with --uds: the ECU serial number (DID 0xF18C; default WC0000000001)\n"
            "      --security-delay-ms N with --uds: the SecurityAccess delay after 3 wrong keys and at start; with\n"
            "                            --xcp --secret-file: the GET_SEED lock-out after 3 wrong keys (default 10000)\n"
            "      --uds-frames-per-step N  with --uds: diagnostic frames sent per step at most (1..8, default 1)\n"
            "      --dtc-aging-cycles N  with --uds: fault-free operation cycles until a confirmed DTC ages out\n"
            "                            (1..255, default 40; a run or a soft reset is one cycle)\n"
            "      --xcp-layout          print the XCP regions and the measured signals' addresses as JSON\n"
            "                            (for `wetclutch a2l`) and exit\n"
            "  -j, --stats-json FILE     also write the exit statistics as JSON\n"
            "  -h, --help\n");
}

static int parse_number(const char *text, const char *option, double lo, double hi, double *value)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(text, &end);
    if (errno != 0 || end == text || *end != '\0' || !(v >= lo && v <= hi)) {
        fprintf(stderr, "wc_tcu: %s: '%s' is not a number in [%g, %g]\n", option, text, lo, hi);
        return -1;
    }
    *value = v;
    return 0;
}

/* --xcp-layout: the slave's regions (bases of its address space, sizes in
 * this build) and each measured signal's place, resolved by the compiler
 * (wc_xcp_signals.c): what `wetclutch a2l` writes the A2L from. */
static void print_xcp_layout(void)
{
    static wc_xcp_t xcp;  /* only its configuration is read */
    xcp.config = (wc_xcp_config_t)WC_XCP_CONFIG_DEFAULT;
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&xcp, regions);
    static const char *const region_names[WC_XCP_REGIONS] = {"cal", "loop", "xcp", "id", "gearbox", "element0",
                                                              "element1", "element2", "element3", "element4",
                                                              "element5"};
    printf("{\n  \"program\": \"wc_tcu\",\n  \"regions\": {");
    for (uint32_t r = 0u; r < WC_XCP_REGIONS; ++r) {
        printf("%s\"%s\": {\"base\": %u, \"size\": %u}", r ? ", " : "", region_names[r], regions[r].base,
               regions[r].size);
    }
    printf("},\n  \"signals\": [");
    for (size_t i = 0; i < wc_xcp_signal_count; ++i) {
        const wc_xcp_signal_t *g = &wc_xcp_signals[i];
        printf("%s\n    {\"name\": \"%s\", \"region\": \"%s\", \"offset\": %u, \"size\": %u}", i ? "," : "", g->name,
               (g->region == WC_XCP_SIGNAL_LOOP) ? "loop" : "xcp", g->offset, g->size);
    }
    printf("\n  ]\n}\n");
}

static int parse_options(int argc, char **argv, options_t *o)
{
    static const struct option longopts[] = {
        {"iface", required_argument, NULL, 'i'},       {"clock", required_argument, NULL, 'c'},
        {"period-us", required_argument, NULL, 'p'},   {"calibration", required_argument, NULL, 'k'},
        {"steps", required_argument, NULL, 'n'},       {"idle-exit", required_argument, NULL, 'I'},
        {"theta-start", required_argument, NULL, 't'}, {"stats-json", required_argument, NULL, 'j'},
        {"sensor-timeout", required_argument, NULL, 1}, {"request-timeout", required_argument, NULL, 2},
        {"bench", no_argument, NULL, 'b'},            {"realtime", no_argument, NULL, 3},
        {"shift", required_argument, NULL, 's'},       {"adaptation-file", required_argument, NULL, 4},
        {"calibration-image", required_argument, NULL, 5}, {"xcp", no_argument, NULL, 6},
        {"xcp-layout", no_argument, NULL, 7},
        {"uds", no_argument, NULL, 8},                 {"secret-file", required_argument, NULL, 9},
        {"dtc-file", required_argument, NULL, 10},     {"serial", required_argument, NULL, 11},
        {"security-delay-ms", required_argument, NULL, 12}, {"uds-frames-per-step", required_argument, NULL, 13},
        {"dtc-aging-cycles", required_argument, NULL, 14},
        {"gearbox", required_argument, NULL, 15},      {"element-image", required_argument, NULL, 15},
        {"start-gear", required_argument, NULL, 15},   {"holding-margin", required_argument, NULL, 15},
        {"holding-floor", required_argument, NULL, 15},  {"gearbox-image", required_argument, NULL, 15},
        {"help", no_argument, NULL, 'h'},              {NULL, 0, NULL, 0}};
    *o = (options_t){.iface = "vcan0", .calibration = "table1", .period_ns = 0, .theta_start_degC = 40.0,
                     .sensor_timeout = 10u, .request_timeout = 10u, .security_delay_ms = 10000u, .dtc_aging_cycles = 40u,
                     .uds_frames_per_step = 1u, .gearbox = WC_TCU_GEARBOX_OPTIONS_DEFAULT};
    double v = 0.0;
    int c;
    int index = 0;
    while ((c = getopt_long(argc, argv, "i:c:p:k:s:n:I:t:j:bh", longopts, &index)) != -1) {
        switch (c) {
        case 15: {  /* the transmission's options, parsed as wc_replay parses them */
            char name[32];
            (void)snprintf(name, sizeof name, "--%s", longopts[index].name);
            char *pair[2] = { name, optarg };
            int at = 0;
            if (wc_tcu_gearbox_option("wc_tcu", 2, pair, &at, &o->gearbox) != 1) { return -1; }
            break;
        }
        case 'i': o->iface = optarg; break;
        case 'c':
            if (strcmp(optarg, "timer") == 0) { o->frame_clock = 0; }
            else if (strcmp(optarg, "frame") == 0) { o->frame_clock = 1; }
            else { fprintf(stderr, "wc_tcu: --clock: '%s': use timer or frame\n", optarg); return -1; }
            break;
        case 'p': if (parse_number(optarg, "--period-us", 50, 1e6, &v)) { return -1; } o->period_ns = (int64_t)(v * 1000.0); break;
        case 'k': o->calibration = optarg; o->compiled_in_given = 1; break;
        case 's': o->shift = optarg; o->compiled_in_given = 1; break;
        case 4: o->adaptation_file = optarg; break;
        case 5: o->calibration_image = optarg; break;
        case 'n': if (parse_number(optarg, "--steps", 1, 1e12, &v)) { return -1; } o->max_steps = (uint64_t)v; break;
        case 'I': if (parse_number(optarg, "--idle-exit", 0.001, 1e6, &v)) { return -1; } o->idle_exit_s = v; break;
        case 't': if (parse_number(optarg, "--theta-start", -40, 250, &v)) { return -1; } o->theta_start_degC = v; break;
        case 'j': o->stats_json = optarg; break;
        case 'b': o->bench = 1; break;
        case 3: o->realtime = 1; break;
        case 6: o->xcp = 1; break;
        case 7: print_xcp_layout(); exit(0);
        case 8: o->uds = 1; break;
        case 9: o->secret_file = optarg; break;
        case 10: o->dtc_file = optarg; break;
        case 11: o->serial = optarg; break;
        case 12: if (parse_number(optarg, "--security-delay-ms", 0, 3600000, &v)) { return -1; } o->security_delay_ms = (unsigned)v; break;
        case 14: if (parse_number(optarg, "--dtc-aging-cycles", 1, 255, &v)) { return -1; } o->dtc_aging_cycles = (unsigned)v; break;
        case 13: if (parse_number(optarg, "--uds-frames-per-step", 1, WC_ISOTP_MAX_FRAMES_PER_STEP, &v)) { return -1; } o->uds_frames_per_step = (unsigned)v; break;
        case 1: if (parse_number(optarg, "--sensor-timeout", 1, 1e6, &v)) { return -1; } o->sensor_timeout = (unsigned)v; o->compiled_in_given = 1; break;
        case 2: if (parse_number(optarg, "--request-timeout", 1, 1e6, &v)) { return -1; } o->request_timeout = (unsigned)v; o->compiled_in_given = 1; break;
        case 'h':
            usage(stdout);
            printf("calibrations:");
            for (size_t i = 0; i < wc_tcu_calibration_count; ++i) { printf(" %s", wc_tcu_calibrations[i].name); }
            printf("\nshift calibrations:");
            for (size_t i = 0; i < wc_tcu_shift_calibration_count; ++i) { printf(" %s", wc_tcu_shift_calibrations[i].name); }
            printf("\n");
            exit(0);
        default: usage(stderr); return -1;
        }
    }
    if (optind < argc) { fprintf(stderr, "wc_tcu: unexpected argument '%s'\n", argv[optind]); return -1; }
    if (!o->uds && ((o->dtc_file != NULL) || (o->serial != NULL))) {
        fprintf(stderr, "wc_tcu: --dtc-file and --serial need --uds\n");
        return -1;
    }
    if (!o->uds && !o->xcp && (o->secret_file != NULL)) {
        fprintf(stderr, "wc_tcu: --secret-file needs --uds or --xcp\n");
        return -1;
    }
    if (o->uds && (o->secret_file == NULL)) {
        fprintf(stderr, "wc_tcu: --uds needs --secret-file FILE (the device secret of SecurityAccess)\n");
        return -1;
    }
    if ((o->gearbox.gearbox != NULL) && (o->xcp || o->uds || o->bench || (o->adaptation_file != NULL))) {
        fprintf(stderr, "wc_tcu: --gearbox: not with --xcp, --uds, --bench or --adaptation-file (not there yet)\n");
        return -1;
    }
    if ((o->calibration_image != NULL) && o->compiled_in_given) {
        fprintf(stderr, "wc_tcu: --calibration-image holds the whole calibration: not with --calibration, --shift,"
                        " --sensor-timeout or --request-timeout\n");
        return -1;
    }
    return 0;
}

static void report(FILE *out, int json, const wc_loop_counters_t *k, uint64_t tx_errors, uint32_t rx_dropped,
                   const step_times_t *h)
{
    static const double pct[] = {50.0, 90.0, 99.0, 99.9};
    if (json) {
        fprintf(out, "{\n");
        wc_loop_stats_json_members(out, k, tx_errors, rx_dropped);
        fprintf(out, "  \"step_time_us\": {\"max\": %.3f, \"p50\": %.3f, \"p90\": %.3f, \"p99\": %.3f, \"p99.9\": %.3f}\n}\n",
                (double)h->max_ns / 1000.0, percentile_us(h, 50), percentile_us(h, 90), percentile_us(h, 99),
                percentile_us(h, 99.9));
        return;
    }
    fprintf(out, "wc_tcu: frames in %u (used %u), out %u, send errors %llu, dropped by the kernel %u\n",
            k->frames_in, k->frames_used, k->frames_out, (unsigned long long)tx_errors, rx_dropped);
    fprintf(out, "wc_tcu: rejected:");
    for (int r = 0; r < WC_REJECT_REASONS; ++r) { fprintf(out, " %s %u", wc_loop_reject_names[r], k->rejected[r]); }
    fprintf(out, "\nwc_tcu: timeouts: sensors %u, request %u; steps %u (safe state %u); deadline misses %u;"
                 " bus errors and failed sends %u\n",
            k->sensor_timeouts, k->request_timeouts, k->steps, k->safe_steps, k->deadline_misses, k->bus_errors);
    fprintf(out, "wc_tcu: step time (loop step + send) max %.1f us", (double)h->max_ns / 1000.0);
    for (size_t i = 0; i < sizeof pct / sizeof pct[0]; ++i) { fprintf(out, ", p%g %.1f us", pct[i], percentile_us(h, pct[i])); }
    fprintf(out, "\n");
}

/* --realtime: SCHED_FIFO and locked memory where the system permits it; the
 * outcome is reported, a refusal is not an error. */
static void realtime(void)
{
    struct sched_param param;
    memset(&param, 0, sizeof param);
    param.sched_priority = 50;
    const int fifo = sched_setscheduler(0, SCHED_FIFO, &param);
    const int fifo_errno = errno;
    const int locked = mlockall(MCL_CURRENT | MCL_FUTURE);
    const int lock_errno = errno;
    fprintf(stderr, "wc_tcu: realtime: SCHED_FIFO priority 50 %s%s, mlockall %s%s\n", (fifo == 0) ? "on" : "refused: ",
            (fifo == 0) ? "" : strerror(fifo_errno), (locked == 0) ? "on" : "refused: ",
            (locked == 0) ? "" : strerror(lock_errno));
}

static const wc_calibration_t *find_calibration(const char *name)
{
    for (size_t i = 0; i < wc_tcu_calibration_count; ++i) {
        if (strcmp(name, wc_tcu_calibrations[i].name) == 0) { return wc_tcu_calibrations[i].calibration; }
    }
    fprintf(stderr, "wc_tcu: --calibration: '%s' is not compiled in (wc_tcu --help lists them); generate its"
                    " headers with `wetclutch lut` and add it to src/port/wc_tcu_calibrations.c\n", name);
    return NULL;
}

/* --xcp: the slave over the loop, its reference page the loop's calibration
 * encoded as an image payload (the same bytes an image file holds); with a
 * secret file, CAL/PAG behind seed & key, else open (said on stderr). */
static int start_xcp(wc_xcp_t *xcp, wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config,
                     const char *secret_file, uint32_t lockout_steps)
{
    static wc_cal_set_t set;
    static uint8_t reference[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
    static wc_device_secret_t secret;   /* XCP seed & key: the device secret of UDS SecurityAccess */
    wc_xcp_config_t xcp_config = WC_XCP_CONFIG_DEFAULT;
    if (secret_file != NULL) {
        if (wc_device_secret_read(&secret, secret_file, "wc_tcu") != 0) { return -1; }
        xcp_config.seed_bytes = WC_XCP_SEED_MAX_BYTES;
        xcp_config.key_bytes = WC_XCP_KEY_MAX_BYTES;
        xcp_config.random = wc_device_secret_random;   /* the key: HMAC-SHA256(secret, seed), its first bytes */
        xcp_config.key = wc_device_secret_key;
        xcp_config.context = &secret;
        xcp_config.unlock_delay_steps = lockout_steps;  /* 3 wrong keys in a row (the default), then the lock-out */
    } else {
        fprintf(stderr, "wc_tcu: warning: --xcp without --secret-file: calibration writes are not protected"
                        " (no XCP seed & key)\n");
    }
    if (!wc_cal_set_from(&set, cal, config->shift, config)) {
        fprintf(stderr, "wc_tcu: --xcp: the calibration does not fit a calibration page\n");
        return -1;
    }
    wc_cal_image_encode(&set, reference);
    if (!wc_xcp_init(xcp, loop, reference, &xcp_config)) {
        fprintf(stderr, "wc_tcu: --xcp: the calibration page does not decode (a bug: the loop accepted it)\n");
        return -1;
    }
    if (config->transmission != NULL) {  /* the gearbox region: the table the transmission runs, as its image's payload */
        static uint8_t gearbox_image[WC_IMAGE_BYTES(WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES)];
        if (wc_gearbox_image_write(config->transmission->gearbox, gearbox_image, sizeof gearbox_image) == 0u) {
            fprintf(stderr, "wc_tcu: --xcp: the gearbox does not fit its image (a bug: the layout grew)\n");
            return -1;
        }
        wc_xcp_set_gearbox(xcp, &gearbox_image[WC_IMAGE_HEADER_BYTES]);
        /* each element's region: its clutch as a calibration payload (shift control off) */
        static wc_cal_set_t element_set;
        static uint8_t element_payload[WC_GEARBOX_ELEMENTS_MAX][WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
        for (uint32_t e = 0u; e < config->transmission->gearbox->element_count; ++e) {
            if (!wc_cal_set_from(&element_set, config->transmission->element[e], NULL, NULL)) {
                fprintf(stderr, "wc_tcu: --xcp: element %u's calibration does not fit a calibration page\n",
                        (unsigned)e);
                return -1;
            }
            wc_cal_image_encode(&element_set, element_payload[e]);
            wc_xcp_set_element(xcp, e, element_payload[e]);
        }
    }
    return 0;
}

/* Everything the main loop counts besides the loop's own counters. */
typedef struct {
    uint64_t tx_errors;
    uint32_t rx_dropped_seen;  /* port->rx_dropped already reported to the loop */
    uint32_t downs;            /* times the interface went down */
    int64_t next_reopen_ns;    /* while down: when to try again */
} port_stats_t;

/* The main loop until a signal, --steps or --idle-exit: wait for a frame or
 * the deadline, one wc_loop_iterate, send what it produced. The port's
 * kernel drops and failed sends are reported to the loop as they happen
 * (StatusFrameLost / StatusBusError in the next VfsCommand). Returns the
 * exit status. */
/* The timer clock: a periodic timerfd on CLOCK_MONOTONIC armed at an absolute
 * first deadline, so every deadline is start + k periods, kept by the kernel
 * (no drift, no wait computed from a "now" that is already late); reading it
 * gives the expirations since the last read: more than one is a miss. */
static int timer_open(int64_t period_ns)
{
    const int fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (fd < 0) { return -1; }
    struct timespec start;
    (void)clock_gettime(CLOCK_MONOTONIC, &start);
    const int64_t first_ns = (int64_t)start.tv_sec * 1000000000LL + start.tv_nsec + period_ns;
    struct itimerspec spec;
    spec.it_value.tv_sec = (time_t)(first_ns / 1000000000LL);
    spec.it_value.tv_nsec = (long)(first_ns % 1000000000LL);
    spec.it_interval.tv_sec = (time_t)(period_ns / 1000000000LL);
    spec.it_interval.tv_nsec = (long)(period_ns % 1000000000LL);
    if (timerfd_settime(fd, TFD_TIMER_ABSTIME, &spec, NULL) != 0) {
        (void)close(fd);
        return -1;
    }
    return fd;
}

/* Sends frames in order; a failure is counted and reported to the loop. */
static void send_frames(wc_loop_t *loop, wc_socketcan_t *port, port_stats_t *ps, const wc_can_frame_t *frames,
                        uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) {
        if (wc_socketcan_send(port, &frames[i]) != 0) {
            if (ps->tx_errors == 0) {
                fprintf(stderr, "wc_tcu: %s (counted; further send errors not printed)\n", port->error);
            }
            ps->tx_errors++;
            wc_loop_port_event(loop, WC_LOOP_PORT_TX_FAILED, 1u);
        }
    }
}

/* ECUReset softReset (UDS 0x11 0x03, wc_tcu_diag.h), at the end of the step that sends its response: the learned
 * values and the fault memory persisted, a new operation cycle and restarted servers (wc_tcu_diag_reset),
 * then the loop re-initialised on the calibration it runs (an XCP page's included: DESIGN 13) and started at
 * --theta-start as at power-on: the safe state until its inputs have been fresh for recovery_periods
 * (DESIGN 8). The learned values come back from their image (without --adaptation-file: as they were); the
 * loop's counters are the program's statistics and carry over. */
static void soft_reset(const options_t *opt, wc_loop_t *loop, wc_tcu_diag_t *diag, wc_adapt_file_t *adaptation_file)
{
    if (loop->config.adaptation_changed != NULL) {  /* written on every change; once more, as an ECU flushes */
        loop->config.adaptation_changed(&loop->adapt, loop->config.adaptation_context);
    }
    wc_tcu_diag_reset(diag);
    const wc_calibration_t *cal = loop->clutch.model.cal;
    const wc_loop_config_t config = loop->config;
    const wc_adapt_t learned = loop->adapt;
    const wc_loop_counters_t counters = loop->counters;
    if (wc_loop_init(loop, cal, &config, (float)opt->theta_start_degC) != WC_CAL_OK) {
        fprintf(stderr, "wc_tcu: soft reset: the loop's own calibration refused (a bug)\n");  /* it ran on it */
    }
    if (adaptation_file != NULL) {
        (void)wc_adapt_file_attach(adaptation_file, loop);
    } else {
        loop->adapt = learned;
    }
    loop->counters = counters;
    loop->overflows_seen = counters.rejected[WC_REJECT_OVERFLOW];  /* not a new loss (wc_loop.c prepare) */
}

static int run(const options_t *opt, wc_loop_t *loop, wc_xcp_t *xcp, wc_tcu_diag_t *diag,
               wc_adapt_file_t *adaptation_file, wc_socketcan_t *port, step_times_t *times, port_stats_t *ps)
{
    int64_t last_rx = -1;  /* the idle timer starts with the first frame */
    const wc_loop_clock_t clock = opt->frame_clock ? WC_LOOP_CLOCK_FRAME : WC_LOOP_CLOCK_TIMER;
    const int timer_fd = opt->frame_clock ? -1 : timer_open(opt->period_ns);
    if (!opt->frame_clock && (timer_fd < 0)) {
        fprintf(stderr, "wc_tcu: timerfd: %s\n", strerror(errno));
        return 1;
    }
    while (!stop_requested && (opt->max_steps == 0 || loop->counters.steps < opt->max_steps)) {
        wc_can_frame_t frame;
        /* frame clock: wake every 100 ms for the idle and reopen checks; timer clock: the timerfd wakes */
        int got = wc_socketcan_receive(port, &frame, 100000LL, timer_fd);
        if (got == WC_SOCKETCAN_FAILED) {
            fprintf(stderr, "wc_tcu: %s\n", port->error);
            return 1;
        }
        if (got == WC_SOCKETCAN_BUS_ERROR) {  /* error passive, bus-off, controller problem: flagged */
            wc_loop_port_event(loop, WC_LOOP_PORT_BUS_ERROR, 1u);
            got = WC_SOCKETCAN_NONE;
        }
        if ((got == WC_SOCKETCAN_DOWN) || ((port->fd < 0) && (now_ns() >= ps->next_reopen_ns))) {
            /* The interface went down: never exit. The inputs time out (safe
             * state), sends fail (counted); reopen every 100 ms until it is back. */
            if (got == WC_SOCKETCAN_DOWN) {
                fprintf(stderr, "wc_tcu: %s\n", port->error);
                ps->downs++;
                wc_loop_port_event(loop, WC_LOOP_PORT_BUS_ERROR, 1u);
                wc_socketcan_close(port);
            } else if (wc_socketcan_reopen(port) == 0) {
                fprintf(stderr, "wc_tcu: %s reopened\n", opt->iface);
            }
            ps->next_reopen_ns = now_ns() + 100000000LL;
            got = WC_SOCKETCAN_NONE;
        }
        if (port->rx_dropped != ps->rx_dropped_seen) {
            wc_loop_port_event(loop, WC_LOOP_PORT_RX_DROPPED, port->rx_dropped - ps->rx_dropped_seen);
            ps->rx_dropped_seen = port->rx_dropped;
        }
        const int64_t t = now_ns();
        if (got == WC_SOCKETCAN_FRAME) {
            last_rx = t;
        } else if (opt->idle_exit_s > 0 && last_rx >= 0 && (double)(t - last_rx) > opt->idle_exit_s * 1e9) {
            return 0;
        }
        bool tick = false;
        if (got == WC_SOCKETCAN_WAKE) {
            uint64_t expirations = 0u;
            if ((read(timer_fd, &expirations, sizeof expirations) == (ssize_t)sizeof expirations) &&
                (expirations > 0u)) {
                tick = true;  /* one step per wake; the deadlines it slept through are misses */
                if (expirations > 1u) { wc_loop_deadline_missed(loop, (uint32_t)(expirations - 1u)); }
            }
            got = WC_SOCKETCAN_NONE;
        }
        /* an XCP command goes to the slave, every other frame to the loop */
        const bool xcp_frame = (xcp != NULL) && (got == WC_SOCKETCAN_FRAME) && (frame.id == WC_CAN_XCP_COMMAND_FRAME_ID);
        if (xcp_frame) { (void)wc_xcp_receive(xcp, &frame); }  /* a full ring is counted */
        /* a UDS request goes to the diagnostic server (the loop would count it an unknown id) */
        const bool uds_frame = (diag != NULL) && (got == WC_SOCKETCAN_FRAME) && wc_tcu_diag_is_request(frame.id);
        if (uds_frame) { wc_tcu_diag_receive(diag, &frame); }
        const int64_t t0 = now_ns();
        wc_can_frame_t out[WC_LOOP_TX_FRAMES];
        const uint32_t n = wc_loop_iterate(loop, clock, ((got == WC_SOCKETCAN_FRAME) && !xcp_frame && !uds_frame) ? &frame : NULL,
                                           tick, out);
        send_frames(loop, port, ps, out, n);  /* VfsCommand first, before any XCP frame */
        if (n > 0u) { record(times, now_ns() - t0); }
        if (xcp != NULL) {  /* after the step's frames: commands, a changed page, the step's DAQ sample */
            wc_can_frame_t xout[WC_XCP_TX_FRAMES];
            send_frames(loop, port, ps, xout, wc_xcp_step(xcp, n > 0u, xout));
        }
        if ((diag != NULL) && (n > 0u)) {  /* after the step's frames: the fault tests, then one server step */
            wc_can_frame_t dout[WC_TCU_DIAG_TX_FRAMES];
            send_frames(loop, port, ps, dout, wc_tcu_diag_step(diag, out, n, dout, WC_TCU_DIAG_TX_FRAMES));
            if (wc_tcu_diag_reset_pending(diag)) { soft_reset(opt, loop, diag, adaptation_file); }
        }
    }
    if (timer_fd >= 0) { (void)close(timer_fd); }
    return 0;
}

static int write_stats_json(const char *path, const wc_loop_counters_t *counters, const port_stats_t *ps,
                            uint32_t rx_dropped, const step_times_t *times)
{
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        fprintf(stderr, "wc_tcu: cannot write %s: %s\n", path, strerror(errno));
        return 1;
    }
    report(f, 1, counters, ps->tx_errors, rx_dropped, times);
    if (fclose(f) != 0) {
        fprintf(stderr, "wc_tcu: cannot write %s: %s\n", path, strerror(errno));
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    options_t opt;
    if (parse_options(argc, argv, &opt) != 0) { return 2; }
    static wc_loop_t loop;  /* large (receive ring): static storage, not the stack */
    static step_times_t times;
    static wc_cal_set_t image;  /* --calibration-image: the loop keeps pointers into it */
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    const wc_calibration_t *cal = NULL;
    if (opt.calibration_image != NULL) {  /* the whole calibration from the image, or not started */
        if (wc_cal_image_file_load(opt.calibration_image, "wc_tcu", "--calibration-image", &image) != 0) { return 2; }
        cal = &image.clutch;
        config = image.loop;
        opt.calibration = opt.calibration_image;
        opt.shift = image.shift_enabled ? "(image)" : NULL;
    } else {
        cal = find_calibration(opt.calibration);
        if (cal == NULL) { return 2; }
        config.sensor_timeout_periods = opt.sensor_timeout;
        config.request_timeout_periods = opt.request_timeout;
        if (opt.shift != NULL) {
            config.shift = wc_tcu_find_shift_calibration(opt.shift);
            if (config.shift == NULL) {
                fprintf(stderr, "wc_tcu: --shift: '%s' is not compiled in (wc_tcu --help lists them)\n", opt.shift);
                return 2;
            }
        }
    }
    config.bench_input_enabled = opt.bench != 0;
    static wc_transmission_config_t transmission;  /* --gearbox: the loop keeps pointers into these */
    static wc_cal_set_t element_images[WC_GEARBOX_ELEMENTS_MAX];
    if (wc_tcu_gearbox_config("wc_tcu", &opt.gearbox, cal, (float)opt.theta_start_degC, &config, &transmission,
                              element_images) != 0) {
        return 2;
    }
    if ((config.shift != NULL) && (config.shift->coordinator == 1u) && (config.offgoing == NULL)) {
        config.offgoing = cal;  /* DESIGN 14: the off-going clutch has the same lining (its own instance) */
    }
    const wc_cal_error_t cal_error = wc_loop_init(&loop, cal, &config, (float)opt.theta_start_degC);
    if (cal_error != WC_CAL_OK) {
        fprintf(stderr, "wc_tcu: calibration %s invalid: field %s\n", opt.calibration, wc_cal_error_name(cal_error));
        return 2;
    }
    static wc_adapt_file_t adaptation_file;  /* the loop's hook keeps a pointer to it */
    if (opt.adaptation_file != NULL) {
        if (opt.shift == NULL) {
            fprintf(stderr, "wc_tcu: --adaptation-file needs --shift (the adaptation learns from shifts)\n");
            return 2;
        }
        adaptation_file.path = opt.adaptation_file;
        adaptation_file.program = "wc_tcu";
        (void)wc_adapt_file_attach(&adaptation_file, &loop);
    }
    /* The model is discretised for the calibration's period (eq. 1 and the VFS
     * lag, exact for that dt): another step period would be a wrong model. */
    const int64_t cal_period_ns = (int64_t)((double)cal->control_period_s * 1e9 + 0.5);
    if (opt.period_ns == 0) { opt.period_ns = cal_period_ns; }
    if (llabs(opt.period_ns - cal_period_ns) > 1000) {
        fprintf(stderr, "wc_tcu: --period-us %lld does not match the calibration's control period of %lld us"
                        " (the model is discretised for it)\n", (long long)(opt.period_ns / 1000),
                (long long)(cal_period_ns / 1000));
        return 2;
    }
    if (opt.realtime) { realtime(); }

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    if (sigaction(SIGINT, &sa, NULL) != 0 || sigaction(SIGTERM, &sa, NULL) != 0) {
        perror("wc_tcu: sigaction");
        return 1;
    }

    /* The XCP slave: its reference page is the calibration the loop started with, as an image payload. */
    static wc_xcp_t xcp;
    const uint64_t delay_us = (uint64_t)opt.security_delay_ms * 1000u;  /* the lock-out in whole steps, at least 1 */
    const uint64_t period_us = (uint64_t)(opt.period_ns / 1000);
    const uint32_t lockout_steps = (delay_us <= period_us) ? 1u : (uint32_t)((delay_us + period_us - 1u) / period_us);
    if (opt.xcp && (start_xcp(&xcp, &loop, cal, &config, opt.secret_file, lockout_steps) != 0)) { return 2; }

    /* The diagnostic server: the calibration image the loop runs (its CRC is a DID), the fault memory. */
    static wc_tcu_diag_t diag;
    if (opt.uds) {
        static wc_cal_set_t set;
        static uint8_t cal_image[WC_CAL_IMAGE_FILE_MAX_BYTES];
        size_t cal_image_length = 0u;
        if (wc_cal_set_from(&set, cal, config.shift, &config)) {
            cal_image_length = wc_cal_image_write(&set, cal_image, sizeof cal_image);
        }
        const wc_tcu_diag_options_t diag_options = {
            "wc_tcu", opt.secret_file, opt.dtc_file, opt.serial, (uint32_t)(opt.period_ns / 1000),
            opt.security_delay_ms, opt.uds_frames_per_step, opt.dtc_aging_cycles };
        if (wc_tcu_diag_open(&diag, &diag_options, &loop, opt.xcp ? &xcp : NULL, cal_image, cal_image_length) != 0) {
            return 2;
        }
    }

    wc_socketcan_t port;
    uint32_t ids[WC_LOOP_RX_ID_COUNT + 3u];
    uint32_t id_count = wc_loop_rx_ids(&config, ids);  /* ShiftCommand only with --shift, bench only with --bench */
    if (opt.xcp) { ids[id_count++] = WC_CAN_XCP_COMMAND_FRAME_ID; }
    if (opt.uds) {
        ids[id_count++] = WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID;
        ids[id_count++] = WC_CAN_UDS_FUNCTIONAL_REQUEST_FRAME_ID;
    }
    if (wc_socketcan_open(&port, opt.iface, ids, id_count) != 0) {
        fprintf(stderr, "wc_tcu: %s\n", port.error);
        return 1;
    }
    fprintf(stderr, "wc_tcu: %s, clock %s, period %lld us, calibration %s%s%s%s\n", opt.iface,
            opt.frame_clock ? "frame" : "timer", (long long)(opt.period_ns / 1000), opt.calibration,
            (opt.shift != NULL) ? ", shift " : "", (opt.shift != NULL) ? opt.shift : "",
            opt.bench ? ", bench input ON (BenchMeasurement replaces the modelled force and heat input)" : "");

    port_stats_t ps = { 0u, 0u, 0u, 0 };
    const int status = run(&opt, &loop, (opt.xcp != 0) ? &xcp : NULL, opt.uds ? &diag : NULL,
                           (opt.adaptation_file != NULL) ? &adaptation_file : NULL, &port, &times, &ps);
    wc_socketcan_close(&port);
    if (opt.uds) { wc_tcu_diag_close(&diag); }
    report(stderr, 0, &loop.counters, ps.tx_errors, port.rx_dropped, &times);
    if ((opt.stats_json != NULL) && (write_stats_json(opt.stats_json, &loop.counters, &ps, port.rx_dropped, &times) != 0)) {
        return 1;
    }
    return status;
}
