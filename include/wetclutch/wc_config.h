/* Build-time settings of the wet-clutch library. Override any of them by
 * defining WC_CONFIG_HEADER="my_config.h" (included first) or -D flags. */
#ifndef WC_CONFIG_H
#define WC_CONFIG_H

#ifdef WC_CONFIG_HEADER
#include WC_CONFIG_HEADER
#endif

/* The integrator's hook for violated API contracts: a NULL pointer, an
 * instance that was never initialised or whose init failed. Never used for bad
 * input data, which is reported through status bits. Default: off (the
 * condition is not evaluated). Route it to the fault handler of the firmware,
 * e.g. in the WC_CONFIG_HEADER:
 *     #define WC_ASSERT(cond) do { if (!(cond)) { tcu_fault(__FILE__, __LINE__); } } while (0)
 * The unit tests route it to cmocka's mock_assert (tests/c/test_contracts.c). */
#ifndef WC_ASSERT
#define WC_ASSERT(cond) ((void)0)
#endif

/* Compile-time check, C99-compatible (C11's _Static_assert where available).
 * name must be a valid identifier, unique in its translation unit. */
#ifndef WC_STATIC_ASSERT
#if defined(__STDC_VERSION__) && (__STDC_VERSION__ >= 201112L)
#define WC_STATIC_ASSERT(cond, name) _Static_assert((cond), #name)
#else
#define WC_STATIC_ASSERT(cond, name) typedef char wc_static_assert_##name[(cond) ? 1 : -1]
#endif
#endif

/* Plausible input ranges; a value outside is rejected as implausible. */
#ifndef WC_SLIP_MAX_rad_s
#define WC_SLIP_MAX_rad_s 1047.2f        /* 10000 rpm */
#endif
#ifndef WC_THETA_MIN_degC
#define WC_THETA_MIN_degC (-40.0f)
#endif
#ifndef WC_THETA_MAX_degC
#define WC_THETA_MAX_degC 250.0f
#endif
/* Thermal envelope (DESIGN section 8): the observer's estimate is kept in
 * [WC_THETA_MIN_degC, WC_THETA_MAX_degC], where the maps are valid; above
 * WC_THETA_OVER_degC the status says over-temperature until the estimate
 * falls below WC_THETA_OVER_degC - WC_THETA_OVER_HYSTERESIS_K. */
#ifndef WC_THETA_OVER_degC
#define WC_THETA_OVER_degC 200.0f
#endif
#ifndef WC_THETA_OVER_HYSTERESIS_K
#define WC_THETA_OVER_HYSTERESIS_K 10.0f
#endif
#ifndef WC_FORCE_MAX_N
#define WC_FORCE_MAX_N 100000.0f
#endif
#ifndef WC_TORQUE_MAX_Nm
#define WC_TORQUE_MAX_Nm 100000.0f
#endif

/* The inverse (wc_inverse.c): Newton steps on the film segment that holds
 * the root stop once a step moves the force by less than half this... */
#ifndef WC_INVERSE_FORCE_TOLERANCE_N
#define WC_INVERSE_FORCE_TOLERANCE_N 0.01f
#endif
/* ...or after this many steps, so the worst case is known at compile time
 * (2 to 3 are typical; a step that would leave the segment bisects it). */
#ifndef WC_INVERSE_MAX_ITERATIONS
#define WC_INVERSE_MAX_ITERATIONS 8u
#endif

/* Keep a helper out of its caller's stack frame (the stack figure is the sum
 * along the deepest call chain). */
#ifndef WC_NOINLINE
#if defined(__GNUC__)
#define WC_NOINLINE __attribute__((noinline))
#else
#define WC_NOINLINE
#endif
#endif

/* Orders memory accesses around the receive ring's index updates
 * (wc_loop_receive in an ISR, wc_loop_step in a task; include/wetclutch_can/
 * wc_loop.h). A compiler barrier is enough on a single-core MCU; a multi-core
 * integration overrides it with a hardware barrier (e.g. __DMB()). */
#ifndef WC_MEMORY_BARRIER
#if defined(__GNUC__)
#define WC_MEMORY_BARRIER() __asm__ volatile("" ::: "memory")
#else
#define WC_MEMORY_BARRIER() ((void)0)
#endif
#endif

/* A small helper on a hot path: always inlined when optimising for speed
 * (-O2: the frame codec folds each signal's constants, bench/arm), left to
 * the compiler when optimising for size (-Os keeps one copy). */
#ifndef WC_INLINE_HOT
#if defined(__GNUC__) && !defined(__OPTIMIZE_SIZE__)
#define WC_INLINE_HOT static inline __attribute__((always_inline))
#else
#define WC_INLINE_HOT static inline
#endif
#endif

/* Longest film table the library accepts (bounds the lookup's search). */
#ifndef WC_FILM_MAX_NODES
#define WC_FILM_MAX_NODES 1024u
#endif

#endif /* WC_CONFIG_H */
