#define _POSIX_C_SOURCE 200809L
#include "wc_atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

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

/* A failed step: the temporary removed (errno kept for the caller). */
static int failed(const char *tmp, const char *what, const char **step)
{
    const int error = errno;
    if (tmp != NULL) { (void)unlink(tmp); }
    *step = what;
    errno = error;
    return -1;
}

int wc_atomic_file_write(const char *path, const uint8_t *bytes, size_t length, const char **step)
{
    char tmp[4096];
    const int n = snprintf(tmp, sizeof tmp, "%s.tmp", path);
    if ((n <= 0) || ((size_t)n >= sizeof tmp)) {
        errno = ENAMETOOLONG;
        return failed(NULL, "path too long", step);
    }
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) { return failed(NULL, "open", step); }
    if (write_all(fd, bytes, length) != 0) {
        const int error = errno;
        (void)close(fd);
        errno = error;
        return failed(tmp, "write", step);
    }
    if (fsync(fd) != 0) {
        const int error = errno;
        (void)close(fd);
        errno = error;
        return failed(tmp, "fsync", step);
    }
    if (close(fd) != 0) { return failed(tmp, "close", step); }
    if (rename(tmp, path) != 0) { return failed(tmp, "rename", step); }
    return 0;
}
