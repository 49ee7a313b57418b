/* wc_exp (src/model/wc_exp.c), the model's e^x, against the C library's
 * expf over the arguments the model uses. Bound: 2 ulp of the float result
 * (the Cephes polynomial's 1.8e-7 relative error plus the roundings of the
 * reduction and of the Horner sum); exact at 0. Below -87 the result is 0
 * by definition, above 88 it is e^88. */
#include "wc_test_support.h"

#include <stdio.h>
#include <stdlib.h>

#include "wc_internal.h"

static int64_t ulp_distance(float a, float b)
{
    int32_t ia;
    int32_t ib;
    memcpy(&ia, &a, sizeof ia);
    memcpy(&ib, &b, sizeof ib);
    return llabs((int64_t)ia - (int64_t)ib);  /* both positive: ordered like the values */
}

static void test_within_two_ulp_of_expf(void **state)
{
    (void)state;
    int64_t worst = 0;
    float worst_x = 0.0f;
    long n = 0;
    for (float x = -87.0f; x <= 88.0f; x += 1.0e-4f * (1.0f + fabsf(x))) {
        const int64_t d = ulp_distance(wc_exp(x), expf(x));
        if (d > worst) { worst = d; worst_x = x; }
        ++n;
    }
    /* every float in the Stribeck range [-30, 0] at a 2^-14 grid */
    for (float x = -30.0f; x <= 0.0f; x += 1.0f / 16384.0f) {
        const int64_t d = ulp_distance(wc_exp(x), expf(x));
        if (d > worst) { worst = d; worst_x = x; }
        ++n;
    }
    printf("    wc_exp vs expf: max %lld ulp at x = %.9g over %ld arguments (allowed 2)\n", (long long)worst,
           (double)worst_x, n);
    WC_CHECK(worst <= 2, "wc_exp is %lld ulp from expf at %.9g", (long long)worst, (double)worst_x);
}

static void test_exact_and_edge_values(void **state)
{
    (void)state;
    assert_true(wc_test_same_float(wc_exp(0.0f), 1.0f));
    assert_true(wc_test_same_float(wc_exp(-0.0f), 1.0f));
    assert_true(wc_test_same_float(wc_exp(-87.5f), 0.0f));
    assert_true(wc_test_same_float(wc_exp(-1000.0f), 0.0f));
    assert_true(wc_test_same_float(wc_exp(-INFINITY), 0.0f));
    assert_true(wc_test_same_float(wc_exp(NAN), 0.0f));
    assert_true(isfinite(wc_exp(1000.0f)));
    assert_true(wc_test_same_float(wc_exp(1000.0f), wc_exp(88.0f)));
    assert_true(isfinite(wc_exp(INFINITY)));
}

/* Monotone non-decreasing on a fine grid: the model relies on mu_v and mu_f
 * moving one way with temperature and speed. */
static void test_monotone(void **state)
{
    (void)state;
    float previous = wc_exp(-87.0f);
    for (float x = -87.0f; x <= 88.0f; x += 1.0e-3f) {
        const float y = wc_exp(x);
        WC_CHECK(y >= previous, "wc_exp not monotone at %.9g", (double)x);
        previous = y;
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_within_two_ulp_of_expf),
        cmocka_unit_test(test_exact_and_edge_values),
        cmocka_unit_test(test_monotone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
