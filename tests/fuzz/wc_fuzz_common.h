/* Shared by the libFuzzer harnesses of tests/fuzz: a byte reader that never
 * fails (an exhausted input reads as zeros), the float decoder that turns
 * fuzz bytes into raw bit patterns, in-range values, boundary values and
 * special values, and the oracle (FZ_CHECK: print what was violated, the call
 * being checked and its arguments, then abort so that libFuzzer saves the
 * input as a crash). */
#ifndef WC_FUZZ_COMMON_H
#define WC_FUZZ_COMMON_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ------------------------------------------------------------------------ */
/* Reader                                                                    */
/* ------------------------------------------------------------------------ */

typedef struct {
    const uint8_t *data;
    size_t size;
    size_t pos;
} fz_reader_t;

static inline void fz_reader_init(fz_reader_t *r, const uint8_t *data, size_t size)
{
    r->data = data;
    r->size = size;
    r->pos = 0u;
}

static inline bool fz_more(const fz_reader_t *r) { return r->pos < r->size; }

/* The reader's bounds check compares a position with the input's length, never a fuzz byte's value: no
 * coverage instrumentation here (its comparison hooks were 4 % of fuzz_loop's time; ASan and UBSan stay). Kept
 * out of line so that the callers' instrumentation does not take the body back. */
#if defined(__clang__)
#define FZ_NO_COVERAGE __attribute__((no_sanitize("coverage"), noinline))
#else
#define FZ_NO_COVERAGE
#endif
FZ_NO_COVERAGE static inline uint8_t fz_u8(fz_reader_t *r) { return fz_more(r) ? r->data[r->pos++] : 0u; }

static inline uint16_t fz_u16(fz_reader_t *r)
{
    const uint16_t lo = fz_u8(r);
    return (uint16_t)(lo | (uint16_t)(fz_u8(r) << 8));
}

static inline uint32_t fz_u32(fz_reader_t *r)
{
    const uint32_t lo = fz_u16(r);
    return lo | ((uint32_t)fz_u16(r) << 16);
}

/* A float from its IEEE-754 bit pattern: any NaN payload, +-Inf, denormals. */
float fz_float_bits(uint32_t bits);
uint32_t fz_bits_of(float x);

/* One float for an argument whose meaningful range is [lo, hi]. A tag byte
 * chooses how the following bytes are read:
 *   0..2  raw bit pattern (4 bytes): NaN, Inf, denormals, huge values
 *   3..5  lo + (hi - lo) u16 / 65535: inside the range
 *   6     a special value (1 byte index): 0, -0, NaN, +-Inf, FLT_MAX, denormals,
 *         the library's limits (slip, theta, force, torque) and their neighbours
 *   7     lo or hi or one ulp beside them (1 byte) */
float fz_float(fz_reader_t *r, float lo, float hi);

/* ------------------------------------------------------------------------ */
/* Oracle                                                                    */
/* ------------------------------------------------------------------------ */

/* The call under check, printed with a violation. */
#define FZ_CTX_ARGS 8
typedef struct {
    const char *call;
    int nargs;
    float args[FZ_CTX_ARGS];
    long iargs[2];
    unsigned step;  /* index of the operation in this input */
} fz_context_t;

extern fz_context_t fz_ctx;

static inline void fz_context(const char *call, unsigned step) { fz_ctx.call = call; fz_ctx.nargs = 0; fz_ctx.step = step; fz_ctx.iargs[0] = fz_ctx.iargs[1] = 0; }
static inline void fz_arg(float x) { if (fz_ctx.nargs < FZ_CTX_ARGS) { fz_ctx.args[fz_ctx.nargs++] = x; } }

/* Print "ORACLE VIOLATION ..." with the context and a formatted detail, abort. */
void fz_fail(const char *harness_file, int line, const char *condition, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((noreturn, format(printf, 4, 5)))
#endif
    ;

#define FZ_CHECK(cond, ...)                                                  \
    do {                                                                     \
        if (!(cond)) { fz_fail(__FILE__, __LINE__, #cond, __VA_ARGS__); }    \
    } while (0)

static inline bool fz_finite(float x) { return isfinite(x) != 0; }

/* Environment switch read once (WC_FUZZ_VERBOSE=1 prints a summary per input;
 * WC_FUZZ_LAX=1 checks the arithmetic helpers only inside their
 * documented domain, see tests/fuzz/README.md). */
bool fz_env_flag(const char *name);

#endif /* WC_FUZZ_COMMON_H */
