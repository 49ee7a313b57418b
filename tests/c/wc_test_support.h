/* Helpers shared by the cmocka unit tests (tests/c/test_*.c). Not part of
 * the library. Include this instead of <cmocka.h>: cmocka needs <stdarg.h>,
 * <stddef.h> and <setjmp.h> first. */
#ifndef WC_TEST_SUPPORT_H
#define WC_TEST_SUPPORT_H

#include <float.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "wetclutch/wetclutch.h"

/* rpm -> rad/s in double; the tests round the product to float once. */
#define WC_TEST_RAD_S_PER_RPM (3.14159265358979323846 / 30.0)

/* FLT_EPSILON as a double, for tolerances computed in double. */
#define WC_TEST_FLT_EPSILON ((double)FLT_EPSILON)

#define WC_TEST_COUNT(array) (sizeof(array) / sizeof((array)[0]))

static inline float wc_test_rpm_to_rad_s(double slip_rpm)
{
    return (float)(slip_rpm * WC_TEST_RAD_S_PER_RPM);
}

/* Bit-for-bit equality of two floats (also tells 0 from -0 and NaN payloads). */
static inline bool wc_test_same_float(float a, float b)
{
    uint32_t x;
    uint32_t y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

/* Relative error |actual/expected - 1|, or the absolute error when expected is 0.
 * NaN in, NaN out (and NaN never passes a <= comparison). */
static inline double wc_test_rel_error(double actual, double expected)
{
    const double diff = fabs(actual - expected);
    return (fabs(expected) > 0.0) ? diff / fabs(expected) : diff;
}

/* Fails the test unless |actual - expected| <= abs_tol + rel_tol |expected|.
 * A NaN actual or expected always fails. */
static inline void wc_test_check_close(const char *file, int line, const char *what, long index,
                                       double actual, double expected, double rel_tol, double abs_tol)
{
    const double diff = fabs(actual - expected);
    if (!(diff <= abs_tol + rel_tol * fabs(expected))) {
        print_error("%s[%ld]: got %.9g, expected %.9g (|diff| %.3g, relative %.3g; allowed %.3g relative + %.3g)\n",
                    what, index, actual, expected, diff, wc_test_rel_error(actual, expected), rel_tol, abs_tol);
        _fail(file, line);
    }
}

#define WC_CHECK_CLOSE(what, index, actual, expected, rel_tol, abs_tol) \
    wc_test_check_close(__FILE__, __LINE__, (what), (long)(index), (double)(actual), (double)(expected), \
                        (rel_tol), (abs_tol))

/* Running maximum of an error, to print how much of a tolerance is used. */
typedef struct {
    double max;
    long index;
} wc_test_worst_t;

static inline void wc_test_worst_update(wc_test_worst_t *worst, double error, long index)
{
    if (!(error <= worst->max)) {  /* NaN also counts as worse */
        worst->max = error;
        worst->index = index;
    }
}

static inline void wc_test_worst_print(const char *what, const wc_test_worst_t *worst, double tolerance)
{
    print_message("    %-28s max error %.3g at [%ld] (tolerance %.3g)\n", what, worst->max, worst->index, tolerance);
}

/* cmocka's assert_true shows only the expression; this adds a formatted reason. */
#define WC_CHECK(cond, ...)                       \
    do {                                          \
        if (!(cond)) {                            \
            print_error("check failed: %s: ", #cond); \
            print_error(__VA_ARGS__);             \
            print_error("\n");                    \
            _fail(__FILE__, __LINE__);            \
        }                                         \
    } while (0)

/* A golden image written by a Python test (tests/vectors/NAME.hex): its
 * hex digits into out (at most capacity bytes), '#' lines skipped. Returns
 * the bytes read. */
static inline size_t wc_test_read_hex(const char *path, uint8_t *out, size_t capacity)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[256];
    size_t n = 0u;
    while (fgets(line, sizeof line, f) != NULL) {
        if (line[0] == '#') { continue; }
        unsigned byte;
        int used;
        for (const char *p = line; sscanf(p, " %2x%n", &byte, &used) == 1; p += used) {
            assert_true(n < capacity);
            out[n++] = (uint8_t)byte;
        }
    }
    fclose(f);
    return n;
}

#endif /* WC_TEST_SUPPORT_H */
