/* Host side of the calibration image (wc_cal_image.h): an image file read
 * once at start, for wc_tcu and wc_replay (--calibration-image FILE). Not
 * portable core: POSIX stdio. */
#ifndef WC_CAL_IMAGE_FILE_H
#define WC_CAL_IMAGE_FILE_H

#include "wetclutch_can/wc_cal_image.h"

/* Reads path (up to WC_CAL_IMAGE_FILE_MAX_BYTES; the bytes after the image's
 * CRC are ignored, as the rest of a flash sector) and loads it into set
 * (wc_cal_image_load). Returns 0 when the image is used; otherwise -1, set
 * zeroed, after one line on stderr, "PROGRAM: --calibration-image PATH: ..."
 * naming the OS error or the image's result and field
 * ("BAD_SHIFT (shift.kp_Nm_per_rad_s)"). */
#define WC_CAL_IMAGE_FILE_MAX_BYTES 16384u
int wc_cal_image_file_load(const char *path, const char *program, wc_cal_set_t *set);

#endif /* WC_CAL_IMAGE_FILE_H */
