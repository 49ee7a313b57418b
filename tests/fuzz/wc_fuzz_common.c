/* Helpers of the libFuzzer harnesses (wc_fuzz_common.h). Not part of the
 * library: stdio, getenv and abort are fine here. */
#include "wc_fuzz_common.h"

#include <float.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wc_config.h>

fz_context_t fz_ctx;

float fz_float_bits(uint32_t bits)
{
    float x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

uint32_t fz_bits_of(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

static float special_value(uint8_t index)
{
    /* Bit patterns where a literal cannot say it (NaN payloads, denormals). */
    static const uint32_t patterns[] = {
        0x00000000u, /* +0 */
        0x80000000u, /* -0 */
        0x7fc00000u, /* quiet NaN */
        0xffc00000u, /* -NaN */
        0x7fa00000u, /* signalling NaN */
        0x7f800001u, /* NaN, smallest payload */
        0x7f800000u, /* +Inf */
        0xff800000u, /* -Inf */
        0x7f7fffffu, /* FLT_MAX */
        0xff7fffffu, /* -FLT_MAX */
        0x00800000u, /* FLT_MIN */
        0x00000001u, /* smallest denormal */
        0x80000001u, /* -smallest denormal */
        0x007fffffu, /* largest denormal */
        0x807fffffu, /* -largest denormal */
    };
    static const float values[] = {
        1.0f, -1.0f, 0.5f, 1e-30f, -1e-30f, 1e30f, -1e30f, 1e-7f, 1e7f, 1e10f, -1e10f,
        WC_SLIP_MAX_rad_s, -WC_SLIP_MAX_rad_s, WC_THETA_MIN_degC, WC_THETA_MAX_degC,
        WC_THETA_OVER_degC, WC_THETA_OVER_degC - WC_THETA_OVER_HYSTERESIS_K, 20.0f, 40.0f, 90.0f,
        WC_FORCE_MAX_N, WC_TORQUE_MAX_Nm, 0.01f, -0.01f, 1000.0f, 2000.0f, 4.2e6f, 11.226f,
        593.3f, 1188.0f, 150.0f, 78.54f, -78.54f, 157.8f, 1e6f, 88.0f, -88.0f, 87.0f, -104.0f,
    };
    const size_t np = sizeof patterns / sizeof patterns[0];
    const size_t nv = sizeof values / sizeof values[0];
    const size_t i = (size_t)index % (np + nv);
    return (i < np) ? fz_float_bits(patterns[i]) : values[i - np];
}

float fz_float(fz_reader_t *r, float lo, float hi)
{
    const uint8_t tag = fz_u8(r) & 7u;
    if (tag <= 2u) { return fz_float_bits(fz_u32(r)); }
    if (tag <= 5u) { return lo + (hi - lo) * ((float)fz_u16(r) / 65535.0f); }
    if (tag == 6u) { return special_value(fz_u8(r)); }
    switch (fz_u8(r) % 6u) {
    case 0: return lo;
    case 1: return hi;
    case 2: return nextafterf(lo, -INFINITY);
    case 3: return nextafterf(lo, INFINITY);
    case 4: return nextafterf(hi, -INFINITY);
    default: return nextafterf(hi, INFINITY);
    }
}

void fz_fail(const char *harness_file, int line, const char *condition, const char *fmt, ...)
{
    fprintf(stderr, "\n==== ORACLE VIOLATION (%s:%d): %s\n", harness_file, line, condition);
    fprintf(stderr, "     ");
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n     in %s (operation %u of the input)", fz_ctx.call ? fz_ctx.call : "?", fz_ctx.step);
    for (int i = 0; i < fz_ctx.nargs; ++i) {
        fprintf(stderr, "%s%.9g [%a]", (i == 0) ? "\n     arguments: " : ", ", (double)fz_ctx.args[i],
                (double)fz_ctx.args[i]);
    }
    if ((fz_ctx.iargs[0] != 0) || (fz_ctx.iargs[1] != 0)) {
        fprintf(stderr, "\n     integer arguments: %ld, %ld", fz_ctx.iargs[0], fz_ctx.iargs[1]);
    }
    fprintf(stderr, "\n");
    fflush(stderr);
    abort();
}

void wc_fuzz_contract_failed(const char *condition, const char *file, int line)
{
    fprintf(stderr, "\n==== WC_ASSERT FAILED (API contract) at %s:%d: %s\n", file, line, condition);
    fflush(stderr);
    abort();
}

bool fz_env_flag(const char *name)
{
    const char *v = getenv(name);
    return (v != NULL) && (v[0] != '\0') && (strcmp(v, "0") != 0);
}
