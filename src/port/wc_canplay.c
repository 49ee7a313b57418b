/* wc_canplay: canplayer paced by the TCU's answers (DESIGN 5: the emulated
 * guest must never set the pace).
 *
 *   wc_canplay LOG [--iface vcan0] [--pace answer|log] [--answer-id ID|none]
 *              [--loops N] [--answer-timeout S] [--record FILE [--record-id ID]...]
 *              [--window N] [--cpu N] [--stop-pid PID]
 *
 * Plays a candump -L log on a SocketCAN interface (every frame to IFACE,
 * whatever interface the log names). A ClutchSensors frame (standard id, not
 * remote: the frame that steps wc_tcu --clock frame) closes a period, and the
 * next period's frames go out only once the TCU's answer to it (a frame of
 * --answer-id, default VfsCommand, ids from the DBC's generated codec) is on
 * the bus. A guest that runs slower makes the replay slower, never
 * different: no input piles up in the TCU's socket, none times out.
 *   --pace answer   as fast as the answers come (default)
 *   --pace log      and never earlier than the log's timestamps, as canplayer:
 *                   for a tool beside the TCU that expects at most the
 *                   control step's rate (XCP DAQ at the 1 ms event)
 *   --answer-id none  canplayer's pace only (the timer clock steps on its own)
 *   --window N      up to N periods sent ahead of the last answer (default 1:
 *                   strict lockstep). The TCU steps on each ClutchSensors frame
 *                   in the order received, so its frames are the same for any N;
 *                   N > 1 lets player and TCU run at once instead of waking each
 *                   other every period (a guest's wake-up latency is most of a
 *                   lockstep period). At most 64: the TCU's socket holds them
 *                   (a few frames a period, its receive buffer some hundreds).
 *   --loops N       play the log N times (0: until SIGINT/SIGTERM); each loop
 *                   starts one millisecond after the previous one's last frame
 *   --record FILE   every frame sent and received, candump -L format, the socket
 *                   bound before the first frame goes out (a candump started
 *                   beside it may not be bound yet in a slow guest); --record-id:
 *                   only these ids (repeatable; default all)
 *   --stop-pid PID  at the end SIGTERM to PID (the TCU) and record until it
 *                   has exited, so its last frames are in the record
 *   --limit-fifo PATH  flow control by a consumer of the TCU's output (the XCP
 *                   master decoding DAQ): each line written to the FIFO is the
 *                   last period the player may step, modulo 65536 (the XCP DAQ
 *                   timestamp's range: one tick a step), or "none"; a consumer
 *                   that falls behind holds the inputs instead of losing frames
 * It keeps to one CPU (--cpu N; default the one it starts on): vcan queues each
 * frame on the sending CPU's backlog, so a player that migrated between CPUs
 * could have two frames of one period delivered out of order (seen with
 * canplayer in the emulated guest); a tool that sends beside it from the same
 * CPU has its frames reach the TCU in the order they were sent.
 * Prints the periods played, the frames recorded and the answers' wait (max,
 * total) on stderr.
 * Exit 0; 1 no answer within --answer-timeout (default 120 s; a stuck or
 * crashed TCU), a send or receive failed; 2 usage, an unreadable or malformed
 * log. Host program (stdio and heap allowed). */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include "wetclutch_can/wc_can.h"

#define MAX_RECORD_IDS 16
#define MAX_WINDOW 64u

typedef struct {
    double t_s;
    struct can_frame frame;
} log_frame_t;

typedef struct {
    const char *log_path;
    const char *iface;
    int pace_log;
    int answer_id;            /* < 0: none */
    unsigned long loops;      /* 0: until a signal */
    double answer_timeout_s;
    const char *record_path;
    uint32_t record_ids[MAX_RECORD_IDS];
    size_t record_id_count;
    long stop_pid;            /* 0: none */
    const char *limit_fifo;   /* NULL: no flow control */
    unsigned long window;     /* periods sent ahead of the last answer, 1..MAX_WINDOW */
    int cpu;                  /* < 0: the one it starts on */
} options_t;

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static double now_s(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void usage(FILE *out)
{
    fprintf(out, "usage: wc_canplay LOG [--iface vcan0] [--pace answer|log] [--answer-id ID|none] [--loops N]\n"
                 "                  [--answer-timeout S] [--record FILE [--record-id ID]...] [--stop-pid PID]\n"
                 "                  [--limit-fifo PATH] [--window N] [--cpu N]\n"
                 "  (the header of src/port/wc_canplay.c says what each does)\n");
}

/* One candump -L line: "(t) iface ID#DATA", "ID#R" remote, an 8-digit id extended. */
static int parse_line(const char *line, log_frame_t *f)
{
    char iface[32];
    char body[80];
    if (sscanf(line, " (%lf) %31s %79s", &f->t_s, iface, body) != 3) { return -1; }
    char *hash = strchr(body, '#');
    if ((hash == NULL) || (hash[1] == '#')) { return -1; }  /* "##": CAN FD, not played */
    *hash = '\0';
    char *end = NULL;
    const size_t id_digits = strlen(body);
    const unsigned long id = strtoul(body, &end, 16);
    if ((end == body) || (*end != '\0') || ((id_digits != 3u) && (id_digits != 8u))) { return -1; }
    memset(&f->frame, 0, sizeof f->frame);
    if (id_digits == 8u) {
        if (id > CAN_EFF_MASK) { return -1; }
        f->frame.can_id = (canid_t)id | CAN_EFF_FLAG;
    } else {
        if (id > CAN_SFF_MASK) { return -1; }
        f->frame.can_id = (canid_t)id;
    }
    const char *data = hash + 1;
    if (data[0] == 'R') {
        f->frame.can_id |= CAN_RTR_FLAG;
        return (data[1] == '\0') ? 0 : -1;
    }
    const size_t digits = strlen(data);
    if (((digits % 2u) != 0u) || (digits > 16u)) { return -1; }
    for (size_t i = 0; i < digits / 2u; ++i) {
        unsigned v = 0u;
        char pair[3] = { data[2u * i], data[2u * i + 1u], '\0' };
        if ((sscanf(pair, "%2x", &v) != 1) || (strspn(pair, "0123456789abcdefABCDEF") != 2u)) { return -1; }
        f->frame.data[i] = (uint8_t)v;
    }
    f->frame.len = (uint8_t)(digits / 2u);
    return 0;
}

/* The whole log in memory (a bench log is a few thousand frames). */
static log_frame_t *read_log(const char *path, size_t *count)
{
    FILE *in = fopen(path, "r");
    if (in == NULL) {
        fprintf(stderr, "wc_canplay: %s: %s\n", path, strerror(errno));
        return NULL;
    }
    size_t cap = 4096, n = 0;
    log_frame_t *frames = malloc(cap * sizeof *frames);
    char line[256];
    unsigned long line_no = 0;
    while ((frames != NULL) && (fgets(line, sizeof line, in) != NULL)) {
        ++line_no;
        if (line[strspn(line, " \t\r\n")] == '\0') { continue; }
        if (n == cap) {
            cap *= 2u;
            log_frame_t *more = realloc(frames, cap * sizeof *frames);
            if (more == NULL) { free(frames); frames = NULL; break; }
            frames = more;
        }
        if (parse_line(line, &frames[n]) != 0) {
            fprintf(stderr, "wc_canplay: %s: line %lu: not a candump -L line of a classic CAN frame\n", path, line_no);
            free(frames);
            fclose(in);
            return NULL;
        }
        if ((n > 0u) && (frames[n].t_s < frames[n - 1u].t_s)) {
            fprintf(stderr, "wc_canplay: %s: line %lu: timestamp earlier than the line before\n", path, line_no);
            free(frames);
            fclose(in);
            return NULL;
        }
        ++n;
    }
    fclose(in);
    if (frames == NULL) {
        fprintf(stderr, "wc_canplay: %s: out of memory\n", path);
        return NULL;
    }
    if (n == 0u) {
        fprintf(stderr, "wc_canplay: %s: no frames\n", path);
        free(frames);
        return NULL;
    }
    *count = n;
    return frames;
}

static int parse_id(const char *text, const char *option, int *id)
{
    char *end = NULL;
    errno = 0;
    const unsigned long v = strtoul(text, &end, 0);
    if ((errno != 0) || (end == text) || (*end != '\0') || (v > CAN_SFF_MASK)) {
        fprintf(stderr, "wc_canplay: %s: '%s' is not a standard CAN id (0x0..0x7FF)\n", option, text);
        return -1;
    }
    *id = (int)v;
    return 0;
}

static int parse_options(int argc, char **argv, options_t *o)
{
    memset(o, 0, sizeof *o);
    o->iface = "vcan0";
    o->answer_id = (int)WC_CAN_VFS_COMMAND_FRAME_ID;
    o->loops = 1u;
    o->answer_timeout_s = 120.0;
    o->window = 1u;
    o->cpu = -1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        char *end = NULL;
        if ((strcmp(a, "-h") == 0) || (strcmp(a, "--help") == 0)) { usage(stdout); exit(0); }
        if ((a[0] != '-') && (o->log_path == NULL)) { o->log_path = a; continue; }
        if (v == NULL) { fprintf(stderr, "wc_canplay: %s needs a value\n", a); return -1; }
        ++i;
        if (strcmp(a, "--iface") == 0) {
            if (strlen(v) >= IFNAMSIZ) { fprintf(stderr, "wc_canplay: --iface: name too long\n"); return -1; }
            o->iface = v;
        } else if (strcmp(a, "--pace") == 0) {
            if ((strcmp(v, "answer") != 0) && (strcmp(v, "log") != 0)) {
                fprintf(stderr, "wc_canplay: --pace: 'answer' or 'log', not '%s'\n", v);
                return -1;
            }
            o->pace_log = strcmp(v, "log") == 0;
        } else if (strcmp(a, "--answer-id") == 0) {
            if (strcmp(v, "none") == 0) { o->answer_id = -1; }
            else if (parse_id(v, a, &o->answer_id) != 0) { return -1; }
        } else if (strcmp(a, "--record-id") == 0) {
            int id = 0;
            if ((o->record_id_count == MAX_RECORD_IDS) || (parse_id(v, a, &id) != 0)) {
                fprintf(stderr, "wc_canplay: --record-id: at most %d standard ids\n", MAX_RECORD_IDS);
                return -1;
            }
            o->record_ids[o->record_id_count++] = (uint32_t)id;
        } else if (strcmp(a, "--loops") == 0) {
            errno = 0;
            o->loops = strtoul(v, &end, 10);
            if ((errno != 0) || (end == v) || (*end != '\0') || (v[0] == '-')) {
                fprintf(stderr, "wc_canplay: --loops: '%s' is not a count\n", v);
                return -1;
            }
        } else if (strcmp(a, "--cpu") == 0) {
            errno = 0;
            const long cpu = strtol(v, &end, 10);
            if ((errno != 0) || (end == v) || (*end != '\0') || (cpu < 0) || (cpu >= CPU_SETSIZE)) {
                fprintf(stderr, "wc_canplay: --cpu: '%s' is not a CPU number\n", v);
                return -1;
            }
            o->cpu = (int)cpu;
        } else if (strcmp(a, "--window") == 0) {
            errno = 0;
            o->window = strtoul(v, &end, 10);
            if ((errno != 0) || (end == v) || (*end != '\0') || (v[0] == '-') || (o->window < 1u) ||
                (o->window > MAX_WINDOW)) {
                fprintf(stderr, "wc_canplay: --window: '%s' is not a number of periods in 1..%u\n", v, MAX_WINDOW);
                return -1;
            }
        } else if (strcmp(a, "--answer-timeout") == 0) {
            o->answer_timeout_s = strtod(v, &end);
            if ((end == v) || (*end != '\0') || !(o->answer_timeout_s > 0.0 && o->answer_timeout_s <= 86400.0)) {
                fprintf(stderr, "wc_canplay: --answer-timeout: '%s' is not a number of seconds in (0, 86400]\n", v);
                return -1;
            }
        } else if (strcmp(a, "--limit-fifo") == 0) {
            o->limit_fifo = v;
        } else if (strcmp(a, "--record") == 0) {
            o->record_path = v;
        } else if (strcmp(a, "--stop-pid") == 0) {
            errno = 0;
            o->stop_pid = strtol(v, &end, 10);
            if ((errno != 0) || (end == v) || (*end != '\0') || (o->stop_pid <= 0)) {
                fprintf(stderr, "wc_canplay: --stop-pid: '%s' is not a process id\n", v);
                return -1;
            }
        } else {
            fprintf(stderr, "wc_canplay: unknown option '%s'\n", a);
            return -1;
        }
    }
    if (o->log_path == NULL) {
        fprintf(stderr, "wc_canplay: no log given\n");
        return -1;
    }
    return 0;
}

static int open_socket(const options_t *o)
{
    const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        fprintf(stderr, "wc_canplay: socket(PF_CAN): %s%s\n", strerror(errno),
                (errno == EAFNOSUPPORT) ? " (no CAN in this kernel: run it through hil/vcan_run.sh)" : "");
        return -1;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", o->iface);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        fprintf(stderr, "wc_canplay: %s: %s (create it: modprobe vcan && ip link add dev %s type vcan &&"
                        " ip link set up %s)\n", o->iface, strerror(errno), o->iface, o->iface);
        (void)close(fd);
        return -1;
    }
    /* What this socket receives: the answers, and what is recorded (default: everything). */
    if ((o->record_path == NULL) || (o->record_id_count > 0u)) {
        struct can_filter filters[MAX_RECORD_IDS + 1];
        size_t n = 0;
        if (o->answer_id >= 0) { filters[n++] = (struct can_filter){ (canid_t)o->answer_id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG }; }
        for (size_t i = 0; (o->record_path != NULL) && (i < o->record_id_count); ++i) {
            filters[n++] = (struct can_filter){ o->record_ids[i], CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG };
        }
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, (n > 0u) ? filters : NULL, (socklen_t)(n * sizeof filters[0])) < 0) {
            fprintf(stderr, "wc_canplay: setsockopt(CAN_RAW_FILTER): %s\n", strerror(errno));
            (void)close(fd);
            return -1;
        }
    }
    const int rcvbuf = 8 << 20;  /* a recording of DAQ traffic must not overflow while a period is sent */
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) < 0) {
        (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        fprintf(stderr, "wc_canplay: bind %s: %s (is it up? ip link set up %s)\n", o->iface, strerror(errno), o->iface);
        (void)close(fd);
        return -1;
    }
    return fd;
}

typedef struct {
    int fd;
    FILE *record;
    const options_t *opt;
    unsigned long long answers;
    unsigned long long recorded;
    int limit_fd;             /* --limit-fifo, -1: none */
    bool limited;
    uint16_t limit;           /* the last period it may step, modulo 65536 */
    char limit_line[32];
    size_t limit_len;
} player_t;

static void record_frame(player_t *p, const struct can_frame *f)
{
    if (p->record == NULL) { return; }
    const canid_t id = f->can_id & ((f->can_id & CAN_EFF_FLAG) ? CAN_EFF_MASK : CAN_SFF_MASK);
    if (p->opt->record_id_count > 0u) {
        bool wanted = false;
        for (size_t i = 0; i < p->opt->record_id_count; ++i) {
            wanted |= ((f->can_id & CAN_EFF_FLAG) == 0u) && (id == p->opt->record_ids[i]);
        }
        if (!wanted) { return; }
    }
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts);
    p->recorded++;
    fprintf(p->record, "(%lld.%06ld) %s ", (long long)ts.tv_sec, ts.tv_nsec / 1000L, p->opt->iface);
    fprintf(p->record, (f->can_id & CAN_EFF_FLAG) ? "%08X#" : "%03X#", (unsigned)id);
    if (f->can_id & CAN_RTR_FLAG) {
        fputc('R', p->record);
    } else {
        for (uint8_t i = 0; (i < f->len) && (i < 8u); ++i) { fprintf(p->record, "%02X", f->data[i]); }
    }
    fputc('\n', p->record);
}

/* Read what has arrived, waiting up to timeout_s (< 0: not at all). Returns 0, or -1 on a receive error. */
static int receive(player_t *p, double timeout_s)
{
    struct pollfd pfd = { .fd = p->fd, .events = POLLIN, .revents = 0 };
    const int ms = (timeout_s <= 0.0) ? 0 : (int)(timeout_s * 1000.0) + 1;
    int ready = poll(&pfd, 1, ms);
    for (int reads = 0; (ready > 0) && (reads < 4096); ++reads) {  /* bounded: a flood cannot hold the player */
        struct can_frame f;
        const ssize_t n = recv(p->fd, &f, sizeof f, MSG_DONTWAIT);
        if (n < 0) {
            if ((errno == EAGAIN) || (errno == EINTR)) { return 0; }
            fprintf(stderr, "wc_canplay: receive on %s: %s\n", p->opt->iface, strerror(errno));
            return -1;
        }
        if ((size_t)n < sizeof f) { continue; }
        record_frame(p, &f);
        if ((p->opt->answer_id >= 0) && ((f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) == 0u) &&
            (f.can_id == (canid_t)p->opt->answer_id)) {
            p->answers++;
        }
    }
    if ((ready < 0) && (errno != EINTR)) {
        fprintf(stderr, "wc_canplay: poll: %s\n", strerror(errno));
        return -1;
    }
    return 0;
}

/* The lines the consumer wrote since the last call: the last one counts. Returns 0, or -1 on a bad line. */
static int read_limit(player_t *p)
{
    char buf[256];
    ssize_t n;
    while ((n = read(p->limit_fd, buf, sizeof buf)) > 0) {
        for (ssize_t i = 0; i < n; ++i) {
            if (buf[i] != '\n') {
                if (p->limit_len + 1u >= sizeof p->limit_line) { p->limit_len = 0; return -1; }
                p->limit_line[p->limit_len++] = buf[i];
                continue;
            }
            p->limit_line[p->limit_len] = '\0';
            p->limit_len = 0;
            char *end = NULL;
            const unsigned long v = strtoul(p->limit_line, &end, 10);
            if (strcmp(p->limit_line, "none") == 0) {
                p->limited = false;
            } else if ((end != p->limit_line) && (*end == '\0') && (v <= 65535u)) {
                p->limited = true;
                p->limit = (uint16_t)v;
            } else {
                fprintf(stderr, "wc_canplay: --limit-fifo: '%s' is neither a period (0..65535) nor 'none'\n",
                        p->limit_line);
                return -1;
            }
        }
    }
    return 0;
}

/* Whether period next is past the consumer's limit (a signed 16-bit difference: the two stay close). */
static bool held(const player_t *p, unsigned long long next)
{
    return p->limited && ((int16_t)(uint16_t)(p->limit - (uint16_t)next) < 0);
}

/* Waits until period next may go (the consumer raised its limit); returns 0, or -1. */
static int await_limit(player_t *p, unsigned long long next)
{
    for (;;) {
        if (read_limit(p) != 0) { return -1; }
        if (!held(p, next) || stop_requested) { return 0; }
        struct pollfd both[2] = { { .fd = p->limit_fd, .events = POLLIN, .revents = 0 },
                                  { .fd = p->fd, .events = POLLIN, .revents = 0 } };
        if ((poll(both, 2, 100) < 0) && (errno != EINTR)) { return -1; }
        if (((both[1].revents & POLLIN) != 0) && (receive(p, -1.0) != 0)) { return -1; }
    }
}


static int send_frame(player_t *p, const struct can_frame *f)
{
    const double give_up_s = now_s() + p->opt->answer_timeout_s;
    for (;;) {
        const ssize_t n = send(p->fd, f, sizeof *f, MSG_DONTWAIT);
        if (n == (ssize_t)sizeof *f) {
            record_frame(p, f);
            return 0;
        }
        if ((n >= 0) || ((errno != ENOBUFS) && (errno != EAGAIN) && (errno != EINTR)) || (now_s() > give_up_s)) {
            fprintf(stderr, "wc_canplay: send on %s: %s\n", p->opt->iface, (n < 0) ? strerror(errno) : "short write");
            return -1;
        }
        if (receive(p, 0.001) != 0) { return -1; }  /* a full queue: let it drain */
    }
}

/* Waits until the answers reach periods; returns the seconds waited, or -1. */
static double await_answers(player_t *p, unsigned long long periods)
{
    const double t0 = now_s();
    while ((p->answers < periods) && !stop_requested) {
        const double waited = now_s() - t0;
        if (waited > p->opt->answer_timeout_s) {
            fprintf(stderr, "wc_canplay: no answer (id 0x%03X) to period %llu within %g s: is the TCU running on %s,"
                            " with the frame clock?\n", (unsigned)p->opt->answer_id, periods, p->opt->answer_timeout_s,
                    p->opt->iface);
            return -1.0;
        }
        if (receive(p, 0.1) != 0) { return -1.0; }
    }
    return now_s() - t0;
}

/* --stop-pid: SIGTERM, then record until the process has exited (pidfd: also when it is not our child). */
static int stop_and_drain(player_t *p)
{
    if (p->opt->stop_pid > 0) {
        const int pidfd = (int)syscall(SYS_pidfd_open, (pid_t)p->opt->stop_pid, 0);
        if (kill((pid_t)p->opt->stop_pid, SIGTERM) != 0) {
            fprintf(stderr, "wc_canplay: --stop-pid %ld: %s\n", p->opt->stop_pid, strerror(errno));
        } else if (pidfd >= 0) {
            struct pollfd both[2] = { { .fd = pidfd, .events = POLLIN, .revents = 0 },
                                      { .fd = p->fd, .events = POLLIN, .revents = 0 } };
            const double give_up_s = now_s() + p->opt->answer_timeout_s;
            while (((both[0].revents & POLLIN) == 0) && (now_s() < give_up_s)) {
                if (poll(both, 2, 100) < 0 && errno != EINTR) { break; }
                if (receive(p, -1.0) != 0) { break; }
            }
        }
        if (pidfd >= 0) { (void)close(pidfd); }
    }
    return receive(p, -1.0);  /* what is queued: vcan delivers a frame before its send returns */
}

int main(int argc, char **argv)
{
    options_t opt;
    if (parse_options(argc, argv, &opt) != 0) { usage(stderr); return 2; }
    size_t count = 0;
    log_frame_t *frames = read_log(opt.log_path, &count);
    if (frames == NULL) { return 2; }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    const int cpu = (opt.cpu >= 0) ? opt.cpu : sched_getcpu();   /* one CPU: frames in the order sent (the header) */
    if (cpu >= 0) {
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET((size_t)cpu, &one);
        if (sched_setaffinity(0, sizeof one, &one) != 0) {
            fprintf(stderr, "wc_canplay: warning: cannot keep to CPU %d: %s\n", cpu, strerror(errno));
        }
    }
    player_t p = { .fd = -1, .record = NULL, .opt = &opt, .answers = 0u, .recorded = 0u, .limit_fd = -1, .limited = false,
                   .limit = 0u, .limit_line = { 0 }, .limit_len = 0u };
    if (opt.limit_fifo != NULL) {  /* read-write: no end of file while the consumer has not opened it yet */
        p.limit_fd = open(opt.limit_fifo, O_RDWR | O_NONBLOCK);
        if (p.limit_fd < 0) {
            fprintf(stderr, "wc_canplay: --limit-fifo %s: %s (make it with mkfifo)\n", opt.limit_fifo, strerror(errno));
            free(frames);
            return 2;
        }
    }
    if (opt.record_path != NULL) {
        p.record = fopen(opt.record_path, "w");
        if (p.record == NULL) {
            fprintf(stderr, "wc_canplay: --record %s: %s\n", opt.record_path, strerror(errno));
            free(frames);
            return 2;
        }
        (void)setvbuf(p.record, NULL, _IOFBF, 1 << 20);
    }
    p.fd = open_socket(&opt);
    int rc = (p.fd < 0) ? 1 : 0;
    const double span_s = frames[count - 1u].t_s - frames[0].t_s + 1e-3;
    const double start_s = now_s();
    unsigned long long periods = 0u;
    double wait_max_s = 0.0, wait_total_s = 0.0;
    for (unsigned long loop = 0; (rc == 0) && !stop_requested && ((opt.loops == 0u) || (loop < opt.loops)); ++loop) {
        for (size_t i = 0; (rc == 0) && !stop_requested && (i < count); ++i) {
            const struct can_frame *f = &frames[i].frame;
            if (opt.pace_log) {  /* not before the log's time (the answers may make it later) */
                const double due_s = start_s + (double)loop * span_s + (frames[i].t_s - frames[0].t_s);
                while (!stop_requested && (now_s() < due_s)) {
                    if (receive(&p, due_s - now_s()) != 0) { rc = 1; }
                    if (rc != 0) { break; }
                }
            }
            const bool steps = (f->can_id == WC_CAN_CLUTCH_SENSORS_FRAME_ID);  /* standard, not remote */
            if ((rc == 0) && steps && (p.limit_fd >= 0) && (await_limit(&p, periods + 1u) != 0)) { rc = 1; }
            if ((rc == 0) && !stop_requested && (send_frame(&p, f) != 0)) { rc = 1; }
            if ((rc == 0) && steps && (opt.answer_id >= 0)) {
                ++periods;   /* this period's answer, or the one opt.window - 1 periods back */
                const double waited_s = await_answers(&p, (periods >= opt.window) ? periods - opt.window + 1u : 0u);
                if (waited_s < 0.0) { rc = 1; break; }
                wait_total_s += waited_s;
                if (waited_s > wait_max_s) { wait_max_s = waited_s; }
            } else if (steps) {
                ++periods;
                if (receive(&p, -1.0) != 0) { rc = 1; }
            }
        }
    }
    if ((rc == 0) && !stop_requested && (opt.answer_id >= 0) && (opt.window > 1u) && (await_answers(&p, periods) < 0.0)) {
        rc = 1;   /* the answers to the last window */
    }
    if ((p.fd >= 0) && (stop_and_drain(&p) != 0) && (rc == 0)) { rc = 1; }
    fprintf(stderr, "wc_canplay: %llu periods in %.1f s, %llu answers, %llu frames recorded; answer wait max %.1f ms,"
                    " total %.1f s%s\n", periods, now_s() - start_s, p.answers, p.recorded, wait_max_s * 1e3, wait_total_s,
            stop_requested ? " (stopped by a signal)" : "");
    if (p.record != NULL && fclose(p.record) != 0) {
        fprintf(stderr, "wc_canplay: --record %s: %s\n", opt.record_path, strerror(errno));
        rc = 1;
    }
    if (p.fd >= 0) { (void)close(p.fd); }
    if (p.limit_fd >= 0) { (void)close(p.limit_fd); }
    free(frames);
    return rc;
}
