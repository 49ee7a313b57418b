/* The gearbox image's fuzz input (fuzz_gearbox_image.c): an extra
 * interpretation of fuzz_calibration's input, as the adaptation image's (a
 * harness of its own would add a minute to scripts/test.sh, README.md). */
#ifndef FUZZ_GEARBOX_IMAGE_H
#define FUZZ_GEARBOX_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Marks an input as a gearbox image: byte 0 with both bits set (bit 7 alone: an adaptation image). */
#define FZ_GEARBOX_IMAGE_INPUT 0xC0u

/* One input ((data[0] & FZ_GEARBOX_IMAGE_INPUT) == FZ_GEARBOX_IMAGE_INPUT: the rest is read here). */
void fz_gearbox_image_input(const uint8_t *data, size_t size, bool verbose);

/* Inputs read so far, and images the load accepted. */
void fz_gearbox_image_counts(unsigned long *inputs, unsigned long *loaded);

#endif /* FUZZ_GEARBOX_IMAGE_H */
