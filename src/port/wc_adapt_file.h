/* Host-side persistence of a clutch's adaptation image (DESIGN 12) in a file:
 * read once before the loop starts, written atomically (a temporary file in
 * the same directory, fsync, rename) by the loop's adaptation hook whenever a
 * shift changed the learned values or a reset cleared them. Used by wc_tcu
 * and wc_replay (--adaptation-file FILE). Not portable core: POSIX stdio. */
#ifndef WC_ADAPT_FILE_H
#define WC_ADAPT_FILE_H

#include "wetclutch_can/wc_loop.h"

typedef struct {
    const char *path;         /* the image file */
    const char *program;      /* for messages */
    unsigned long writes;     /* images written */
    unsigned long failures;   /* writes that failed (reported on stderr, the old file kept) */
} wc_adapt_file_t;

/* Load path into the loop's adaptation state (after wc_loop_init): a missing
 * file is the calibration's values (WC_ADAPT_STATUS_IMAGE_MISSING), an
 * unreadable, short, corrupt or wrong-version one too (IMAGE_INVALID), each
 * with one line on stderr; then hook the loop's adaptation_changed to write
 * the file. Returns wc_loop_load_adaptation's code. */
uint32_t wc_adapt_file_attach(wc_adapt_file_t *file, wc_loop_t *loop);

#endif /* WC_ADAPT_FILE_H */
