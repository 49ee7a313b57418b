#define _GNU_SOURCE
#include "wc_socketcan.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#define WC_SOCKETCAN_MAX_FILTERS 16u

static int fail(wc_socketcan_t *port, const char *what, int err, const char *hint)
{
    (void)snprintf(port->error, sizeof port->error, "%s: %s%s%s", what, strerror(err), hint[0] ? "; " : "", hint);
    return -1;
}

int wc_socketcan_open(wc_socketcan_t *port, const char *iface, const uint32_t *filter_ids, size_t count)
{
    port->fd = -1;
    port->rx_dropped = 0;
    port->bus_errors = 0;
    port->bus_off = false;
    port->error[0] = '\0';
    if ((strlen(iface) >= IFNAMSIZ) || (strlen(iface) >= sizeof port->iface)) {
        return fail(port, "interface name too long", ENAMETOOLONG, "");
    }
    if (count > WC_SOCKETCAN_MAX_FILTERS) {
        return fail(port, "too many receive filters", EINVAL, "");
    }
    (void)snprintf(port->iface, sizeof port->iface, "%s", iface);
    memcpy(port->filter_ids, filter_ids, count * sizeof filter_ids[0]);
    port->filter_count = count;
    return wc_socketcan_reopen(port);
}

int wc_socketcan_reopen(wc_socketcan_t *port)
{
    wc_socketcan_close(port);
    const char *iface = port->iface;
    const uint32_t *filter_ids = port->filter_ids;
    const size_t count = port->filter_count;
    const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        const int err = errno;
        return fail(port, "socket(PF_CAN, SOCK_RAW, CAN_RAW)", err,
                    (err == EAFNOSUPPORT)
                        ? "this kernel has no CAN support (CONFIG_CAN); run inside the VM: bash hil/vcan_run.sh -- <command>"
                        : "");
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", iface);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        const int err = errno;
        char hint[200];
        (void)snprintf(hint, sizeof hint,
                       "create it: modprobe vcan && ip link add dev %s type vcan && ip link set up %s", iface, iface);
        (void)close(fd);
        return fail(port, iface, err, hint);
    }
    struct can_filter filters[WC_SOCKETCAN_MAX_FILTERS];
    for (size_t i = 0; i < count; ++i) {
        filters[i].can_id = filter_ids[i] & CAN_SFF_MASK;
        filters[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters, (socklen_t)(count * sizeof filters[0])) < 0) {
        const int err = errno;
        (void)close(fd);
        return fail(port, "setsockopt(CAN_RAW_FILTER)", err, "");
    }
    /* Error frames: every class the controller reports, so that bus-off and
     * error passive are seen (they arrive with CAN_ERR_FLAG set). */
    const can_err_mask_t err_mask = CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_PROT |
                                    CAN_ERR_TRX | CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_BUSERROR | CAN_ERR_RESTARTED;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) < 0) {
        const int err = errno;
        (void)close(fd);
        return fail(port, "setsockopt(CAN_RAW_ERR_FILTER)", err, "");
    }
    /* Ask for the kernel's drop counter with every frame, so no loss goes unseen,
     * and a receive buffer large enough for bursts of a replayed log. */
    const int one = 1;
    const int rcvbuf = 1 << 20;
    if (setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) < 0) {
        const int err = errno;
        (void)close(fd);
        return fail(port, "setsockopt(SO_RXQ_OVFL)", err, "");
    }
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) < 0) {
        (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);  /* not root: best effort */
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        const int err = errno;
        (void)close(fd);
        return fail(port, "bind", err, "is the interface up? ip link set up <iface>");
    }
    port->fd = fd;
    return 0;
}

int wc_socketcan_receive(wc_socketcan_t *port, wc_can_frame_t *frame, int64_t timeout_us, int wake_fd)
{
    struct pollfd pfds[2] = { { .fd = port->fd, .events = POLLIN, .revents = 0 },
                              { .fd = wake_fd, .events = POLLIN, .revents = 0 } };  /* fd < 0: ignored */
    struct pollfd *pfd = &pfds[0];
    struct timespec timeout = { .tv_sec = (time_t)(timeout_us / 1000000), .tv_nsec = (long)(timeout_us % 1000000) * 1000L };
    const int ready = ppoll(pfds, 2, (timeout_us < 0) ? NULL : &timeout, NULL);  /* ns resolution, unlike poll */
    if (ready < 0) {
        if (errno == EINTR) { return WC_SOCKETCAN_NONE; }
        (void)fail(port, "poll", errno, "");
        return WC_SOCKETCAN_FAILED;
    }
    if (ready == 0) { return WC_SOCKETCAN_NONE; }
    if ((pfd->revents & (POLLIN | POLLERR)) == 0) {
        return ((pfds[1].revents & POLLIN) != 0) ? WC_SOCKETCAN_WAKE : WC_SOCKETCAN_NONE;
    }
    struct can_frame raw;
    char control[CMSG_SPACE(sizeof(uint32_t))];
    struct iovec iov = { .iov_base = &raw, .iov_len = sizeof raw };
    struct msghdr msg = { .msg_iov = &iov, .msg_iovlen = 1, .msg_control = control, .msg_controllen = sizeof control };
    const ssize_t n = recvmsg(port->fd, &msg, 0);
    if (n < 0) {
        const int err = errno;
        if ((err == EINTR) || (err == EAGAIN)) { return WC_SOCKETCAN_NONE; }
        (void)fail(port, "read", err, ((err == ENETDOWN) || (err == ENODEV) || (err == ENXIO))
                                          ? "interface down: the loop keeps its safe state and reopens" : "");
        return ((err == ENETDOWN) || (err == ENODEV) || (err == ENXIO)) ? WC_SOCKETCAN_DOWN : WC_SOCKETCAN_FAILED;
    }
    for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c)) {
        if ((c->cmsg_level == SOL_SOCKET) && (c->cmsg_type == SO_RXQ_OVFL)) {
            memcpy(&port->rx_dropped, CMSG_DATA(c), sizeof port->rx_dropped);  /* cumulative */
        }
    }
    if ((size_t)n >= sizeof raw && (raw.can_id & CAN_ERR_FLAG) != 0u) {
        port->bus_errors++;
        if ((raw.can_id & CAN_ERR_BUSOFF) != 0u) { port->bus_off = true; }
        if ((raw.can_id & CAN_ERR_RESTARTED) != 0u) { port->bus_off = false; }
        return WC_SOCKETCAN_BUS_ERROR;
    }
    memset(frame, 0, sizeof *frame);
    if ((size_t)n < sizeof raw) {  /* never from a CAN_RAW socket, but never trust a length */
        frame->dlc = 0;
        frame->flags = WC_CAN_FLAG_ERROR;
        return 1;
    }
    frame->flags = (uint8_t)(((raw.can_id & CAN_EFF_FLAG) ? WC_CAN_FLAG_EXTENDED : 0u) |
                             ((raw.can_id & CAN_RTR_FLAG) ? WC_CAN_FLAG_REMOTE : 0u) |
                             ((raw.can_id & CAN_ERR_FLAG) ? WC_CAN_FLAG_ERROR : 0u));
    frame->id = raw.can_id & ((raw.can_id & CAN_EFF_FLAG) ? CAN_EFF_MASK : CAN_SFF_MASK);
    frame->dlc = (raw.len <= 8u) ? raw.len : 8u;
    memcpy(frame->data, raw.data, frame->dlc);
    return 1;
}

int wc_socketcan_send(wc_socketcan_t *port, const wc_can_frame_t *frame)
{
    struct can_frame raw;
    memset(&raw, 0, sizeof raw);
    raw.can_id = frame->id & CAN_SFF_MASK;
    raw.len = (frame->dlc <= 8u) ? frame->dlc : 8u;
    memcpy(raw.data, frame->data, raw.len);
    const ssize_t n = send(port->fd, &raw, sizeof raw, MSG_DONTWAIT);  /* never block the loop */
    if (n != (ssize_t)sizeof raw) {
        const int err = (n < 0) ? errno : EIO;
        return fail(port, "send", err, ((err == ENOBUFS) || (err == EAGAIN)) ? "transmit queue full" : "");
    }
    return 0;
}

void wc_socketcan_close(wc_socketcan_t *port)
{
    if (port->fd >= 0) {
        (void)close(port->fd);
        port->fd = -1;
    }
}
