/* Table-driven range check of a calibration struct's scalar fields (the
 * clutch's wc_calibration_check and wc_shift_calibration_check): one pair of
 * bounds and one flag byte per field, the fields 4-byte floats or uint32_t
 * from the start of the struct in declaration order, so that field i fails
 * with the i-th error code (each table static_asserts its fields' offsets
 * against their codes). One loop instead of a compare-and-branch per field:
 * about 9 bytes of flash per field instead of 25 to 35 on a Cortex-M4F. */
#ifndef WC_FIELD_RANGES_H
#define WC_FIELD_RANGES_H

#include <stdint.h>

typedef struct {
    float low;
    float high;  /* inclusive */
} wc_field_range_t;

/* Flags of a field (or-ed). Without any: low <= x <= high. */
#define WC_FIELD_LOW_OPEN 1u      /* low < x <= high */
#define WC_FIELD_INTEGER 2u       /* a uint32_t, compared as a float (exact for the integer bounds used) */
#define WC_FIELD_OR_ZERO 4u       /* 0 (off) is accepted as well */
#define WC_FIELD_LOW_PREVIOUS 8u  /* the low bound is the previous field's value (checked before it) */

#define WC_FIELD_MAX_COUNT 64u

typedef struct {
    const wc_field_range_t *range;  /* per field, declaration order */
    const uint8_t *flags;           /* per field, WC_FIELD_* */
    uint32_t count;                 /* fields, <= WC_FIELD_MAX_COUNT */
} wc_field_rules_t;

/* Index of the first field (declaration order) outside its range, or
 * rules->count when every field is within. NaN fails every range. */
uint32_t wc_field_first_invalid(const void *fields, const wc_field_rules_t *rules);

#endif /* WC_FIELD_RANGES_H */
