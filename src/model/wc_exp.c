/* e^x for the model's exponentials (eq. 2 and eq. 18), DESIGN section 11:
 * newlib's expf costs about 80 instructions on a Cortex-M4F, this about 30.
 *
 * Cody-Waite range reduction x = n ln2 + r, |r| <= ln2/2, with ln2 split in
 * two so that n ln2 is exact enough; e^r by the Cephes expf polynomial
 * (degree 7 in total, relative error about 1.8e-7 on the interval); 2^n
 * built in the exponent field. tests/c/test_exp.c measures the error against
 * the C library's expf over [-87, 88]: at most 2 ulp (the bound asserted).
 *
 * Domain: the arguments the model produces are -30..0 (Stribeck term, eq. 18)
 * and b theta for eq. 2, which the calibration check keeps within +-75 (|b| <= 0.3 /K).
 * Below -87 the result is 0 (e^-87 = 1.6e-38, the smallest normal float is
 * 1.2e-38), above 88 it is e^88 (no overflow); NaN gives 0. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "wc_internal.h"

float wc_exp(float x)
{
    if (!(x >= -87.0f)) { return 0.0f; }   /* also NaN */
    const float xc = (x < 88.0f) ? x : 88.0f;
    /* n = round(x / ln2): adding and removing 1.5 * 2^23 rounds to an integer
     * in float arithmetic (to nearest even; either tie is a valid reduction). */
    const float nf = (xc * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
    const int32_t n = (int32_t)nf;
    /* r = x - n ln2, ln2 = 0.693359375 - 2.12194440e-4; fmaf is one VFMA
     * instruction on the Cortex-M4F and exactly rounded everywhere. */
    const float r = fmaf(nf, 2.12194440e-4f, fmaf(nf, -0.693359375f, xc));
    float q = fmaf(1.9875691500e-4f, r, 1.3981999507e-3f);
    q = fmaf(q, r, 8.3334519073e-3f);
    q = fmaf(q, r, 4.1665795894e-2f);
    q = fmaf(q, r, 1.6666665459e-1f);
    q = fmaf(q, r, 5.0000001201e-1f);
    const float poly = fmaf(q, r * r, r) + 1.0f;                        /* e^r */
    const uint32_t bits = (uint32_t)(n + 127) << 23;                    /* 2^n, n in [-126, 127] */
    float scale;
    memcpy(&scale, &bits, sizeof scale);
    return poly * scale;
}
