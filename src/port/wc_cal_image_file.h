/* Host side of the images (wc_cal_image.h, wc_gearbox_image.h): an image
 * file read once at start, for wc_tcu and wc_replay (--calibration-image
 * FILE, --element-image FILE, --gearbox-image FILE). Not portable core:
 * POSIX stdio. */
#ifndef WC_CAL_IMAGE_FILE_H
#define WC_CAL_IMAGE_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_cal_image.h"
#include "wetclutch_can/wc_gearbox_image.h"

/* The longest image file read (the bytes after the image's CRC are ignored,
 * as the rest of a flash sector). */
#define WC_CAL_IMAGE_FILE_MAX_BYTES 16384u

/* Reads path into buffer (up to capacity bytes): 0 and *length, or -1 after
 * one line on stderr, "PROGRAM: OPTION PATH: <the OS error>". */
int wc_image_file_read(const char *path, const char *program, const char *option, uint8_t *buffer, size_t capacity,
                       size_t *length);

/* Reads path and loads it into set (wc_cal_image_load). Returns 0 when the
 * image is used; otherwise -1, set zeroed, after one line on stderr,
 * "PROGRAM: OPTION PATH: ..." (option: the one that named the file,
 * "--calibration-image", "--element-image", ...) naming the OS error or the
 * image's result and field ("BAD_SHIFT (shift.kp_Nm_per_rad_s)"). */
int wc_cal_image_file_load(const char *path, const char *program, const char *option, wc_cal_set_t *set);

/* The same for a gearbox image (wc_gearbox_image_load; --gearbox-image):
 * 0, or -1 with gearbox zeroed after one line naming the OS error or the
 * result and field ("BAD_FIELD (gearbox.shift.oncoming)"). */
int wc_gearbox_image_file_load(const char *path, const char *program, wc_gearbox_t *gearbox);

#endif /* WC_CAL_IMAGE_FILE_H */
