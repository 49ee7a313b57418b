/* The adaptation image's fuzz input (fuzz_adapt_image.c): an extra
 * interpretation of fuzz_calibration's input, not a harness of its own (see
 * README.md: a fourth fuzzer would add a minute to scripts/test.sh). */
#ifndef FUZZ_ADAPT_IMAGE_H
#define FUZZ_ADAPT_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Marks an input as an adaptation image: byte 0 with this bit set. */
#define FZ_ADAPT_IMAGE_INPUT 0x80u

/* One input (data[0] & FZ_ADAPT_IMAGE_INPUT: the rest is read here). */
void fz_adapt_image_input(const uint8_t *data, size_t size, bool verbose);

/* Inputs read so far, and images the load accepted. */
void fz_adapt_image_counts(unsigned long *inputs, unsigned long *loaded);

#endif /* FUZZ_ADAPT_IMAGE_H */
