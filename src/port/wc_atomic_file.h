/* Atomic replacement of a small file on the host (DESIGN 12, 17): the bytes
 * written to PATH.tmp, synced, renamed over PATH, so that a crash or a full
 * disk leaves the old file or the new one, never half of one. Used by the
 * adaptation image (wc_adapt_file.c) and the fault memory (wc_tcu_diag.c).
 * Not portable core: POSIX. */
#ifndef WC_ATOMIC_FILE_H
#define WC_ATOMIC_FILE_H

#include <stddef.h>
#include <stdint.h>

/* Returns 0, or -1 with *step naming the call that failed ("path too long",
 * "open", "write", "fsync", "close", "rename") and errno set; on failure
 * the temporary file is removed and PATH is untouched. */
int wc_atomic_file_write(const char *path, const uint8_t *bytes, size_t length, const char **step);

#endif /* WC_ATOMIC_FILE_H */
