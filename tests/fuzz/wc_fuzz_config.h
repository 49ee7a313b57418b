/* WC_CONFIG_HEADER of the fuzz build (tests/fuzz/CMakeLists.txt passes
 * -DWC_CONFIG_HEADER="wc_fuzz_config.h" to the libraries and the harnesses).
 *
 * The harnesses never violate an API contract (no NULL, every instance
 * initialised), so a WC_ASSERT that fires is a finding: it reports the
 * condition and aborts, and libFuzzer saves the input as a crash. Every other
 * setting keeps its default (include/wetclutch/wc_config.h). */
#ifndef WC_FUZZ_CONFIG_H
#define WC_FUZZ_CONFIG_H

/* Defined in tests/fuzz/wc_fuzz_common.c (linked into every harness). */
void wc_fuzz_contract_failed(const char *condition, const char *file, int line);

#define WC_ASSERT(cond)                                            \
    do {                                                           \
        if (!(cond)) { wc_fuzz_contract_failed(#cond, __FILE__, __LINE__); } \
    } while (0)

#endif /* WC_FUZZ_CONFIG_H */
