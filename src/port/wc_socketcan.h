/* Linux SocketCAN port: a raw CAN socket bound to one interface, with a
 * kernel receive filter. Every call reports failures as a message a user
 * can act on (how to create a missing vcan, what to do without AF_CAN). */
#ifndef WC_SOCKETCAN_H
#define WC_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_can_frame.h"

typedef struct {
    int fd;
    uint32_t rx_dropped;  /* frames the kernel dropped before we read them (SO_RXQ_OVFL) */
    uint32_t bus_errors;  /* CAN error frames received (error passive, bus-off, controller, ...) */
    bool bus_off;         /* the last error frame said bus-off (cleared by a restart frame) */
    char iface[16];       /* IFNAMSIZ on Linux */
    uint32_t filter_ids[16];
    size_t filter_count;
    char error[256];      /* last error, human readable */
} wc_socketcan_t;

/* wc_socketcan_receive results. */
#define WC_SOCKETCAN_FRAME 1          /* a data, remote or malformed frame in *frame */
#define WC_SOCKETCAN_NONE 0           /* timeout or signal */
#define WC_SOCKETCAN_BUS_ERROR 2      /* a CAN error frame: counted in bus_errors, nothing in *frame */
#define WC_SOCKETCAN_DOWN (-2)        /* the interface went down or away: reopen later */
#define WC_SOCKETCAN_WAKE 3           /* wake_fd became readable (the caller's timer): nothing read from CAN */
#define WC_SOCKETCAN_FAILED (-1)      /* any other error */

/* Open and bind; filter_ids (count entries, standard 11-bit ids) become the
 * kernel receive filter; CAN error frames (bus-off, error passive,
 * controller problems, transmit timeouts, restarts) are received too
 * (CAN_RAW_ERR_FILTER). Returns 0, or -1 with port->error set. */
int wc_socketcan_open(wc_socketcan_t *port, const char *iface, const uint32_t *filter_ids, size_t count);

/* Wait up to timeout_us (< 0: forever) for one frame: WC_SOCKETCAN_FRAME
 * (remote and extended frames are returned with their flags so the loop can
 * reject and count them), WC_SOCKETCAN_NONE, WC_SOCKETCAN_BUS_ERROR (an error
 * frame: bus_errors and bus_off updated), WC_SOCKETCAN_DOWN (ENETDOWN,
 * ENODEV, ENXIO: the interface went down; wc_socketcan_reopen later) or
 * WC_SOCKETCAN_FAILED, with port->error set for the last two. wake_fd >= 0
 * (e.g. a timerfd) is polled too: WC_SOCKETCAN_WAKE when it is readable
 * (the caller reads it); a pending frame is returned first. */
int wc_socketcan_receive(wc_socketcan_t *port, wc_can_frame_t *frame, int64_t timeout_us, int wake_fd);

/* Send one frame without blocking (a full transmit queue at bus-off must not
 * stall the loop). Returns 0, or -1 with port->error set: the caller counts
 * it as a dropped output frame. */
int wc_socketcan_send(wc_socketcan_t *port, const wc_can_frame_t *frame);

/* Close and open again with the same interface and filters (after
 * WC_SOCKETCAN_DOWN). Returns 0, or -1 with port->error set (still down). */
int wc_socketcan_reopen(wc_socketcan_t *port);

void wc_socketcan_close(wc_socketcan_t *port);

#endif /* WC_SOCKETCAN_H */
