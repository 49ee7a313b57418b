/* A calibration image from a file (wc_cal_image_file.h). */
#include "wc_cal_image_file.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

int wc_cal_image_file_load(const char *path, const char *program, wc_cal_set_t *set)
{
    static uint8_t image[WC_CAL_IMAGE_FILE_MAX_BYTES];
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: --calibration-image %s: %s\n", program, path, strerror(errno));
        (void)wc_cal_image_load(NULL, 0u, set);
        return -1;
    }
    const size_t length = fread(image, 1u, sizeof image, f);
    const int failed = ferror(f);
    const int saved = errno;
    fclose(f);
    if (failed) {
        fprintf(stderr, "%s: --calibration-image %s: %s\n", program, path, strerror(saved));
        (void)wc_cal_image_load(NULL, 0u, set);
        return -1;
    }
    const wc_cal_image_status_t status = wc_cal_image_load(image, length, set);
    if (status.result != (uint32_t)WC_CAL_IMAGE_OK) {
        const char *field = wc_cal_image_error_name(status);
        fprintf(stderr, "%s: --calibration-image %s: refused: %s%s%s%s (%zu bytes); not started\n", program, path,
                wc_cal_image_result_name(status.result), (field[0] != '\0') ? " (" : "", field,
                (field[0] != '\0') ? ")" : "", length);
        return -1;
    }
    return 0;
}
