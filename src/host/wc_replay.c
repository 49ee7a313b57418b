/* wc_replay: the TCU's frame loop linked in-process, without SocketCAN.
 *
 *   wc_replay LOG [--bench] [--calibration NAME] [--theta-start DEGC]
 *             [--shift NAME [--set FIELD=VALUE]...] [--lockstep]
 *   wc_replay LOG [--bench] --calibration-image FILE [--theta-start DEGC] [--lockstep]
 *   ... [--offgoing-calibration-image FILE]
 *   wc_replay LOG --gearbox NAME (--shift NAME | --calibration-image FILE) [--element-image FILE]...
 *             [--start-gear N] [--holding-margin F] [--holding-floor NM] [--theta-start DEGC] [--lockstep]
 *
 * --gearbox: the transmission (DESIGN 15, wc_loop_config_t.transmission) on
 * a compiled-in gearbox description (8hp): the loop takes GearboxSensors and
 * ShiftCommand and sends one VFS command per element, GearboxStatus and
 * EngineTorqueRequest. Its shift calibration is --shift's or the image's
 * (coordinator 1 required); each element's clutch is the next
 * --element-image's (one per element, in element order; an image with its
 * clutch alone, shift off), or without them --calibration's for every
 * element. Holding in a gear: the need x --holding-margin (1.3) and at least
 * --holding-floor N m (30). Starts holding --start-gear (1).
 *
 * --calibration-image: the whole calibration (clutch, shift control, loop
 * timeouts and E2E) from an image file (wc_cal_image.h, `wetclutch
 * cal-image`), as wc_tcu --calibration-image; a refused image: one line,
 * exit 2. Not with --calibration, --shift or --set.
 *
 * --offgoing-calibration-image: the whole shift's off-going clutch (DESIGN
 * 14, wc_loop_config_t.offgoing) from an image of its own that carries one
 * clutch (shift control off: its shift and loop parts are not used, so the
 * image says so); without it the off-going clutch is an instance of the
 * on-coming one's calibration. Needs shift control with the coordinator
 * (--shift NAME or an image with it on); a refused image: exit 2. The
 * 8-speed's shifts give each element its own clutch this way
 * (tools/wetclutch/shift/matrix8.py).
 *
 * LOG "-" reads standard input. --shift turns shift control on with a
 * compiled-in shift calibration (as wc_tcu --shift); --set overrides one of
 * its float fields (the C name, e.g. kp_Nm_per_rad_s=4: the feedback-gain
 * search of `wetclutch shift`), the result checked by
 * wc_shift_calibration_check. --lockstep: after every step's output frames a
 * line "." and a flush, so that a plant simulator can drive the loop in
 * closed loop through a pipe (tools/wetclutch/shift/tcu.py).
 *
 * Reads a candump -L log (the input frames), feeds each frame the TCU would
 * receive (wc_tcu's kernel filter: ClutchSensors, TorqueRequest, and
 * BenchMeasurement with --bench) to the same wc_loop_iterate as wc_tcu with
 * --clock frame, and prints the output frames as a candump -L log (timestamp
 * of the frame that stepped the loop, interface "inproc"). The same firmware
 * code as on vcan, for fast checks: tests/python/test_replay_inproc.py
 * compares it with the double-precision reference of the loop, and with the
 * frames wc_tcu sends on vcan. Host program: stdio allowed. */
#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wetclutch/wc_config.h"
#include "wetclutch_can/wc_loop.h"
#include "wc_adapt_file.h"
#include "wc_cal_image_file.h"
#include "wc_loop_stats.h"
#include "wc_tcu_calibrations.h"
#include "wc_tcu_gearbox.h"

static int parse_line(const char *line, double *t_s, wc_can_frame_t *frame)
{
    char iface[32];
    char body[80];
    if (sscanf(line, " (%lf) %31s %79s", t_s, iface, body) != 3) { return -1; }
    char *hash = strchr(body, '#');
    if (hash == NULL) { return -1; }
    *hash = '\0';
    char *end = NULL;
    const unsigned long id = strtoul(body, &end, 16);
    if ((end == body) || (*end != '\0') || (strlen(body) > 8u)) { return -1; }
    memset(frame, 0, sizeof *frame);
    frame->id = (uint32_t)(id & 0x1FFFFFFFu);
    if (strlen(body) > 3u) { frame->flags |= WC_CAN_FLAG_EXTENDED; }
    const char *data = hash + 1;
    if (*data == 'R') { frame->flags |= WC_CAN_FLAG_REMOTE; return 0; }
    const size_t n = strlen(data) / 2u;
    if ((strlen(data) % 2u) != 0u || n > 8u) { return -1; }
    for (size_t i = 0; i < n; ++i) {
        unsigned v = 0u;
        if (sscanf(data + 2u * i, "%2x", &v) != 1) { return -1; }
        frame->data[i] = (uint8_t)v;
    }
    frame->dlc = (uint8_t)n;
    return 0;
}

/* The float fields of wc_shift_calibration_t that --set may override. */
typedef struct {
    const char *name;
    size_t offset;
} shift_field_t;
#define SHIFT_FIELD(f) { #f, offsetof(wc_shift_calibration_t, f) }
static const shift_field_t shift_fields[] = {
    SHIFT_FIELD(turbine_inertia_kg_m2), SHIFT_FIELD(turbine_ratio), SHIFT_FIELD(output_inertia_kg_m2),
    SHIFT_FIELD(output_ratio), SHIFT_FIELD(jerk_per_torque_rate),
    SHIFT_FIELD(prepare_time_s), SHIFT_FIELD(torque_phase_time_s), SHIFT_FIELD(inertia_time_min_s),
    SHIFT_FIELD(inertia_time_max_s), SHIFT_FIELD(inertia_timeout_factor), SHIFT_FIELD(lockup_ramp_time_s),
    SHIFT_FIELD(holding_torque_factor), SHIFT_FIELD(min_start_slip_rad_s), SHIFT_FIELD(feedforward_gain),
    SHIFT_FIELD(kp_Nm_per_rad_s), SHIFT_FIELD(ki_Nm_per_rad), SHIFT_FIELD(integral_limit_Nm),
    SHIFT_FIELD(lag_compensation_time_s), SHIFT_FIELD(flare_slip_rad_s), SHIFT_FIELD(tie_up_factor),
    SHIFT_FIELD(jerk_filter_time_s),
    SHIFT_FIELD(adapt_theta_node_degC[0]), SHIFT_FIELD(adapt_theta_node_degC[1]), SHIFT_FIELD(adapt_theta_node_degC[2]),
    SHIFT_FIELD(adapt_theta_node_degC[3]), SHIFT_FIELD(adapt_theta_node_degC[4]), SHIFT_FIELD(adapt_scale_band),
    SHIFT_FIELD(adapt_scale_step), SHIFT_FIELD(adapt_scale_gain), SHIFT_FIELD(adapt_confidence_gain),
    SHIFT_FIELD(adapt_film_factor_min), SHIFT_FIELD(adapt_film_factor_max), SHIFT_FIELD(adapt_film_step),
    SHIFT_FIELD(adapt_film_gain), SHIFT_FIELD(adapt_kiss_band_Pa), SHIFT_FIELD(adapt_kiss_step_Pa),
    SHIFT_FIELD(adapt_kiss_gain), SHIFT_FIELD(adapt_window_skip_s), SHIFT_FIELD(adapt_film_window_s),
    SHIFT_FIELD(adapt_min_slip_drop), SHIFT_FIELD(adapt_min_conditioning),
    SHIFT_FIELD(offgoing_ratio), SHIFT_FIELD(fill_pulse_current_mA), SHIFT_FIELD(fill_pulse_time_s),
    SHIFT_FIELD(offgoing_holding_factor), SHIFT_FIELD(offgoing_margin_factor), SHIFT_FIELD(offgoing_lag_compensation_time_s),
    SHIFT_FIELD(flare_kp_Nm_per_rad_s), SHIFT_FIELD(flare_ki_Nm_per_rad), SHIFT_FIELD(handover_slip_rad_s),
    SHIFT_FIELD(engine_increase_max_Nm), SHIFT_FIELD(engine_reduction_max_Nm), SHIFT_FIELD(engine_fill_fraction),
    SHIFT_FIELD(engine_reduction_fraction), SHIFT_FIELD(engine_recovery_time_s), SHIFT_FIELD(engine_lead_time_s),
    SHIFT_FIELD(fallback_time_s),
};

static int set_shift_field(wc_shift_calibration_t *cal, const char *assignment)
{
    const char *eq = strchr(assignment, '=');
    if (eq == NULL) { return -1; }
    for (size_t i = 0; i < sizeof shift_fields / sizeof shift_fields[0]; ++i) {
        if ((strlen(shift_fields[i].name) == (size_t)(eq - assignment)) &&
            (strncmp(assignment, shift_fields[i].name, (size_t)(eq - assignment)) == 0)) {
            char *end = NULL;
            const double v = strtod(eq + 1, &end);
            if ((end == eq + 1) || (*end != '\0')) { return -1; }
            const float f = (float)v;
            memcpy((char *)cal + shift_fields[i].offset, &f, sizeof f);
            return 0;
        }
    }
    return -1;
}

/* --stats-json: the counters as wc_tcu writes them (no SocketCAN: nothing dropped, no send failed, no
 * step times); a failed write is one line and exit 1, never a half-written file left behind. */
static int write_stats(const char *path, const wc_loop_counters_t *counters)
{
    FILE *f = fopen(path, "w");
    int failed = (f == NULL);
    if (f != NULL) {
        fprintf(f, "{\n");
        wc_loop_stats_json_members(f, counters, 0u, 0u);
        fprintf(f, "  \"step_time_us\": null\n}\n");
        failed = (ferror(f) != 0);
        failed |= (fclose(f) != 0);
    }
    if (failed) {
        fprintf(stderr, "wc_replay: cannot write %s: %s\n", path, strerror(errno));
        (void)remove(path);
        return 1;
    }
    return 0;
}

#define USAGE "usage: wc_replay LOG|- [--bench] [--calibration NAME] [--theta-start DEGC (-40..250)]" \
              " [--shift NAME [--set FIELD=VALUE]... [--adaptation-file FILE]] [--lockstep]\n" \
              "       wc_replay LOG|- [--bench] --calibration-image FILE [--theta-start DEGC] [--adaptation-file FILE]" \
              " [--lockstep]\n" \
              "       --offgoing-calibration-image FILE: the whole shift's off-going clutch (an image, shift off)\n" \
              "       --stats-json FILE: the loop's counters at the end, as wc_tcu --stats-json writes them\n" \
              WC_TCU_GEARBOX_USAGE

int main(int argc, char **argv)
{
    static wc_shift_calibration_t shift;  /* the loop keeps a pointer to it */
    const char *shift_name = NULL;
    const char *adaptation_path = NULL;
    int lockstep = 0;
    const char *log_path = NULL;
    const char *stats_path = NULL;  /* --stats-json */
    const char *calibration = "table1";
    const char *image_path = NULL;  /* --calibration-image */
    const char *offgoing_image_path = NULL;  /* --offgoing-calibration-image */
    int calibration_given = 0;
    int bench = 0;
    double theta_start_degC = 40.0;  /* as wc_tcu --theta-start */
    wc_tcu_gearbox_options_t gearbox = WC_TCU_GEARBOX_OPTIONS_DEFAULT;  /* --gearbox and its options */
    for (int i = 1; i < argc; ++i) {
        char *end = NULL;
        const int gearbox_option = wc_tcu_gearbox_option("wc_replay", argc, argv, &i, &gearbox);
        if (gearbox_option < 0) { return 2; }
        if (gearbox_option > 0) { continue; }
        if (strcmp(argv[i], "--bench") == 0) { bench = 1; }
        else if (strcmp(argv[i], "--lockstep") == 0) { lockstep = 1; }
        else if ((strcmp(argv[i], "--shift") == 0) && (i + 1 < argc) && (shift_name == NULL)) {
            shift_name = argv[++i];
            const wc_shift_calibration_t *found = wc_tcu_find_shift_calibration(shift_name);
            if (found == NULL) {
                fprintf(stderr, "wc_replay: --shift: '%s' is not compiled in\n", shift_name);
                return 2;
            }
            shift = *found;
        }
        else if ((strcmp(argv[i], "--set") == 0) && (i + 1 < argc) && (shift_name != NULL)) {
            if (set_shift_field(&shift, argv[++i]) != 0) {
                fprintf(stderr, "wc_replay: --set: '%s' is not FIELD=NUMBER of a float shift calibration field\n", argv[i]);
                return 2;
            }
        }
        else if ((strcmp(argv[i], "--adaptation-file") == 0) && (i + 1 < argc) &&
                 ((shift_name != NULL) || (image_path != NULL))) {
            adaptation_path = argv[++i];
        }
        else if ((strcmp(argv[i], "--stats-json") == 0) && (i + 1 < argc)) { stats_path = argv[++i]; }
        else if ((strcmp(argv[i], "--calibration") == 0) && (i + 1 < argc)) { calibration = argv[++i]; calibration_given = 1; }
        else if ((strcmp(argv[i], "--calibration-image") == 0) && (i + 1 < argc) && (image_path == NULL)) {
            image_path = argv[++i];
        }
        else if ((strcmp(argv[i], "--offgoing-calibration-image") == 0) && (i + 1 < argc) &&
                 (offgoing_image_path == NULL)) {
            offgoing_image_path = argv[++i];
        }
        else if ((strcmp(argv[i], "--theta-start") == 0) && (i + 1 < argc) &&
                 ((void)(theta_start_degC = strtod(argv[i + 1], &end)), (end != argv[i + 1]) && (*end == '\0')) &&
                 (theta_start_degC >= -40.0) && (theta_start_degC <= 250.0)) { ++i; }
        else if (((argv[i][0] != '-') || (strcmp(argv[i], "-") == 0)) && (log_path == NULL)) { log_path = argv[i]; }
        else {
            fprintf(stderr, USAGE);
            return 2;
        }
    }
    if (log_path == NULL) {
        fprintf(stderr, USAGE);
        return 2;
    }
    static wc_cal_set_t image;  /* --calibration-image: the loop keeps pointers into it */
    const wc_calibration_t *cal = NULL;
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    if (image_path != NULL) {
        if (calibration_given || (shift_name != NULL)) {
            fprintf(stderr, "wc_replay: --calibration-image holds the whole calibration: not with --calibration,"
                            " --shift or --set\n");
            return 2;
        }
        if (wc_cal_image_file_load(image_path, "wc_replay", "--calibration-image", &image) != 0) { return 2; }
        cal = &image.clutch;
        config = image.loop;
        calibration = image_path;
        if ((adaptation_path != NULL) && (config.shift == NULL)) {
            fprintf(stderr, "wc_replay: --adaptation-file needs shift control (the image has it off)\n");
            return 2;
        }
    }
    for (size_t i = 0; (cal == NULL) && (i < wc_tcu_calibration_count); ++i) {
        if (strcmp(calibration, wc_tcu_calibrations[i].name) == 0) { cal = wc_tcu_calibrations[i].calibration; }
    }
    if (cal == NULL) {
        fprintf(stderr, "wc_replay: --calibration: '%s' is not compiled in\n", calibration);
        return 2;
    }
    static wc_loop_t loop;  /* large (receive ring): static storage */
    config.bench_input_enabled = bench != 0;
    if (shift_name != NULL) {
        const wc_shift_cal_error_t shift_error = wc_shift_calibration_check(&shift);
        if (shift_error != WC_SHIFT_CAL_OK) {
            fprintf(stderr, "wc_replay: shift calibration %s rejected (wc_shift_cal_error_t %d)\n", shift_name,
                    (int)shift_error);
            return 2;
        }
        config.shift = &shift;
    }
    static wc_cal_set_t offgoing_image;  /* --offgoing-calibration-image: the loop keeps a pointer into it */
    if (offgoing_image_path != NULL) {
        if ((config.shift == NULL) || (config.shift->coordinator != 1u)) {
            fprintf(stderr, "wc_replay: --offgoing-calibration-image needs shift control with the coordinator (the"
                            " whole shift): --shift NAME or an image with it\n");
            return 2;
        }
        if (wc_cal_image_file_load(offgoing_image_path, "wc_replay", "--offgoing-calibration-image", &offgoing_image) != 0) { return 2; }
        if (offgoing_image.shift_enabled) {
            fprintf(stderr, "wc_replay: --offgoing-calibration-image %s: carries shift control; the off-going"
                            " clutch's image holds its clutch alone (shift off)\n", offgoing_image_path);
            return 2;
        }
        config.offgoing = &offgoing_image.clutch;
    }
    static wc_transmission_config_t transmission;  /* --gearbox: the loop keeps pointers into these */
    static wc_cal_set_t element_images[WC_GEARBOX_ELEMENTS_MAX];
    if ((gearbox.gearbox != NULL) && ((offgoing_image_path != NULL) || (adaptation_path != NULL) || bench)) {
        fprintf(stderr, "wc_replay: --gearbox takes no --offgoing-calibration-image, --adaptation-file or --bench\n");
        return 2;
    }
    if (wc_tcu_gearbox_config("wc_replay", &gearbox, cal, (float)theta_start_degC, &config, &transmission,
                              element_images) != 0) {
        return 2;
    }
    if ((config.shift != NULL) && (config.shift->coordinator == 1u) && (config.offgoing == NULL)) {
        config.offgoing = cal;  /* DESIGN 14: the off-going clutch has the same lining (its own instance) */
    }
    if (wc_loop_init(&loop, cal, &config, (float)theta_start_degC) != WC_CAL_OK) {
        fprintf(stderr, "wc_replay: calibration %s rejected\n", calibration);
        return 2;
    }
    static wc_adapt_file_t adaptation_file;  /* the loop's hook keeps a pointer to it */
    if (adaptation_path != NULL) {
        adaptation_file.path = adaptation_path;
        adaptation_file.program = "wc_replay";
        (void)wc_adapt_file_attach(&adaptation_file, &loop);
    }
    FILE *in = (strcmp(log_path, "-") == 0) ? stdin : fopen(log_path, "r");
    if (in == NULL) {
        fprintf(stderr, "wc_replay: %s: %s\n", log_path, strerror(errno));
        return 2;
    }
    uint32_t ids[WC_LOOP_RX_ID_COUNT];
    const size_t id_count = wc_loop_rx_ids(&config, ids);  /* wc_tcu's kernel filter */
    char line[256];
    unsigned long line_no = 0;
    while (fgets(line, sizeof line, in) != NULL) {
        ++line_no;
        if (line[strspn(line, " \t\r\n")] == '\0') { continue; }
        double t_s = 0.0;
        wc_can_frame_t frame;
        if (parse_line(line, &t_s, &frame) != 0) {
            fprintf(stderr, "wc_replay: %s: line %lu: not a candump -L line\n", log_path, line_no);
            fclose(in);
            return 2;
        }
        int passes = 0;  /* the kernel filter of wc_tcu: standard ids of the frames it receives */
        for (size_t i = 0; i < id_count; ++i) {
            passes |= ((frame.flags & WC_CAN_FLAG_EXTENDED) == 0u) && (frame.id == ids[i]);
        }
        if (!passes) { continue; }
        wc_can_frame_t out[WC_LOOP_TX_FRAMES];
        const uint32_t n = wc_loop_iterate(&loop, WC_LOOP_CLOCK_FRAME, &frame, false, out);
        for (uint32_t k = 0; k < n; ++k) {
            printf("(%.6f) inproc %03X#", t_s, (unsigned)out[k].id);
            for (uint8_t j = 0; j < out[k].dlc; ++j) { printf("%02X", out[k].data[j]); }
            printf("\n");
        }
        if (lockstep && (n > 0u)) {
            printf(".\n");
            if (fflush(stdout) != 0) { return 1; }
        }
    }
    if (in != stdin) { fclose(in); }
    if (fflush(stdout) != 0) {
        fprintf(stderr, "wc_replay: writing stdout failed\n");
        return 1;
    }
    return (stats_path != NULL) ? write_stats(stats_path, &loop.counters) : 0;
}
