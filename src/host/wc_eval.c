/* wc_eval: the firmware's own arithmetic (float, the generated table1
 * calibration and film table) on CSV, for comparison with the double-precision
 * reference `wetclutch reference <mode>` (tools/wetclutch/reference/evaluate.py), whose
 * column names and semantics it follows.
 *
 * A host program: stdio and double are fine here, but every model number
 * comes from the library; this file only parses, converts units and prints. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wetclutch/wetclutch.h"
#include "wc_table1_calibration.h"

#define LINE_MAX_CHARS 4096u   /* longest input line accepted, newline included */
#define FIELDS_MAX 256u        /* most columns in a row */
#define INPUTS_MAX 5u          /* most input columns of a mode */
#define ROW_MAX_CHARS 256u     /* one output row */

enum { EXIT_BAD_INPUT = 1, EXIT_USAGE = 2 };

typedef enum { MODE_TORQUE, MODE_INVERSE, MODE_THERMAL } eval_mode_t;

typedef struct {
    const char *name;
    eval_mode_t mode;
    const char *inputs[INPUTS_MAX];
    size_t input_count;
    const char *outputs;  /* the output header */
} mode_spec_t;

static const mode_spec_t MODES[] = {
    { "torque", MODE_TORQUE, { "slip_rpm", "theta_degC", "force_N" }, 3u,
      "torque_Nm,coulomb_Nm,viscous_Nm,hbar_um,mu_f" },
    { "inverse", MODE_INVERSE, { "slip_rpm", "theta_degC", "torque_Nm" }, 3u,
      "force_N,pressure_kPa,current_mA,status" },
    { "thermal", MODE_THERMAL, { "t_s", "slip_rpm", "torque_Nm", "theta_oil_degC", "theta_housing_degC" }, 5u,
      "t_s,theta_degC" },
};

static const char *g_mode_name = "";

static void usage(FILE *stream)
{
    fprintf(stream,
            "usage: wc_eval {torque|inverse|thermal} < input.csv > output.csv\n"
            "       wc_eval --help\n"
            "\n"
            "Runs the wet-clutch firmware's own float arithmetic on CSV rows, with the\n"
            "bundled calibration 'table1' (lut/wc_table1_calibration.h). Same columns as\n"
            "`wetclutch reference <mode>`, so the two outputs can be compared.\n"
            "\n"
            "  torque   in:  slip_rpm,theta_degC,force_N\n"
            "           out: torque_Nm,coulomb_Nm,viscous_Nm,hbar_um,mu_f\n"
            "  inverse  in:  slip_rpm,theta_degC,torque_Nm   (torque request, magnitude >= 0)\n"
            "           out: force_N,pressure_kPa,current_mA,status\n"
            "           status bits: 1 below drag (force 0), 2 saturated, 4 current clamped\n"
            "  thermal  in:  t_s,slip_rpm,torque_Nm,theta_oil_degC,theta_housing_degC\n"
            "           one row per control period (%g s); the observer starts at the first\n"
            "           row's oil temperature\n"
            "           out: t_s,theta_degC  (the estimate before the row's input is applied)\n"
            "\n"
            "Input: a header row naming the columns (any order, extra columns ignored),\n"
            "then one row of plain numbers per line (no quoting). Output numbers are\n"
            "printed with %%.9g. A bad row (wrong field count, not a number, NaN or\n"
            "infinite, outside the library's plausible range) is reported on stderr\n"
            "with its line number (the header is line 1); the rows before it have been\n"
            "printed, that row and later ones are not, and the exit status is 1.\n"
            "Exit status: 0 success, 1 bad input, 2 usage error.\n",
            (double)wc_table1_calibration.control_period_s);
}

static int fail_line(unsigned long line, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    fprintf(stderr, "wc_eval %s: <stdin>: line %lu: ", g_mode_name, line);
    vfprintf(stderr, format, args);
    fputc('\n', stderr);
    va_end(args);
    return EXIT_BAD_INPUT;
}

/* Cut trailing "\n" / "\r\n"; false when the line did not fit the buffer. */
static bool read_line(char *buffer, size_t size, bool *eof)
{
    *eof = false;
    if (fgets(buffer, (int)size, stdin) == NULL) {
        *eof = true;
        return true;
    }
    size_t n = strlen(buffer);
    const bool complete = (n > 0u) && (buffer[n - 1u] == '\n');
    if (!complete && !feof(stdin)) {
        return false;
    }
    while ((n > 0u) && ((buffer[n - 1u] == '\n') || (buffer[n - 1u] == '\r'))) {
        buffer[--n] = '\0';
    }
    return true;
}

static char *trim(char *s)
{
    while ((*s == ' ') || (*s == '\t')) { ++s; }
    size_t n = strlen(s);
    while ((n > 0u) && ((s[n - 1u] == ' ') || (s[n - 1u] == '\t'))) { s[--n] = '\0'; }
    return s;
}

/* Split at commas in place; returns the field count, or FIELDS_MAX + 1 if too many. */
static size_t split(char *line, char *fields[FIELDS_MAX])
{
    size_t count = 0u;
    char *start = line;
    for (;;) {
        char *comma = strchr(start, ',');
        if (count == FIELDS_MAX) { return FIELDS_MAX + 1u; }
        if (comma != NULL) { *comma = '\0'; }
        fields[count++] = trim(start);
        if (comma == NULL) { return count; }
        start = comma + 1;
    }
}

static bool blank(const char *line)
{
    for (; *line != '\0'; ++line) {
        if ((*line != ' ') && (*line != '\t')) { return false; }
    }
    return true;
}

/* A finite number taking the whole field. */
static bool parse_number(const char *text, double *value)
{
    if (*text == '\0') { return false; }
    char *end = NULL;
    const double v = strtod(text, &end);  /* overflow gives +-HUGE_VAL: "not finite" below */
    if ((end == text) || (*end != '\0')) { return false; }
    *value = v;
    return true;
}

/* The firmware's inputs are float: a double beyond the float range is out of
 * every plausible range (and converting it would be undefined behaviour). */
static float to_float(double x)
{
    if (x > (double)FLT_MAX) { return INFINITY; }
    if (x < -(double)FLT_MAX) { return -INFINITY; }
    return (float)x;
}

static float rpm_to_rad_s(double slip_rpm)
{
    return to_float(slip_rpm) * WC_RAD_S_PER_RPM;  /* as the firmware converts a sensor's rpm */
}

/* Append "; "-separated text to a fixed buffer, truncating if it is full. */
static void append(char *buffer, size_t size, size_t *used, const char *format, ...)
{
    if (*used + 1u >= size) { return; }
    if (*used > 0u) {
        const int n = snprintf(buffer + *used, size - *used, "; ");
        *used = (n < 0) ? *used : ((size_t)n >= size - *used ? size - 1u : *used + (size_t)n);
    }
    va_list args;
    va_start(args, format);
    const int n = vsnprintf(buffer + *used, size - *used, format, args);
    va_end(args);
    *used = (n < 0) ? *used : ((size_t)n >= size - *used ? size - 1u : *used + (size_t)n);
}

/* Say which input the library rejected, with the accepted range. */
static int fail_status(unsigned long line, wc_status_t status)
{
    char reason[512];
    size_t used = 0u;
    reason[0] = '\0';
    if ((status & WC_STATUS_SLIP_INVALID) != 0u) {
        append(reason, sizeof reason, &used, "slip_rpm not within +-%g rpm",
               (double)(WC_SLIP_MAX_rad_s / WC_RAD_S_PER_RPM));
    }
    if ((status & WC_STATUS_THETA_INVALID) != 0u) {
        append(reason, sizeof reason, &used, "a temperature not within %g..%g degC", (double)WC_THETA_MIN_degC,
               (double)WC_THETA_MAX_degC);
    }
    if ((status & WC_STATUS_FORCE_INVALID) != 0u) {
        append(reason, sizeof reason, &used, "force_N not within 0..%g N", (double)WC_FORCE_MAX_N);
    }
    if ((status & WC_STATUS_TORQUE_INVALID) != 0u) {
        append(reason, sizeof reason, &used, "torque_Nm not within 0..%g Nm", (double)WC_TORQUE_MAX_Nm);
    }
    if ((status & WC_STATUS_POWER_INVALID) != 0u) {
        append(reason, sizeof reason, &used, "heat input |torque_Nm x slip| not finite");
    }
    return fail_line(line, "input rejected by the model (status 0x%x): %s", (unsigned)status, reason);
}

/* Print one complete row, or nothing. */
static int emit(unsigned long line, const char *format, ...)
{
    char row[ROW_MAX_CHARS];
    va_list args;
    va_start(args, format);
    const int n = vsnprintf(row, sizeof row, format, args);
    va_end(args);
    if ((n < 0) || ((size_t)n >= sizeof row)) {
        return fail_line(line, "internal error: output row too long");
    }
    if (fputs(row, stdout) == EOF) {
        fprintf(stderr, "wc_eval %s: writing stdout failed\n", g_mode_name);
        return EXIT_BAD_INPUT;
    }
    return 0;
}

typedef struct {
    bool started;
    float theta_degC;  /* observer state */
    double t_previous_s;
} thermal_run_t;

static int evaluate(const wc_model_t *model, const mode_spec_t *spec, unsigned long line, const double *v,
                    thermal_run_t *thermal)
{
    switch (spec->mode) {
    case MODE_TORQUE: {
        wc_torque_t out;
        const wc_status_t status = wc_torque(model, rpm_to_rad_s(v[0]), to_float(v[1]), to_float(v[2]), &out);
        if ((status & WC_STATUS_INPUT_INVALID) != 0u) { return fail_status(line, status); }
        return emit(line, "%.9g,%.9g,%.9g,%.9g,%.9g\n", (double)out.torque_Nm, (double)out.coulomb_Nm,
                    (double)out.viscous_Nm, (double)out.hbar_m * 1e6, (double)out.mu_f);
    }
    case MODE_INVERSE: {
        wc_inverse_t out;
        const wc_status_t status = wc_inverse(model, rpm_to_rad_s(v[0]), to_float(v[1]), to_float(v[2]), &out);
        if ((status & WC_STATUS_INPUT_INVALID) != 0u) { return fail_status(line, status); }
        return emit(line, "%.9g,%.9g,%.9g,%u\n", (double)out.force_N, (double)out.pressure_Pa * 1e-3,
                    (double)out.current_mA, (unsigned)status);
    }
    case MODE_THERMAL:
    default: {
        const double t_s = v[0];
        const double period_s = (double)model->cal->control_period_s;
        if (!thermal->started) {
            const float oil = to_float(v[3]);
            if (!((oil >= WC_THETA_MIN_degC) && (oil <= WC_THETA_MAX_degC))) {
                return fail_status(line, WC_STATUS_THETA_INVALID);
            }
            thermal->theta_degC = oil;  /* the observer starts at the first oil temperature */
        } else {
            /* same rule as the reference: within 1e-6 of a period (+ 1 ns) */
            const double step_s = t_s - thermal->t_previous_s;
            if (!(fabs(step_s - period_s) <= 1e-6 * period_s + 1e-9)) {
                return fail_line(line, "column t_s: step %.9g s, expected one control period (%g s) per row", step_s,
                                 period_s);
            }
        }
        /* eq. 1 heat input P = |T dw|, as wc_clutch_step computes it */
        const float power_W = fabsf(to_float(v[2]) * rpm_to_rad_s(v[1]));
        const float theta_before = thermal->theta_degC;
        const wc_status_t status =
            wc_thermal_step(model, &thermal->theta_degC, power_W, to_float(v[3]), to_float(v[4]));
        if ((status & WC_STATUS_INPUT_INVALID) != 0u) { return fail_status(line, status); }
        thermal->started = true;
        thermal->t_previous_s = t_s;
        return emit(line, "%.9g,%.9g\n", t_s, (double)theta_before);
    }
    }
}

int main(int argc, char **argv)
{
    if ((argc == 2) && ((strcmp(argv[1], "--help") == 0) || (strcmp(argv[1], "-h") == 0))) {
        usage(stdout);
        return 0;
    }
    const mode_spec_t *spec = NULL;
    if (argc == 2) {
        for (size_t i = 0u; i < sizeof MODES / sizeof MODES[0]; ++i) {
            if (strcmp(argv[1], MODES[i].name) == 0) { spec = &MODES[i]; }
        }
    }
    if (spec == NULL) {
        if (argc >= 2) { fprintf(stderr, "wc_eval: unknown mode or option '%s'\n", argv[1]); }
        usage(stderr);
        return EXIT_USAGE;
    }
    g_mode_name = spec->name;

    wc_model_t model;
    const wc_cal_error_t cal_error = wc_model_init(&model, &wc_table1_calibration);
    if (cal_error != WC_CAL_OK) {
        fprintf(stderr, "wc_eval: bundled calibration invalid: %s\n", wc_cal_error_name(cal_error));
        return EXIT_BAD_INPUT;
    }

    static char buffer[LINE_MAX_CHARS];
    char *fields[FIELDS_MAX];
    bool eof = false;
    unsigned long line = 1u;

    /* Header: find each input column by name (the first of duplicates). */
    if (!read_line(buffer, sizeof buffer, &eof)) {
        return fail_line(line, "longer than %u characters", LINE_MAX_CHARS - 2u);
    }
    if (eof) {
        fprintf(stderr, "wc_eval %s: <stdin>: empty input, expected a header\n", g_mode_name);
        return EXIT_BAD_INPUT;
    }
    const size_t columns = split(buffer, fields);
    if (columns > FIELDS_MAX) { return fail_line(line, "more than %u columns", FIELDS_MAX); }
    size_t index[INPUTS_MAX];
    char missing[256];
    missing[0] = '\0';
    for (size_t c = 0u; c < spec->input_count; ++c) {
        index[c] = columns;
        for (size_t k = 0u; (k < columns) && (index[c] == columns); ++k) {
            if (strcmp(fields[k], spec->inputs[c]) == 0) { index[c] = k; }
        }
        if (index[c] == columns) {
            strncat(missing, (missing[0] != '\0') ? ", " : "", sizeof missing - strlen(missing) - 1u);
            strncat(missing, spec->inputs[c], sizeof missing - strlen(missing) - 1u);
        }
    }
    if (missing[0] != '\0') {
        char expected[256];
        expected[0] = '\0';
        for (size_t c = 0u; c < spec->input_count; ++c) {
            strncat(expected, (c > 0u) ? "," : "", sizeof expected - strlen(expected) - 1u);
            strncat(expected, spec->inputs[c], sizeof expected - strlen(expected) - 1u);
        }
        return fail_line(line, "missing column(s) %s; expected %s", missing, expected);
    }
    if (emit(line, "%s\n", spec->outputs) != 0) { return EXIT_BAD_INPUT; }

    thermal_run_t thermal = { false, 0.0f, 0.0 };
    for (;;) {
        ++line;
        if (!read_line(buffer, sizeof buffer, &eof)) {
            return fail_line(line, "longer than %u characters", LINE_MAX_CHARS - 2u);
        }
        if (eof) { break; }
        if (blank(buffer)) { continue; }
        const size_t count = split(buffer, fields);
        if (count != columns) {
            if (count > FIELDS_MAX) { return fail_line(line, "more than %u fields", FIELDS_MAX); }
            return fail_line(line, "%zu fields, header has %zu", count, columns);
        }
        double values[INPUTS_MAX];
        for (size_t c = 0u; c < spec->input_count; ++c) {
            const char *text = fields[index[c]];
            if (!parse_number(text, &values[c])) {
                return fail_line(line, "column %s: '%s' is not a number", spec->inputs[c], text);
            }
            if (!isfinite(values[c])) {
                return fail_line(line, "column %s: '%s' is not finite", spec->inputs[c], text);
            }
        }
        const int error = evaluate(&model, spec, line, values, &thermal);
        if (error != 0) { return error; }
    }
    if (ferror(stdin)) {
        fprintf(stderr, "wc_eval %s: reading stdin failed\n", g_mode_name);
        return EXIT_BAD_INPUT;
    }
    if ((fflush(stdout) != 0) || ferror(stdout)) {
        fprintf(stderr, "wc_eval %s: writing stdout failed\n", g_mode_name);
        return EXIT_BAD_INPUT;
    }
    return 0;
}
