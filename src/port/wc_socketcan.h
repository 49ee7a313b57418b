/* Linux SocketCAN port: a raw CAN socket bound to one interface, with a
 * kernel receive filter. Every call reports failures as a message a user
 * can act on (how to create a missing vcan, what to do without AF_CAN). */
#ifndef WC_SOCKETCAN_H
#define WC_SOCKETCAN_H

#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_can_frame.h"

typedef struct {
    int fd;
    uint32_t rx_dropped;  /* frames the kernel dropped before we read them (SO_RXQ_OVFL) */
    char error[256];      /* last error, human readable */
} wc_socketcan_t;

/* Open and bind; filter_ids (count entries, standard 11-bit ids) become the
 * kernel receive filter. Returns 0, or -1 with port->error set. */
int wc_socketcan_open(wc_socketcan_t *port, const char *iface, const uint32_t *filter_ids, size_t count);

/* Wait up to timeout_us (< 0: forever) for one frame. Returns 1 with a frame,
 * 0 on timeout or signal, -1 on error. Frames of other types (FD, error,
 * remote) are returned with their flags so the loop can reject and count them. */
int wc_socketcan_receive(wc_socketcan_t *port, wc_can_frame_t *frame, int64_t timeout_us);

/* Send one frame. Returns 0, or -1 with port->error set (ENOBUFS counts as an
 * error: the caller counts it as a dropped output frame). */
int wc_socketcan_send(wc_socketcan_t *port, const wc_can_frame_t *frame);

void wc_socketcan_close(wc_socketcan_t *port);

#endif /* WC_SOCKETCAN_H */
