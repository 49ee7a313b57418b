#define _POSIX_C_SOURCE 200809L
#include "wc_adapt_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "wetclutch/wc_adapt_image.h"

static const char *const load_reason[] = {
    "ok", "missing", "truncated", "bad magic", "bad layout version", "bad length", "bad CRC-32",
    "another clutch's image", "a value outside its band",
};

/* Write all of buffer to fd (short writes retried). */
static int write_all(int fd, const uint8_t *buffer, size_t length)
{
    size_t done = 0u;
    while (done < length) {
        const ssize_t n = write(fd, buffer + done, length - done);
        if (n < 0) {
            if (errno == EINTR) { continue; }
            return -1;
        }
        done += (size_t)n;
    }
    return 0;
}

/* A failed write: reported with the step and errno, the temporary removed, the old image kept. */
static void store_failed(wc_adapt_file_t *file, const char *tmp, const char *step, int error)
{
    if (tmp != NULL) { (void)unlink(tmp); }
    file->failures++;
    fprintf(stderr, "%s: adaptation image %s not written (%s: %s); the previous image is kept\n", file->program,
            file->path, step, strerror(error));
}

/* DESIGN 12: the image written to PATH.tmp, synced, renamed over PATH: a crash
 * or a full disk leaves the old image or the new one, never half of one. */
static void store(const wc_adapt_t *adapt, void *context)
{
    wc_adapt_file_t *file = context;
    uint8_t image[WC_ADAPT_IMAGE_BYTES];
    char tmp[4096];
    const int n = snprintf(tmp, sizeof tmp, "%s.tmp", file->path);
    if ((n <= 0) || ((size_t)n >= sizeof tmp) || (wc_adapt_image_write(adapt, 0u, image, sizeof image) != sizeof image)) {
        store_failed(file, NULL, "path too long", ENAMETOOLONG);
        return;
    }
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        store_failed(file, NULL, "open", errno);
        return;
    }
    if (write_all(fd, image, sizeof image) != 0) {
        const int error = errno;
        (void)close(fd);
        store_failed(file, tmp, "write", error);
        return;
    }
    if (fsync(fd) != 0) {
        const int error = errno;
        (void)close(fd);
        store_failed(file, tmp, "fsync", error);
        return;
    }
    if (close(fd) != 0) {
        store_failed(file, tmp, "close", errno);
        return;
    }
    if (rename(tmp, file->path) != 0) {
        store_failed(file, tmp, "rename", errno);
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
