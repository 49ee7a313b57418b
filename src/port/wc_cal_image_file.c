/* Image files (wc_cal_image_file.h). */
#include "wc_cal_image_file.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

int wc_image_file_read(const char *path, const char *program, const char *option, uint8_t *buffer, size_t capacity,
                       size_t *length)
{
    *length = 0u;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: %s %s: %s\n", program, option, path, strerror(errno));
        return -1;
    }
    const size_t n = fread(buffer, 1u, capacity, f);
    const int failed = ferror(f);
    const int saved = errno;
    fclose(f);
    if (failed) {
        fprintf(stderr, "%s: %s %s: %s\n", program, option, path, strerror(saved));
        return -1;
    }
    *length = n;
    return 0;
}

/* "NAME (FIELD)" or "NAME" when the status names no field. */
static void refused(const char *program, const char *option, const char *path, const char *result, const char *field,
                    size_t length)
{
    fprintf(stderr, "%s: %s %s: refused: %s%s%s%s (%zu bytes); not started\n", program, option, path, result,
            (field[0] != '\0') ? " (" : "", field, (field[0] != '\0') ? ")" : "", length);
}

int wc_cal_image_file_load(const char *path, const char *program, const char *option, wc_cal_set_t *set)
{
    static uint8_t image[WC_CAL_IMAGE_FILE_MAX_BYTES];
    size_t length = 0u;
    if (wc_image_file_read(path, program, option, image, sizeof image, &length) != 0) {
        (void)wc_cal_image_load(NULL, 0u, set);
        return -1;
    }
    const wc_cal_image_status_t status = wc_cal_image_load(image, length, set);
    if (status.result != (uint32_t)WC_CAL_IMAGE_OK) {
        refused(program, option, path, wc_cal_image_result_name(status.result),
                wc_cal_image_error_name(status), length);
        return -1;
    }
    return 0;
}

int wc_gearbox_image_file_load(const char *path, const char *program, wc_gearbox_t *gearbox)
{
    static uint8_t image[WC_CAL_IMAGE_FILE_MAX_BYTES];
    size_t length = 0u;
    if (wc_image_file_read(path, program, "--gearbox-image", image, sizeof image, &length) != 0) {
        (void)wc_gearbox_image_load(NULL, 0u, gearbox);
        return -1;
    }
    const wc_gearbox_image_status_t status = wc_gearbox_image_load(image, length, gearbox);
    if (status.result != (uint32_t)WC_GEARBOX_IMAGE_OK) {
        refused(program, "--gearbox-image", path, wc_gearbox_image_result_name(status.result),
                wc_gearbox_image_error_name(status), length);
        return -1;
    }
    return 0;
}
