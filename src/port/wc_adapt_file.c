#define _POSIX_C_SOURCE 200809L
#include "wc_adapt_file.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "wetclutch/wc_adapt_image.h"
#include "wc_atomic_file.h"

static const char *const load_reason[] = {
    "ok", "missing", "truncated", "bad magic", "bad layout version", "bad length", "bad CRC-32",
    "another clutch's image", "a value outside its band",
};

/* DESIGN 12: the image replaces the file atomically (wc_atomic_file.h): a
 * crash or a full disk leaves the old image or the new one, never half of one.
 * A failure is reported with the step and errno, the old image kept. */
static void store(const wc_adapt_t *adapt, void *context)
{
    wc_adapt_file_t *file = context;
    uint8_t image[WC_ADAPT_IMAGE_BYTES];
    const char *step = "encode";
    if ((wc_adapt_image_write(adapt, 0u, image, sizeof image) != sizeof image) ||
        (wc_atomic_file_write(file->path, image, sizeof image, &step) != 0)) {
        const int error = errno;
        file->failures++;
        fprintf(stderr, "%s: adaptation image %s not written (%s: %s); the previous image is kept\n", file->program,
                file->path, step, strerror(error));
        return;
    }
    file->writes++;
}

uint32_t wc_adapt_file_attach(wc_adapt_file_t *file, wc_loop_t *loop)
{
    uint8_t image[WC_ADAPT_IMAGE_BYTES + 1u];  /* one byte more: a longer file is not this image */
    size_t length = 0u;
    FILE *f = fopen(file->path, "rb");
    if (f != NULL) {
        length = fread(image, 1u, sizeof image, f);
        if (ferror(f)) {
            fprintf(stderr, "%s: adaptation image %s: %s\n", file->program, file->path, strerror(errno));
            length = 0u;
        }
        fclose(f);
    } else if (errno != ENOENT) {
        fprintf(stderr, "%s: adaptation image %s: %s\n", file->program, file->path, strerror(errno));
    }
    const uint32_t code = wc_loop_load_adaptation(loop, (f != NULL) ? image : NULL, length);
    if ((code != (uint32_t)WC_IMAGE_OK) && (f != NULL)) {
        const char *why = (code < (uint32_t)(sizeof load_reason / sizeof load_reason[0])) ? load_reason[code] : "invalid";
        fprintf(stderr, "%s: adaptation image %s not used (%s): the calibration's values\n", file->program,
                file->path, why);
    }
    loop->config.adaptation_changed = store;
    loop->config.adaptation_context = file;
    return code;
}
