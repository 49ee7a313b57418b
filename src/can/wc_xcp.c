/* XCP on CAN slave (ASAM MCD-1 XCP, CAN transport; DESIGN 13): the
 * contract is in wc_xcp.h. Command layouts: ASAM XCP part 2 (protocol
 * layer); the byte offsets below are those of the standard's tables. */
#include "wetclutch_can/wc_xcp.h"

#include <string.h>

#include "wc_xcp_internal.h"
#include "wetclutch/wetclutch.h"

#define MAX_CTO 8u
#define MAX_DTO 8u
#define UPLOAD_MAX (MAX_CTO - 1u)   /* bytes a positive response carries */
#define DOWNLOAD_MAX (MAX_CTO - 2u) /* bytes a DOWNLOAD carries */
#define TIMESTAMP_BYTES 2u          /* in the first ODT of every list */
#define ODT_PAYLOAD (MAX_DTO - 1u)  /* bytes after the PID */
#define PAGES 2u                    /* 0: RAM working page, 1: flash reference page */

/* Session status (GET_STATUS) and DAQ list mode bits. */
#define SESSION_DAQ_RUNNING 0x40u
#define MODE_TIMESTAMP 0x10u
#define MODE_SELECTED 0x40u
#define MODE_RUNNING 0x80u
/* SET_CAL_PAGE mode bits */
#define PAGE_MODE_ECU 0x01u
#define PAGE_MODE_XCP 0x02u
#define PAGE_MODE_ALL 0x80u

/* Dynamic DAQ allocation must run FREE_DAQ, ALLOC_DAQ, ALLOC_ODT..., ALLOC_ODT_ENTRY... in this order. */
enum { ALLOC_NONE = 0, ALLOC_FREED, ALLOC_DAQ_DONE, ALLOC_ODT_DONE, ALLOC_ENTRY_DONE };

/* The identification texts in xcp->id (GET_ID, GET_DAQ_EVENT_INFO's name). */
#define ID_IDENT 0u
#define ID_A2L 40u
#define ID_EVENT 72u
static const char event_name[] = "control_step";

WC_STATIC_ASSERT((WC_XCP_RX_CAPACITY & (WC_XCP_RX_CAPACITY - 1u)) == 0u, xcp_rx_ring_is_a_power_of_two);
WC_STATIC_ASSERT(WC_XCP_ODTS <= 0xFBu, xcp_pids_below_the_reserved_ones);
WC_STATIC_ASSERT(WC_XCP_ODT_ENTRIES <= 0xFFu, xcp_entries_fit_a_byte);
WC_STATIC_ASSERT(WC_XCP_DAQ_LISTS <= 0xFFu, xcp_lists_fit_a_byte);
WC_STATIC_ASSERT(ID_EVENT + sizeof event_name <= WC_XCP_ID_BYTES, xcp_id_texts_fit);
WC_STATIC_ASSERT(WC_CAN_XCP_RESPONSE_LENGTH == MAX_DTO, xcp_response_is_a_classic_can_frame);
WC_STATIC_ASSERT(WC_XCP_SEED_MAX_BYTES <= MAX_CTO - 2u, xcp_seed_fits_one_response);
WC_STATIC_ASSERT(WC_XCP_KEY_MAX_BYTES <= MAX_CTO - 2u, xcp_key_fits_one_unlock);

static void put16(uint8_t *dst, uint32_t value)
{
    dst[0] = (uint8_t)(value & 0xFFu);
    dst[1] = (uint8_t)((value >> 8) & 0xFFu);
}

static uint32_t get16(const uint8_t *src) { return (uint32_t)src[0] | ((uint32_t)src[1] << 8); }

/* Byte copies without the C library's memcpy (the core links only memset),
 * bounded by their length: at most a calibration page. */
static void copy_bytes(uint8_t *dst, const uint8_t *src, uint32_t length)
{
    for (uint32_t i = 0u; i < length; ++i) { dst[i] = src[i]; }
}

#ifndef WC_XCP_READ_ONLY
/* The same into the working page: returns whether any byte changed (a
 * page written with the bytes it holds needs no check). */
static bool write_bytes(uint8_t *dst, const uint8_t *src, uint32_t length)
{
    bool changed = false;
    for (uint32_t i = 0u; i < length; ++i) {
        changed = changed || (dst[i] != src[i]);
        dst[i] = src[i];
    }
    return changed;
}
#endif

/* Copies text (at most capacity - 1 characters) to dst, NUL-terminated; returns its length. */
static uint32_t copy_text(char *dst, const char *text, uint32_t capacity)
{
    uint32_t n = 0u;
    if (text != NULL) {
        for (; (n + 1u < capacity) && (text[n] != '\0'); ++n) { dst[n] = text[n]; }
    }
    dst[n] = '\0';
    return n;
}

static uint32_t text_length(const char *text, uint32_t capacity)
{
    uint32_t n = 0u;
    while ((n < capacity) && (text[n] != '\0')) { ++n; }
    return n;
}

/* The resources seed & key protects under config (both hooks set). */
static uint8_t protected_resources(const wc_xcp_config_t *config)
{
    if ((config->random == NULL) || (config->key == NULL)) { return 0u; }
    return (uint8_t)(WC_XCP_RESOURCE_CAL_PAG | (config->protect_daq ? WC_XCP_RESOURCE_DAQ : 0u));
}

bool wc_xcp_init(wc_xcp_t *xcp, wc_loop_t *loop, const uint8_t *reference_payload, const wc_xcp_config_t *config)
{
    WC_ASSERT((xcp != NULL) && (loop != NULL) && (reference_payload != NULL) && (config != NULL));
    if ((xcp == NULL) || (loop == NULL) || (reference_payload == NULL) || (config == NULL)) { return false; }
    memset(xcp, 0, sizeof *xcp);
    if (wc_cal_image_payload_bytes > WC_CAL_IMAGE_PAYLOAD_MAX_BYTES) { return false; }
    if ((config->random == NULL) != (config->key == NULL)) { return false; }  /* half a protection: none */
    if ((config->random != NULL) &&
        ((config->seed_bytes == 0u) || (config->seed_bytes > WC_XCP_SEED_MAX_BYTES) || (config->key_bytes == 0u) ||
         (config->key_bytes > WC_XCP_KEY_MAX_BYTES) || (config->unlock_attempts == 0u) ||
         (config->unlock_attempts > 255u) || (config->unlock_delay_steps == 0u) ||
         (config->unlock_delay_steps > WC_XCP_UNLOCK_DELAY_MAX_STEPS))) {
        return false;
    }
    xcp->config = *config;
    xcp->locked = protected_resources(config);
    xcp->loop = loop;
    xcp->reference_page = reference_payload;
    copy_bytes(xcp->working_page, reference_payload, wc_cal_image_payload_bytes);
    xcp->loop_set = -1;
    (void)copy_text(&xcp->id[ID_IDENT], config->ident, ID_A2L - ID_IDENT);
    (void)copy_text(&xcp->id[ID_A2L], config->a2l_name, ID_EVENT - ID_A2L);
    (void)copy_text(&xcp->id[ID_EVENT], event_name, WC_XCP_ID_BYTES - ID_EVENT);
    /* the reference must be a calibration the check accepts: the loop runs on it */
    return wc_cal_image_decode(reference_payload, &xcp->sets[0]).result == (uint32_t)WC_CAL_IMAGE_OK;
}

bool wc_xcp_receive(wc_xcp_t *xcp, const wc_can_frame_t *frame)
{
    WC_ASSERT((xcp != NULL) && (frame != NULL));
    if ((xcp == NULL) || (frame == NULL)) { return false; }
    const uint32_t tail = xcp->rx_tail;
    if ((tail - xcp->rx_head) >= WC_XCP_RX_CAPACITY) {
        xcp->status.rx_overflows++;
        return false;
    }
    xcp->rx[tail & (WC_XCP_RX_CAPACITY - 1u)] = *frame;
    WC_MEMORY_BARRIER();
    xcp->rx_tail = tail + 1u;
    return true;
}

/* ------------------------------------------------------------------ DAQ */

static void daq_stop_all(wc_xcp_t *x)
{
    for (uint32_t i = 0u; i < WC_XCP_DAQ_LISTS; ++i) { x->lists[i].mode &= (uint8_t)~(MODE_RUNNING | MODE_SELECTED); }
    x->daq_running = false;
}

static void daq_update_running(wc_xcp_t *x)
{
    bool running = false;
    for (uint32_t i = 0u; i < x->daq_count; ++i) { running = running || ((x->lists[i].mode & MODE_RUNNING) != 0u); }
    if (running && !x->daq_running) { x->overload_reported = false; }
    x->daq_running = running;
}

static uint32_t free_daq(wc_xcp_t *x)
{
    daq_stop_all(x);
    memset(x->lists, 0, sizeof x->lists);
    memset(x->odts, 0, sizeof x->odts);
    memset(x->entries, 0, sizeof x->entries);
    x->daq_count = 0u;
    x->odt_count = 0u;
    x->entry_count = 0u;
    x->ptr_valid = false;
    x->alloc_stage = ALLOC_FREED;
    return XCP_OK;
}

static uint32_t alloc_daq(wc_xcp_t *x, const uint8_t *cmd)
{
    if ((x->alloc_stage != ALLOC_FREED) && (x->alloc_stage != ALLOC_DAQ_DONE)) { return WC_XCP_ERR_SEQUENCE; }
    const uint32_t count = get16(&cmd[2]);
    if (count > WC_XCP_DAQ_LISTS) { return WC_XCP_ERR_MEMORY_OVERFLOW; }
    x->daq_count = (uint8_t)count;
    for (uint32_t i = 0u; i < WC_XCP_DAQ_LISTS; ++i) { x->lists[i] = (wc_xcp_daq_list_t){ 0u, 0u, 0u, 1u, 0u }; }
    x->alloc_stage = ALLOC_DAQ_DONE;
    return XCP_OK;
}

static uint32_t alloc_odt(wc_xcp_t *x, const uint8_t *cmd)
{
    if ((x->alloc_stage != ALLOC_DAQ_DONE) && (x->alloc_stage != ALLOC_ODT_DONE)) { return WC_XCP_ERR_SEQUENCE; }
    const uint32_t list = get16(&cmd[2]);
    const uint32_t count = cmd[4];
    if (list >= x->daq_count) { return WC_XCP_ERR_OUT_OF_RANGE; }
    if (x->lists[list].odts != 0u) { return WC_XCP_ERR_SEQUENCE; }  /* one ALLOC_ODT per list */
    if ((uint32_t)x->odt_count + count > WC_XCP_ODTS) { return WC_XCP_ERR_MEMORY_OVERFLOW; }
    x->lists[list].first_odt = x->odt_count;
    x->lists[list].odts = (uint8_t)count;
    x->odt_count = (uint8_t)(x->odt_count + count);
    x->alloc_stage = ALLOC_ODT_DONE;
    return XCP_OK;
}

static uint32_t alloc_odt_entry(wc_xcp_t *x, const uint8_t *cmd)
{
    if ((x->alloc_stage != ALLOC_ODT_DONE) && (x->alloc_stage != ALLOC_ENTRY_DONE)) { return WC_XCP_ERR_SEQUENCE; }
    const uint32_t list = get16(&cmd[2]);
    const uint32_t odt = cmd[4];
    const uint32_t count = cmd[5];
    if ((list >= x->daq_count) || (odt >= x->lists[list].odts)) { return WC_XCP_ERR_OUT_OF_RANGE; }
    wc_xcp_odt_t *o = &x->odts[x->lists[list].first_odt + odt];
    if (o->entries != 0u) { return WC_XCP_ERR_SEQUENCE; }
    if ((uint32_t)x->entry_count + count > WC_XCP_ODT_ENTRIES) { return WC_XCP_ERR_MEMORY_OVERFLOW; }
    o->first_entry = x->entry_count;
    o->entries = (uint8_t)count;
    x->entry_count = (uint8_t)(x->entry_count + count);
    x->alloc_stage = ALLOC_ENTRY_DONE;
    return XCP_OK;
}

static bool list_running(const wc_xcp_t *x, uint32_t list) { return (x->lists[list].mode & MODE_RUNNING) != 0u; }

static uint32_t set_daq_ptr(wc_xcp_t *x, const uint8_t *cmd)
{
    const uint32_t list = get16(&cmd[2]);
    const uint32_t odt = cmd[4];
    const uint32_t entry = cmd[5];
    x->ptr_valid = false;
    if ((list >= x->daq_count) || (odt >= x->lists[list].odts) ||
        (entry >= x->odts[x->lists[list].first_odt + odt].entries)) {
        return WC_XCP_ERR_OUT_OF_RANGE;
    }
    if (list_running(x, list)) { return WC_XCP_ERR_DAQ_ACTIVE; }
    x->ptr_list = (uint8_t)list;
    x->ptr_odt = (uint8_t)odt;
    x->ptr_entry = (uint8_t)entry;
    x->ptr_valid = true;
    return XCP_OK;
}

static uint32_t write_daq(wc_xcp_t *x, const uint8_t *cmd)
{
    if (!x->ptr_valid) { return WC_XCP_ERR_SEQUENCE; }
    if (list_running(x, x->ptr_list)) { return WC_XCP_ERR_DAQ_ACTIVE; }
    const uint32_t bit_offset = cmd[1];
    const uint32_t size = cmd[2];
    if ((bit_offset != 0xFFu) || (size == 0u) || (size > ODT_PAYLOAD)) { return WC_XCP_ERR_OUT_OF_RANGE; }
    uint8_t *src = NULL;
    const uint32_t found = wc_xcp_resolve(x, wc_image_get_u32(&cmd[4]), cmd[3], size, false, &src);
    if (found != XCP_OK) { return found; }
    const wc_xcp_odt_t *o = &x->odts[x->lists[x->ptr_list].first_odt + x->ptr_odt];
    /* the ODT's bytes with this entry in place of the old one fit one frame */
    uint32_t used = size;
    for (uint32_t e = 0u; e < o->entries; ++e) {
        if (e != x->ptr_entry) { used += x->entries[o->first_entry + e].size; }
    }
    const uint32_t capacity = ODT_PAYLOAD - ((x->ptr_odt == 0u) ? TIMESTAMP_BYTES : 0u);
    if (used > capacity) { return WC_XCP_ERR_DAQ_CONFIG; }
    x->entries[o->first_entry + x->ptr_entry] = (wc_xcp_odt_entry_t){ src, (uint8_t)size };
    x->ptr_entry++;
    x->ptr_valid = x->ptr_entry < o->entries;  /* WRITE_DAQ past the ODT's last entry: SET_DAQ_PTR first */
    return XCP_OK;
}

static uint32_t set_daq_list_mode(wc_xcp_t *x, const uint8_t *cmd)
{
    const uint32_t mode = cmd[1];
    const uint32_t list = get16(&cmd[2]);
    const uint32_t event = get16(&cmd[4]);
    const uint32_t prescaler = cmd[6];
    if ((list >= x->daq_count) || (event != 0u) || (prescaler == 0u)) { return WC_XCP_ERR_OUT_OF_RANGE; }
    if ((mode & ~MODE_TIMESTAMP) != 0u) { return WC_XCP_ERR_MODE_NOT_VALID; }  /* no STIM, DTO_CTR, PID_OFF, alternating */
    if (list_running(x, list)) { return WC_XCP_ERR_DAQ_ACTIVE; }
    x->lists[list].mode = (uint8_t)((x->lists[list].mode & MODE_SELECTED) | MODE_TIMESTAMP);  /* timestamps are fixed */
    x->lists[list].prescaler = (uint8_t)prescaler;
    return XCP_OK;
}

static uint32_t start_stop_daq_list(wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    const uint32_t mode = cmd[1];
    const uint32_t list = get16(&cmd[2]);
    if (list >= x->daq_count) { return WC_XCP_ERR_OUT_OF_RANGE; }
    if (mode > 2u) { return WC_XCP_ERR_MODE_NOT_VALID; }
    wc_xcp_daq_list_t *l = &x->lists[list];
    if ((mode != 0u) && (l->odts == 0u)) { return WC_XCP_ERR_DAQ_CONFIG; }
    if (mode == 0u) { l->mode &= (uint8_t)~MODE_RUNNING; }
    if (mode == 1u) { l->mode |= MODE_RUNNING; l->prescaler_count = 0u; }
    if (mode == 2u) { l->mode |= MODE_SELECTED; }
    daq_update_running(x);
    res[1] = l->first_odt;  /* FIRST_PID */
    return XCP_OK;
}

static uint32_t start_stop_synch(wc_xcp_t *x, const uint8_t *cmd)
{
    const uint32_t mode = cmd[1];
    if (mode > 2u) { return WC_XCP_ERR_MODE_NOT_VALID; }
    if (mode == 0u) { daq_stop_all(x); return XCP_OK; }
    for (uint32_t i = 0u; i < x->daq_count; ++i) {
        wc_xcp_daq_list_t *l = &x->lists[i];
        if ((l->mode & MODE_SELECTED) == 0u) { continue; }
        if (mode == 1u) { l->mode |= MODE_RUNNING; l->prescaler_count = 0u; }
        else { l->mode &= (uint8_t)~MODE_RUNNING; }
        l->mode &= (uint8_t)~MODE_SELECTED;
    }
    daq_update_running(x);
    return XCP_OK;
}

static void frame_init(wc_can_frame_t *f, uint8_t pid)
{
    memset(f, 0, sizeof *f);
    f->id = WC_CAN_XCP_RESPONSE_FRAME_ID;
    f->dlc = (uint8_t)MAX_DTO;
    f->data[0] = pid;
}

/* One sample of every running list (prescaler permitting) that fits in the
 * step's DAQ frame budget. Returns the frames written to out. */
static uint32_t daq_sample(wc_xcp_t *x, wc_can_frame_t *out, wc_can_frame_t *event, bool *has_event)
{
    uint32_t n = 0u;
    for (uint32_t i = 0u; i < x->daq_count; ++i) {
        wc_xcp_daq_list_t *l = &x->lists[i];
        if ((l->mode & MODE_RUNNING) == 0u) { continue; }
        l->prescaler_count++;
        if (l->prescaler_count < l->prescaler) { continue; }
        l->prescaler_count = 0u;
        if (n + l->odts > WC_XCP_DAQ_FRAMES_PER_STEP) {
            x->status.daq_overloads++;
            if (!x->overload_reported) {
                x->overload_reported = true;
                frame_init(event, WC_XCP_PID_EV);
                event->data[1] = WC_XCP_EV_DAQ_OVERLOAD;
                *has_event = true;
            }
            continue;
        }
        for (uint32_t j = 0u; j < l->odts; ++j) {
            wc_can_frame_t *f = &out[n++];
            frame_init(f, (uint8_t)(l->first_odt + j));
            uint32_t pos = 1u;
            if (j == 0u) {
                put16(&f->data[1], x->status.timestamp);
                pos += TIMESTAMP_BYTES;
            }
            const wc_xcp_odt_t *o = &x->odts[l->first_odt + j];
            for (uint32_t e = 0u; e < o->entries; ++e) {
                const wc_xcp_odt_entry_t *entry = &x->entries[o->first_entry + e];
                if ((entry->size == 0u) || (pos + entry->size > MAX_DTO)) { continue; }  /* not written */
                copy_bytes(&f->data[pos], entry->src, entry->size);
                pos += entry->size;
            }
        }
        x->status.daq_samples++;
        x->status.daq_frames += l->odts;
    }
    return n;
}

/* ------------------------------------------------------- calibration pages */

/* Decode and check the ECU page and give it to the loop; a refusal keeps
 * the last good calibration and fills event with EV_USER (result, error). */
static bool check_page(wc_xcp_t *x, wc_can_frame_t *event)
{
    const int32_t next = (x->loop_set == 0) ? 1 : 0;
    wc_cal_set_t *set = &x->sets[next];
    const uint8_t *page = (x->status.ecu_page == 0u) ? x->working_page : x->reference_page;
    wc_cal_image_status_t checked = wc_cal_image_decode(page, set);
    if (checked.result == (uint32_t)WC_CAL_IMAGE_OK) {
        const wc_calibration_t *now = x->loop->clutch.model.cal;
        const bool same_period = (set->clutch.control_period_s <= now->control_period_s) &&
                                 (set->clutch.control_period_s >= now->control_period_s);
        if (!same_period || (set->shift_enabled != (x->loop->config.shift != NULL))) {
            checked = (wc_cal_image_status_t){ WC_XCP_PAGE_NOT_ONLINE, 0u };
        }
    }
    if (checked.result == (uint32_t)WC_CAL_IMAGE_OK) {
        const wc_cal_error_t error = wc_loop_recalibrate(x->loop, &set->clutch, &set->loop);
        if (error != WC_CAL_OK) { checked = (wc_cal_image_status_t){ WC_CAL_IMAGE_BAD_CLUTCH, (uint32_t)error }; }
    }
    x->status.page_result = checked.result;
    x->status.page_error = checked.error;
    if (checked.result == (uint32_t)WC_CAL_IMAGE_OK) {
        x->loop_set = next;
        x->status.pages_accepted++;
        return false;
    }
    x->status.pages_rejected++;
    frame_init(event, WC_XCP_PID_EV);
    event->data[1] = WC_XCP_EV_USER;
    event->data[2] = (uint8_t)checked.result;
    put16(&event->data[3], checked.error);
    return true;
}

#ifndef WC_XCP_READ_ONLY
static uint32_t set_cal_page(wc_xcp_t *x, const uint8_t *cmd)
{
    const uint32_t mode = cmd[1];
    const uint32_t segment = cmd[2];
    const uint32_t page = cmd[3];
    if ((mode & (PAGE_MODE_ECU | PAGE_MODE_XCP)) == 0u) { return WC_XCP_ERR_MODE_NOT_VALID; }
    if (((mode & PAGE_MODE_ALL) == 0u) && (segment != 0u)) { return WC_XCP_ERR_SEGMENT_NOT_VALID; }
    if (page >= PAGES) { return WC_XCP_ERR_PAGE_NOT_VALID; }
    if ((mode & PAGE_MODE_XCP) != 0u) { x->xcp_page = page; }
    if (((mode & PAGE_MODE_ECU) != 0u) && (page != x->status.ecu_page)) {
        x->status.ecu_page = page;
        x->page_dirty = true;  /* the controller changes page at this step's check */
    }
    return XCP_OK;
}
#endif

static uint32_t get_cal_page(const wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    if (cmd[2] != 0u) { return WC_XCP_ERR_SEGMENT_NOT_VALID; }
    if ((cmd[1] != PAGE_MODE_ECU) && (cmd[1] != PAGE_MODE_XCP)) { return WC_XCP_ERR_MODE_NOT_VALID; }
    res[3] = (uint8_t)((cmd[1] == PAGE_MODE_ECU) ? x->status.ecu_page : x->xcp_page);
    return XCP_OK;
}

#ifndef WC_XCP_READ_ONLY
static uint32_t copy_cal_page(wc_xcp_t *x, const uint8_t *cmd)
{
    if ((cmd[1] != 0u) || (cmd[3] != 0u)) { return WC_XCP_ERR_SEGMENT_NOT_VALID; }
    if ((cmd[2] >= PAGES) || (cmd[4] >= PAGES)) { return WC_XCP_ERR_PAGE_NOT_VALID; }
    if (cmd[4] != 0u) { return WC_XCP_ERR_WRITE_PROTECTED; }  /* the reference page is flash */
    if (cmd[2] == 1u) {
        const bool changed = write_bytes(x->working_page, x->reference_page, wc_cal_image_payload_bytes);
        x->page_dirty = (changed && (x->status.ecu_page == 0u)) || x->page_dirty;  /* checked when the ECU uses it */
    }
    return XCP_OK;
}
#endif

/* ------------------------------------------------------------ memory access */

static uint32_t upload(wc_xcp_t *x, uint32_t address, uint32_t extension, uint32_t length, uint8_t *res)
{
    if ((length == 0u) || (length > UPLOAD_MAX)) { return WC_XCP_ERR_OUT_OF_RANGE; }
    uint8_t *src = NULL;
    const uint32_t found = wc_xcp_resolve(x, address, extension, length, false, &src);
    if (found != XCP_OK) { return found; }
    copy_bytes(&res[1], src, length);
    x->mta = address + length;
    return XCP_OK;
}

#ifndef WC_XCP_READ_ONLY
static uint32_t download(wc_xcp_t *x, const uint8_t *cmd, uint32_t dlc)
{
    const uint32_t length = cmd[1];
    if ((length == 0u) || (length > DOWNLOAD_MAX)) { return WC_XCP_ERR_OUT_OF_RANGE; }
    if (dlc < 2u + length) { return WC_XCP_ERR_CMD_SYNTAX; }
    uint8_t *dst = NULL;
    const uint32_t found = wc_xcp_resolve(x, x->mta, 0u, length, true, &dst);
    if (found != XCP_OK) { return found; }
    const bool changed = write_bytes(dst, &cmd[2], length);
    /* a page the controller does not use is checked when SET_CAL_PAGE switches to it */
    x->page_dirty = (changed && (x->status.ecu_page == 0u)) || x->page_dirty;
    x->mta += length;
    return XCP_OK;
}
#endif

static uint32_t build_checksum(wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    const uint32_t length = wc_image_get_u32(&cmd[4]);
    if ((length == 0u) || (length > WC_XCP_CHECKSUM_MAX_BYTES)) {
        wc_image_put_u32(&res[4], WC_XCP_CHECKSUM_MAX_BYTES);  /* MAX_BLOCKSIZE in the error packet */
        return WC_XCP_ERR_OUT_OF_RANGE;
    }
    uint8_t *src = NULL;
    const uint32_t found = wc_xcp_resolve(x, x->mta, 0u, length, false, &src);
    if (found != XCP_OK) { return found; }
    res[1] = 0x09u;  /* XCP_CRC_32: IEEE 802.3, as wc_image_crc32 */
    wc_image_put_u32(&res[4], wc_image_crc32(src, length));
    x->mta += length;
    return XCP_OK;
}

static uint32_t get_id(wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    uint32_t offset = ID_IDENT, length = 0u;
    if (cmd[1] == 0u) { length = text_length(&x->id[ID_IDENT], ID_A2L - ID_IDENT); }
    if (cmd[1] == 1u) { offset = ID_A2L; length = text_length(&x->id[ID_A2L], ID_EVENT - ID_A2L); }
    res[1] = 0u;  /* mode: the text is uploaded from the MTA */
    wc_image_put_u32(&res[4], length);
    x->mta = x->config.id_base + offset;
    return XCP_OK;
}

/* ------------------------------------------------------------ information */

static uint32_t control_ticks_10us(const wc_xcp_t *x)
{
    const float ticks = x->loop->clutch.model.cal->control_period_s * 1e5f + 0.5f;
    return (ticks >= 1.0f) && (ticks <= 65535.0f) ? (uint32_t)ticks : 1u;
}

static void daq_processor_info(uint8_t *res)
{
    res[1] = 0x01u | 0x02u | 0x10u | 0x80u;  /* dynamic, prescaler, timestamps, overload by event packet */
    put16(&res[2], WC_XCP_DAQ_LISTS);      /* MAX_DAQ */
    put16(&res[4], 1u);                    /* MAX_EVENT_CHANNEL */
    res[6] = 0u;                           /* MIN_DAQ */
    res[7] = 0u;                           /* DAQ_KEY_BYTE: absolute ODT number, any address extension */
}

static void daq_resolution_info(const wc_xcp_t *x, uint8_t *res)
{
    res[1] = 1u;             /* granularity of an ODT entry (DAQ) */
    res[2] = ODT_PAYLOAD;    /* largest ODT entry (DAQ) */
    res[3] = 1u;             /* STIM: none */
    res[4] = 0u;
    res[5] = 0x40u | 0x08u | 0x02u;  /* unit 10 us, TIMESTAMP_FIXED, 2 bytes */
    put16(&res[6], control_ticks_10us(x));  /* one tick per control step */
}

static uint32_t daq_event_info(wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    if (get16(&cmd[2]) != 0u) { return WC_XCP_ERR_OUT_OF_RANGE; }
    const uint32_t ticks = control_ticks_10us(x);
    res[1] = 0x04u | 0x80u;  /* DAQ, event-consistent (sampled after the step) */
    res[2] = WC_XCP_DAQ_LISTS;
    res[3] = (uint8_t)text_length(&x->id[ID_EVENT], WC_XCP_ID_BYTES - ID_EVENT);
    res[4] = (uint8_t)((ticks <= 255u) ? ticks : (ticks + 50u) / 100u);  /* cycle */
    res[5] = (uint8_t)((ticks <= 255u) ? 4u : 6u);                       /* unit: 10 us or 1 ms */
    res[6] = 0xFFu;                                                     /* priority */
    x->mta = x->config.id_base + ID_EVENT;
    return XCP_OK;
}

/* ------------------------------------------------------------ seed & key */

/* Protection back on, no seed waiting: at DISCONNECT and after a wrong key. */
static void relock(wc_xcp_t *x)
{
    x->locked = protected_resources(&x->config);
    x->seed_resource = 0u;
    memset(x->seed, 0, sizeof x->seed);
}

/* A lock-out runs (wc_xcp.h, failed attempts): the steps to its end, lockout_end - status.timestamp mod 2^32,
 * are in (0, unlock_delay_steps]. At its end the count of wrong keys starts from 0. Looked at only here (no
 * cost per step): a first GET_SEED 2^32 - unlock_delay_steps steps after the end (49.7 days at 1 ms) finds
 * it running again, for at most unlock_delay_steps. */
static bool locked_out(wc_xcp_t *x)
{
    if (!x->lockout) { return false; }
    const uint32_t left_steps = x->lockout_end - x->status.timestamp;
    if ((left_steps != 0u) && (left_steps <= x->config.unlock_delay_steps)) { return true; }
    x->lockout = false;
    x->unlock_failures = 0u;
    return false;
}

static uint32_t get_seed(wc_xcp_t *x, const uint8_t *cmd, uint8_t *res)
{
    const uint32_t mode = cmd[1];
    const uint32_t resource = cmd[2];
    if (mode == 1u) { return WC_XCP_ERR_SEQUENCE; }  /* the seed fits one response: no remaining part */
    if (mode != 0u) { return WC_XCP_ERR_OUT_OF_RANGE; }
    if ((resource != WC_XCP_RESOURCE_CAL_PAG) && (resource != WC_XCP_RESOURCE_DAQ) &&
        (resource != WC_XCP_RESOURCE_STIM) && (resource != WC_XCP_RESOURCE_PGM)) {
        return WC_XCP_ERR_OUT_OF_RANGE;  /* exactly one resource a seed */
    }
    x->seed_resource = 0u;  /* a new request forgets the old seed */
    if ((x->locked & resource) == 0u) {
        res[1] = 0u;  /* not protected (or unlocked already): seed length 0 */
        return XCP_OK;
    }
    if (locked_out(x)) { return WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE; }  /* no seed, so no key to try */
    const uint32_t length = x->config.seed_bytes;
    if (!x->config.random(x->config.context, x->seed, length)) { return WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE; }
    x->seed_resource = (uint8_t)resource;
    res[1] = (uint8_t)length;
    copy_bytes(&res[2], x->seed, length);
    return XCP_OK;
}

static uint32_t unlock(wc_xcp_t *x, const uint8_t *cmd, uint32_t dlc, uint8_t *res)
{
    const uint32_t length = cmd[1];
    if ((length <= WC_XCP_KEY_MAX_BYTES) && (dlc < 2u + length)) { return WC_XCP_ERR_CMD_SYNTAX; }
    if (x->seed_resource == 0u) { return WC_XCP_ERR_SEQUENCE; }
    const uint8_t resource = x->seed_resource;
    x->seed_resource = 0u;  /* every UNLOCK consumes the seed */
    uint8_t expected[WC_XCP_KEY_MAX_BYTES] = { 0u };
    const uint32_t key_length = x->config.key_bytes;
    bool good = (length == key_length) &&
                x->config.key(x->config.context, x->seed, x->config.seed_bytes, expected, key_length);
    uint32_t difference = 0u;  /* every byte compared: the time says nothing of the first wrong one */
    for (uint32_t i = 0u; i < WC_XCP_KEY_MAX_BYTES; ++i) {
        difference |= (i < key_length) ? (uint32_t)(expected[i] ^ cmd[2u + i]) : 0u;
    }
    good = good && (difference == 0u);
    memset(expected, 0, sizeof expected);
    if (!good) {  /* the standard: ERR_ACCESS_LOCKED and back to disconnected; counted, then the lock-out */
        daq_stop_all(x);
        x->connected = false;
        relock(x);
        x->unlock_failures++;  /* at most unlock_attempts (<= 255): the lock-out's end resets it */
        if (x->unlock_failures >= x->config.unlock_attempts) {
            x->lockout = true;
            x->lockout_end = x->status.timestamp + x->config.unlock_delay_steps;
        }
        return WC_XCP_ERR_ACCESS_LOCKED;
    }
    x->unlock_failures = 0u;
    x->locked &= (uint8_t)~resource;
    res[1] = x->locked;  /* the current resource protection status */
    return XCP_OK;
}

/* The resource a command needs unlocked (0: none). */
static uint32_t resource_of(uint32_t code)
{
    switch (code) {
    case WC_XCP_DOWNLOAD: case WC_XCP_SET_CAL_PAGE: case WC_XCP_GET_CAL_PAGE: case WC_XCP_COPY_CAL_PAGE:
    case WC_XCP_GET_PAG_PROCESSOR_INFO: return WC_XCP_RESOURCE_CAL_PAG;
    case WC_XCP_GET_DAQ_PROCESSOR_INFO: case WC_XCP_GET_DAQ_RESOLUTION_INFO: case WC_XCP_GET_DAQ_EVENT_INFO:
    case WC_XCP_GET_DAQ_CLOCK: case WC_XCP_FREE_DAQ: case WC_XCP_ALLOC_DAQ: case WC_XCP_ALLOC_ODT:
    case WC_XCP_ALLOC_ODT_ENTRY: case WC_XCP_SET_DAQ_PTR: case WC_XCP_WRITE_DAQ: case WC_XCP_SET_DAQ_LIST_MODE:
    case WC_XCP_START_STOP_DAQ_LIST: case WC_XCP_START_STOP_SYNCH: return WC_XCP_RESOURCE_DAQ;
    default: return 0u;
    }
}

/* --------------------------------------------------------------- commands */

/* Bytes each command needs (its code included); 0: not supported. */
static uint32_t command_length(uint32_t code)
{
    switch (code) {
    case WC_XCP_CONNECT: case WC_XCP_UPLOAD: case WC_XCP_START_STOP_SYNCH: case WC_XCP_UNLOCK: return 2u;
#ifndef WC_XCP_READ_ONLY
    case WC_XCP_DOWNLOAD: return 2u;
    case WC_XCP_SET_CAL_PAGE: return 4u;
    case WC_XCP_COPY_CAL_PAGE: return 5u;
#endif
    case WC_XCP_DISCONNECT: case WC_XCP_GET_STATUS: case WC_XCP_SYNCH: case WC_XCP_GET_COMM_MODE_INFO:
    case WC_XCP_GET_PAG_PROCESSOR_INFO: case WC_XCP_GET_DAQ_CLOCK: case WC_XCP_GET_DAQ_PROCESSOR_INFO:
    case WC_XCP_GET_DAQ_RESOLUTION_INFO: case WC_XCP_FREE_DAQ: return 1u;
    case WC_XCP_GET_ID: return 2u;
    case WC_XCP_GET_CAL_PAGE: case WC_XCP_GET_SEED: return 3u;
    case WC_XCP_ALLOC_DAQ: case WC_XCP_START_STOP_DAQ_LIST:
    case WC_XCP_GET_DAQ_EVENT_INFO: return 4u;
    case WC_XCP_ALLOC_ODT: return 5u;
    case WC_XCP_ALLOC_ODT_ENTRY: case WC_XCP_SET_DAQ_PTR: return 6u;
    case WC_XCP_SET_MTA: case WC_XCP_SHORT_UPLOAD: case WC_XCP_BUILD_CHECKSUM: case WC_XCP_WRITE_DAQ:
    case WC_XCP_SET_DAQ_LIST_MODE: return 8u;
    default: return 0u;
    }
}

static uint32_t dispatch(wc_xcp_t *x, const uint8_t *cmd, uint32_t dlc, uint8_t *res)
{
    switch (cmd[0]) {
    case WC_XCP_CONNECT:
        x->connected = true;
        res[1] = 0x01u | 0x04u;  /* RESOURCE: CAL/PAG, DAQ */
        res[2] = 0x80u;          /* COMM_MODE_BASIC: Intel, byte granularity, GET_COMM_MODE_INFO available */
        res[3] = MAX_CTO;
        put16(&res[4], MAX_DTO);
        res[6] = 1u;             /* protocol layer version */
        res[7] = 1u;             /* transport layer version */
        return XCP_OK;
    case WC_XCP_DISCONNECT: daq_stop_all(x); x->connected = false; relock(x); return XCP_OK;
    case WC_XCP_GET_STATUS:
        res[1] = x->daq_running ? SESSION_DAQ_RUNNING : 0u;
        res[2] = x->locked;  /* resource protection status */
        return XCP_OK;
    case WC_XCP_GET_SEED: return get_seed(x, cmd, res);
    case WC_XCP_UNLOCK: return unlock(x, cmd, dlc, res);
    case WC_XCP_SYNCH: return WC_XCP_ERR_CMD_SYNCH;
    case WC_XCP_GET_COMM_MODE_INFO: res[7] = 0x10u; return XCP_OK;  /* no block modes, driver version 1.0 */
    case WC_XCP_GET_ID: return get_id(x, cmd, res);
    case WC_XCP_SET_MTA:
        if (cmd[3] != 0u) { return WC_XCP_ERR_ACCESS_DENIED; }
        x->mta = wc_image_get_u32(&cmd[4]);
        return XCP_OK;
    case WC_XCP_UPLOAD: return upload(x, x->mta, 0u, cmd[1], res);
    case WC_XCP_SHORT_UPLOAD: return upload(x, wc_image_get_u32(&cmd[4]), cmd[3], cmd[1], res);
#ifndef WC_XCP_READ_ONLY
    case WC_XCP_DOWNLOAD: return download(x, cmd, dlc);
    case WC_XCP_SET_CAL_PAGE: return set_cal_page(x, cmd);
    case WC_XCP_COPY_CAL_PAGE: return copy_cal_page(x, cmd);
#endif
    case WC_XCP_BUILD_CHECKSUM: return build_checksum(x, cmd, res);
    case WC_XCP_GET_CAL_PAGE: return get_cal_page(x, cmd, res);
    case WC_XCP_GET_PAG_PROCESSOR_INFO: res[1] = 1u; return XCP_OK;  /* one segment, no freeze */
    case WC_XCP_GET_DAQ_PROCESSOR_INFO: daq_processor_info(res); return XCP_OK;
    case WC_XCP_GET_DAQ_RESOLUTION_INFO: daq_resolution_info(x, res); return XCP_OK;
    case WC_XCP_GET_DAQ_EVENT_INFO: return daq_event_info(x, cmd, res);
    case WC_XCP_GET_DAQ_CLOCK: wc_image_put_u32(&res[4], x->status.timestamp & 0xFFFFu); return XCP_OK;
    case WC_XCP_FREE_DAQ: return free_daq(x);
    case WC_XCP_ALLOC_DAQ: return alloc_daq(x, cmd);
    case WC_XCP_ALLOC_ODT: return alloc_odt(x, cmd);
    case WC_XCP_ALLOC_ODT_ENTRY: return alloc_odt_entry(x, cmd);
    case WC_XCP_SET_DAQ_PTR: return set_daq_ptr(x, cmd);
    case WC_XCP_WRITE_DAQ: return write_daq(x, cmd);
    case WC_XCP_SET_DAQ_LIST_MODE: return set_daq_list_mode(x, cmd);
    case WC_XCP_START_STOP_DAQ_LIST: return start_stop_daq_list(x, cmd, res);
    case WC_XCP_START_STOP_SYNCH: return start_stop_synch(x, cmd);
    default: return WC_XCP_ERR_CMD_UNKNOWN;
    }
}

/* One command frame: its response (or error) in *res; false when the frame
 * gets no answer (not a command frame, or not connected). */
static bool command(wc_xcp_t *x, const wc_can_frame_t *in, wc_can_frame_t *res)
{
    if ((in->id != WC_CAN_XCP_COMMAND_FRAME_ID) || (in->flags != 0u) || (in->dlc == 0u) || (in->dlc > MAX_CTO) ||
        (!x->connected && (in->data[0] != WC_XCP_CONNECT))) {
        x->status.ignored++;
        return false;
    }
    frame_init(res, WC_XCP_PID_RES);
    const uint32_t needed = command_length(in->data[0]);
    uint8_t cmd[MAX_CTO] = { 0u };
    copy_bytes(cmd, in->data, in->dlc);  /* bytes past the DLC read as 0, never as old data */
    uint32_t result = WC_XCP_ERR_CMD_UNKNOWN;
    if (needed != 0u) {
        if (in->dlc < needed) { result = WC_XCP_ERR_CMD_SYNTAX; }
        else if ((x->locked & resource_of(cmd[0])) != 0u) { result = WC_XCP_ERR_ACCESS_LOCKED; }  /* seed & key first */
        else { result = dispatch(x, cmd, in->dlc, res->data); }
    }
    x->status.commands++;
    if (result != XCP_OK) {
        const uint8_t max_block[4] = { res->data[4], res->data[5], res->data[6], res->data[7] };
        frame_init(res, WC_XCP_PID_ERR);
        res->data[1] = (uint8_t)result;
        if (result == WC_XCP_ERR_OUT_OF_RANGE) { copy_bytes(&res->data[4], max_block, sizeof max_block); }
        x->status.errors++;
    }
    return true;
}

uint32_t wc_xcp_step(wc_xcp_t *xcp, bool control_step, wc_can_frame_t out[WC_XCP_TX_FRAMES])
{
    WC_ASSERT((xcp != NULL) && (out != NULL) && (xcp->loop != NULL));
    if ((xcp == NULL) || (out == NULL) || (xcp->loop == NULL)) { return 0u; }
    uint32_t n = 0u;
    const uint32_t tail = xcp->rx_tail;
    WC_MEMORY_BARRIER();
    if (xcp->rx_head != tail) {  /* one command a step: the step's cost is that of the costliest command */
        const wc_can_frame_t *in = &xcp->rx[xcp->rx_head & (WC_XCP_RX_CAPACITY - 1u)];
        if (command(xcp, in, &out[n])) { ++n; }
        xcp->rx_head++;
    }
    if (xcp->page_dirty) {
        xcp->page_dirty = false;
        if (check_page(xcp, &out[n])) { ++n; }
    }
    if (control_step) {
        xcp->status.timestamp++;
        if (xcp->daq_running && xcp->connected) {
            bool has_event = false;
            wc_can_frame_t *event = &out[n + WC_XCP_DAQ_FRAMES_PER_STEP];  /* past every sample */
            n += daq_sample(xcp, &out[n], event, &has_event);
            if (has_event) { out[n++] = *event; }  /* right after the samples */
        }
    }
    return n;
}
