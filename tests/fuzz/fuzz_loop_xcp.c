/* The loop fuzzer's XCP slave (fuzz_loop.h; its records: fuzz_loop.c's input format):
 *
 * XCP (wc_xcp.h, DESIGN 13): a wc_xcp_t beside the loop, started at the
 * input's first XCP frame, its reference page the loop's calibration
 * (wc_cal_set_from + wc_cal_image_encode; a fuzzed loop configuration
 * outside the image's limits: no slave, an XCP record is a port event). As in
 * wc_tcu, every frame of the XcpCommand id goes to wc_xcp_receive (the loop
 * iterates without it) and wc_xcp_step runs after every wc_loop_iterate
 * (control_step = the loop stepped) into its own output array, except after
 * an XCP record with c bit 6 that did not step the loop (its frame waits in
 * the ring: several in a row overflow it). An XCP
 * record (c & 3 == 3, c bit 4; c bit 5: a tick with it) is a selector byte
 * s, then [a format byte as above if s bit 6], then 7 data bytes after the
 * command code: s & 0x1F picks the code from xcp_codes (past its end: the
 * first data byte is the code); s bit 5 "aimed": an address (SET_MTA,
 * SHORT_UPLOAD, WRITE_DAQ) is put inside or just past a region (data byte 4
 * picks it, bytes 5-6 the offset), extension 0; a DOWNLOAD writes 4 bytes,
 * the working page's float at the MTA times 1 + (int8)byte 2 / 128 (so that
 * pages the check accepts, with other values, reach the loop); SET_CAL_PAGE
 * a valid mode and page 0/1; BUILD_CHECKSUM a block of at most 1 KiB. */
#include "fuzz_loop.h"

static wc_xcp_t xcp;    /* the XCP slave beside the loop (~10 KiB) */
static bool xcp_on;     /* wc_xcp_init accepted the loop's calibration as a page */
static bool xcp_tried;  /* wc_xcp_init was tried (at the input's first XCP frame) */
static uint32_t xcp_checks;  /* page checks seen (accepted + rejected): the calibration can change only there */
static wc_cal_set_t xcp_set;
static uint8_t xcp_reference[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
static const wc_xcp_config_t xcp_config = WC_XCP_CONFIG_DEFAULT;
static uint32_t xcp_frames;  /* statistics for WC_FUZZ_VERBOSE */

/* The commands an XCP record picks (s & 0x1F); past the end the frame's first data byte is the code. */
static const uint8_t xcp_codes[] = {
    WC_XCP_CONNECT, WC_XCP_DISCONNECT, WC_XCP_GET_STATUS, WC_XCP_SYNCH, WC_XCP_GET_COMM_MODE_INFO, WC_XCP_GET_ID,
    WC_XCP_SET_MTA, WC_XCP_UPLOAD, WC_XCP_SHORT_UPLOAD, WC_XCP_BUILD_CHECKSUM, WC_XCP_DOWNLOAD, WC_XCP_DOWNLOAD,
    WC_XCP_SET_CAL_PAGE, WC_XCP_GET_CAL_PAGE, WC_XCP_GET_PAG_PROCESSOR_INFO, WC_XCP_COPY_CAL_PAGE,
    WC_XCP_SET_DAQ_PTR, WC_XCP_WRITE_DAQ, WC_XCP_SET_DAQ_LIST_MODE, WC_XCP_START_STOP_DAQ_LIST,
    WC_XCP_START_STOP_SYNCH, WC_XCP_GET_DAQ_CLOCK, WC_XCP_GET_DAQ_PROCESSOR_INFO, WC_XCP_GET_DAQ_RESOLUTION_INFO,
    WC_XCP_GET_DAQ_EVENT_INFO, WC_XCP_FREE_DAQ, WC_XCP_ALLOC_DAQ, WC_XCP_ALLOC_ODT, WC_XCP_ALLOC_ODT_ENTRY,
};

static bool same_bits(float a, float b)
{
    uint32_t x;
    uint32_t y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

/* wc_xcp_step after the loop's iteration, into its own array, and its oracle. */
void xcp_step(const harness_t *h, bool control_step, unsigned record)
{
    wc_can_frame_t xout[WC_XCP_TX_FRAMES];  /* exactly the contract's size: ASan sees a write past it */
    memset(xout, 0, sizeof xout);
    fz_context("wc_xcp_step(control_step)", record);
    fz_ctx.iargs[0] = control_step;
    const uint32_t n = wc_xcp_step(&xcp, control_step, xout);
    FZ_CHECK(n <= WC_XCP_TX_FRAMES, "wc_xcp_step returned %u frames", (unsigned)n);
    xcp_frames += n;
    for (uint32_t i = 0u; i < n; ++i) {
        const wc_can_frame_t *f = &xout[i];
        FZ_CHECK((f->id == WC_CAN_XCP_RESPONSE_FRAME_ID) && (f->dlc == 8u) && (f->flags == 0u),
                 "XCP frame %u: id 0x%x dlc %u flags %u", (unsigned)i, (unsigned)f->id, (unsigned)f->dlc,
                 (unsigned)f->flags);
        const uint8_t pid = f->data[0];
        FZ_CHECK((pid == WC_XCP_PID_RES) || (pid == WC_XCP_PID_ERR) || (pid == WC_XCP_PID_EV) || (pid < xcp.odt_count),
                 "XCP frame %u: PID 0x%02x (ODTs %u)", (unsigned)i, (unsigned)pid, (unsigned)xcp.odt_count);
    }
    const uint32_t checks = xcp.status.pages_accepted + xcp.status.pages_rejected;
    if (checks == xcp_checks) { return; }  /* no page check in this step: the loop's calibration is as it was */
    xcp_checks = checks;
    const wc_calibration_t *now = loop.clutch.model.cal;
    const wc_cal_error_t e = wc_calibration_check(now);
    FZ_CHECK(e == WC_CAL_OK, "the loop runs on a calibration the check refuses: %s", wc_cal_error_name(e));
    FZ_CHECK(same_bits(now->control_period_s, cal->control_period_s), "control period changed online: %g s",
             (double)now->control_period_s);
    FZ_CHECK((loop.config.shift != NULL) == h->shift, "shift control %s online",
             (loop.config.shift != NULL) ? "switched on" : "switched off");
    FZ_CHECK(wc_loop_whole_shift(&loop.config) == h->whole, "the whole shift %s online",
             h->whole ? "switched off" : "switched on");
    if (h->whole) {
        const wc_cal_error_t eo = wc_calibration_check(loop.offgoing.model.cal);
        FZ_CHECK(eo == WC_CAL_OK, "the off-going clutch runs on a calibration the check refuses: %s",
                 wc_cal_error_name(eo));
    }
    if (loop.config.shift != NULL) {
        FZ_CHECK(wc_shift_calibration_check(loop.config.shift) == WC_SHIFT_CAL_OK,
                 "the loop runs on a shift calibration the check refuses");
    }
}

/* The slave, started at the input's first XCP frame (inputs without one pay nothing for it): the loop still
 * runs on the calibration it was initialised with, the reference page's. A fuzzed loop configuration outside
 * the image's limits (a timeout or SyncCounter 0, ...) does not decode: no slave then. */
bool xcp_start(const harness_t *h)
{
    if (!xcp_tried) {
        xcp_tried = true;
        xcp_on = wc_cal_set_from(&xcp_set, cal, h->config.shift, &h->config);
        if (xcp_on) {
            wc_cal_image_encode(&xcp_set, xcp_reference);
            xcp_on = wc_xcp_init(&xcp, &loop, xcp_reference, &xcp_config);
        }
    }
    return xcp_on;
}

/* An XCP command frame as the fuzzer describes it (see the top of the file). */
void build_xcp_frame(fz_reader_t *r, wc_can_frame_t *f)
{
    const uint8_t s = fz_u8(r);
    memset(f, 0, sizeof *f);
    f->id = WC_CAN_XCP_COMMAND_FRAME_ID;
    f->dlc = 8u;
    if ((s & 0x40u) != 0u) {
        const uint8_t format = fz_u8(r);
        f->dlc = (uint8_t)(format & 0x0Fu);
        f->flags = (uint8_t)((format >> 4) & 0x07u);
    }
    const uint32_t pick = s & 0x1Fu;
    uint8_t *d = f->data;
    for (size_t i = 1u; i < sizeof f->data; ++i) { d[i] = fz_u8(r); }
    d[0] = (pick < sizeof xcp_codes) ? xcp_codes[pick] : d[1];
    if ((s & 0x20u) == 0u) { return; }  /* as fuzzed */
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&xcp, regions);
    switch (d[0]) {
    case WC_XCP_SET_MTA:
    case WC_XCP_SHORT_UPLOAD:
    case WC_XCP_WRITE_DAQ: {
        const wc_xcp_region_t *g = &regions[d[4] & 3u];
        const uint32_t address = g->base + (uint32_t)(d[5] | (d[6] << 8)) % (g->size + 8u);
        d[3] = 0u;
        for (uint32_t i = 0u; i < 4u; ++i) { d[4u + i] = (uint8_t)(address >> (8u * i)); }
        if (d[0] == WC_XCP_WRITE_DAQ) { d[1] = 0xFFu; d[2] = (uint8_t)(d[2] % 8u); }
        break;
    }
    case WC_XCP_DOWNLOAD: {
        const uint32_t offset = xcp.mta - regions[0].base;
        const float factor = 1.0f + (float)(int8_t)d[2] / 128.0f;
        float v = factor;
        if ((xcp.mta >= regions[0].base) && (offset + 4u <= regions[0].size)) {
            memcpy(&v, &xcp.working_page[offset], sizeof v);
            v *= factor;
        }
        d[1] = 4u;
        memcpy(&d[2], &v, sizeof v);
        break;
    }
    case WC_XCP_SET_CAL_PAGE:
        d[1] = (uint8_t)(1u + d[1] % 3u);
        d[2] = 0u;
        d[3] &= 1u;
        break;
    case WC_XCP_BUILD_CHECKSUM:
        d[6] = 0u;
        d[7] = 0u;
        d[5] &= 3u;
        break;
    default:
        break;
    }
}

bool xcp_running(void) { return xcp_on; }

void xcp_receive(const wc_can_frame_t *f) { (void)wc_xcp_receive(&xcp, f); }

void xcp_reset(void)
{
    xcp_on = false;
    xcp_tried = false;
    xcp_frames = 0u;
    xcp_checks = 0u;
}

void xcp_print(void)
{
    if (xcp_on) {
        fprintf(stderr,
                "fuzz_loop: xcp commands %u (errors %u, ignored %u, lost %u), frames out %u, pages accepted %u "
                "rejected %u (last %u/%u), daq samples %u overloads %u\n",
                (unsigned)xcp.status.commands, (unsigned)xcp.status.errors, (unsigned)xcp.status.ignored,
                (unsigned)xcp.status.rx_overflows, (unsigned)xcp_frames, (unsigned)xcp.status.pages_accepted,
                (unsigned)xcp.status.pages_rejected, (unsigned)xcp.status.page_result,
                (unsigned)xcp.status.page_error, (unsigned)xcp.status.daq_samples,
                (unsigned)xcp.status.daq_overloads);
    }
}
