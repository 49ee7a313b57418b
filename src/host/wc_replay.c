/* wc_replay: the TCU's frame loop linked in-process, without SocketCAN.
 *
 *   wc_replay LOG [--bench] [--calibration NAME]
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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wetclutch/wc_config.h"
#include "wetclutch_can/wc_loop.h"
#include "wc_tcu_calibrations.h"

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

int main(int argc, char **argv)
{
    const char *log_path = NULL;
    const char *calibration = "table1";
    int bench = 0;
    double theta_start_degC = 40.0;  /* as wc_tcu --theta-start */
    for (int i = 1; i < argc; ++i) {
        char *end = NULL;
        if (strcmp(argv[i], "--bench") == 0) { bench = 1; }
        else if ((strcmp(argv[i], "--calibration") == 0) && (i + 1 < argc)) { calibration = argv[++i]; }
        else if ((strcmp(argv[i], "--theta-start") == 0) && (i + 1 < argc) &&
                 ((void)(theta_start_degC = strtod(argv[i + 1], &end)), (end != argv[i + 1]) && (*end == '\0')) &&
                 (theta_start_degC >= -40.0) && (theta_start_degC <= 250.0)) { ++i; }
        else if ((argv[i][0] != '-') && (log_path == NULL)) { log_path = argv[i]; }
        else {
            fprintf(stderr, "usage: wc_replay LOG [--bench] [--calibration NAME] [--theta-start DEGC (-40..250)]\n");
            return 2;
        }
    }
    if (log_path == NULL) {
        fprintf(stderr, "usage: wc_replay LOG [--bench] [--calibration NAME] [--theta-start DEGC (-40..250)]\n");
        return 2;
    }
    const wc_calibration_t *cal = NULL;
    for (size_t i = 0; i < wc_tcu_calibration_count; ++i) {
        if (strcmp(calibration, wc_tcu_calibrations[i].name) == 0) { cal = wc_tcu_calibrations[i].calibration; }
    }
    if (cal == NULL) {
        fprintf(stderr, "wc_replay: --calibration: '%s' is not compiled in\n", calibration);
        return 2;
    }
    static wc_loop_t loop;  /* large (receive ring): static storage */
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.bench_input_enabled = bench != 0;
    if (wc_loop_init(&loop, cal, &config, (float)theta_start_degC) != WC_CAL_OK) {
        fprintf(stderr, "wc_replay: calibration %s rejected\n", calibration);
        return 2;
    }
    FILE *in = fopen(log_path, "r");
    if (in == NULL) {
        fprintf(stderr, "wc_replay: %s: %s\n", log_path, strerror(errno));
        return 2;
    }
    const uint32_t ids[] = WC_LOOP_RX_IDS;
    const size_t id_count = bench ? WC_LOOP_RX_ID_COUNT : WC_LOOP_RX_ID_COUNT - 1u;
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
    }
    fclose(in);
    if (fflush(stdout) != 0) {
        fprintf(stderr, "wc_replay: writing stdout failed\n");
        return 1;
    }
    return 0;
}
