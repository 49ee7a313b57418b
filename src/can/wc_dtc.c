/* Fault memory (ISO 14229-1:2013 Annex D.2 status bits; DESIGN 17): the
 * contract is in wc_dtc.h. */
#include "wetclutch_can/wc_dtc.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "wetclutch/wc_config.h"

#define DTC_NUMBER_MAX 0xFFFFFEu            /* 0xFFFFFF is the group "all" */
#define COUNT_MAX 0xFFFFFFFFu
#define CYCLES_MAX 0xFFu
#define SLOTS_AT 8u
#define ENTRIES_AT (SLOTS_AT + WC_DTC_SLOT_BYTES * WC_DTC_MAX_DEFINITIONS)

WC_STATIC_ASSERT(WC_DTC_IMAGE_PAYLOAD_BYTES == ENTRIES_AT + WC_DTC_ENTRY_BYTES * WC_DTC_MAX_ENTRIES, dtc_image_layout);
WC_STATIC_ASSERT(WC_DTC_ENTRY_BYTES == 8u + 4u * WC_DTC_SNAPSHOT_FLOATS + 4u, dtc_entry_layout);
WC_STATIC_ASSERT(WC_DTC_IMAGE_PAYLOAD_BYTES <= WC_IMAGE_PAYLOAD_MAX_BYTES, dtc_image_fits_the_format);
WC_STATIC_ASSERT(WC_DTC_MAX_ENTRIES < WC_DTC_NO_ENTRY, dtc_entry_index_fits_a_byte);
WC_STATIC_ASSERT(WC_DTC_MAX_DEFINITIONS < WC_DTC_NO_ENTRY, dtc_definition_index_fits_a_byte);

/* The snapshot's floats in struct order: the image and the UDS form. */
static void snapshot_floats(const wc_dtc_snapshot_t *s, float v[WC_DTC_SNAPSHOT_FLOATS])
{
    v[0] = s->slip_speed_rad_s;
    v[1] = s->output_speed_rad_s;
    v[2] = s->turbine_speed_rad_s;
    v[3] = s->theta_clutch_degC;
    v[4] = s->theta_oil_degC;
    v[5] = s->theta_housing_degC;
    v[6] = s->current_oncoming_mA;
    v[7] = s->current_offgoing_mA;
}

static float finite_or_limit(float x)
{
    if (isnan(x)) { return 0.0f; }
    if (x > FLT_MAX) { return FLT_MAX; }
    return (x < -FLT_MAX) ? -FLT_MAX : x;
}

static void snapshot_from_floats(wc_dtc_snapshot_t *s, const float v[WC_DTC_SNAPSHOT_FLOATS])
{
    s->slip_speed_rad_s = finite_or_limit(v[0]);
    s->output_speed_rad_s = finite_or_limit(v[1]);
    s->turbine_speed_rad_s = finite_or_limit(v[2]);
    s->theta_clutch_degC = finite_or_limit(v[3]);
    s->theta_oil_degC = finite_or_limit(v[4]);
    s->theta_housing_degC = finite_or_limit(v[5]);
    s->current_oncoming_mA = finite_or_limit(v[6]);
    s->current_offgoing_mA = finite_or_limit(v[7]);
}

static void put_be32(uint8_t *dst, uint32_t value)
{
    dst[0] = (uint8_t)(value >> 24);
    dst[1] = (uint8_t)((value >> 16) & 0xFFu);
    dst[2] = (uint8_t)((value >> 8) & 0xFFu);
    dst[3] = (uint8_t)(value & 0xFFu);
}

void wc_dtc_snapshot_encode(const wc_dtc_snapshot_t *snapshot, uint8_t out[WC_DTC_SNAPSHOT_BYTES])
{
    WC_ASSERT((snapshot != NULL) && (out != NULL));
    if ((snapshot == NULL) || (out == NULL)) { return; }
    float v[WC_DTC_SNAPSHOT_FLOATS];
    snapshot_floats(snapshot, v);
    for (uint32_t i = 0u; i < WC_DTC_SNAPSHOT_FLOATS; ++i) {
        uint8_t le[4];
        wc_image_put_f32(le, v[i]);  /* the IEEE-754 bit pattern, whatever the host */
        put_be32(&out[4u * i], wc_image_get_u32(le));
    }
    out[4u * WC_DTC_SNAPSHOT_FLOATS] = snapshot->shift_phase;
    out[4u * WC_DTC_SNAPSHOT_FLOATS + 1u] = snapshot->gear;
}

/* -------------------------------------------------------------- memory */

static void clear_one(wc_dtc_t *dtc, uint32_t index)
{
    wc_dtc_state_t *st = &dtc->state[index];
    if (st->entry != WC_DTC_NO_ENTRY) { dtc->entries[st->entry].definition = WC_DTC_NO_ENTRY; }
    *st = (wc_dtc_state_t){ 0, (uint8_t)WC_DTC_STATUS_EMPTY, 0u, 0u, WC_DTC_NO_ENTRY, 0u };
    if (index == dtc->config.memory_lost) { dtc->memory_lost_pending = false; }
}

static void empty_memory(wc_dtc_t *dtc)
{
    for (uint32_t e = 0u; e < WC_DTC_MAX_ENTRIES; ++e) {
        memset(&dtc->entries[e], 0, sizeof dtc->entries[e]);
        dtc->entries[e].definition = WC_DTC_NO_ENTRY;
    }
    for (uint32_t i = 0u; i < WC_DTC_MAX_DEFINITIONS; ++i) {
        dtc->state[i] = (wc_dtc_state_t){ 0, 0u, 0u, 0u, WC_DTC_NO_ENTRY, 0u };
        if (i < dtc->config.count) { clear_one(dtc, i); }
    }
    dtc->next_sequence = 0u;
    dtc->overflows = 0u;
    dtc->memory_lost_pending = false;
}

static bool definitions_valid(const wc_dtc_config_t *c)
{
    if ((c->definitions == NULL) || (c->count < 1u) || (c->count > WC_DTC_MAX_DEFINITIONS) ||
        (c->aging_cycles < 1u) || (c->aging_cycles > CYCLES_MAX) ||
        ((c->memory_lost != WC_DTC_NONE) && (c->memory_lost >= c->count))) {
        return false;
    }
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < c->count); ++i) {
        const wc_dtc_definition_t *d = &c->definitions[i];
        if ((d->number == 0u) || (d->number > DTC_NUMBER_MAX) || (d->fail_threshold < 1) || (d->pass_threshold > 0) ||
            (d->fail_step < 1u) || (d->pass_step < 1u) || (d->confirm_cycles < 1u)) {
            return false;
        }
        for (uint32_t j = 0u; j < i; ++j) {
            if (c->definitions[j].number == d->number) { return false; }
        }
    }
    return true;
}

bool wc_dtc_init(wc_dtc_t *dtc, const wc_dtc_config_t *config)
{
    WC_ASSERT((dtc != NULL) && (config != NULL));
    if ((dtc == NULL) || (config == NULL)) { return false; }
    memset(dtc, 0, sizeof *dtc);
    if (!definitions_valid(config)) { return false; }
    dtc->config = *config;
    empty_memory(dtc);
    dtc->initialised = true;
    return true;
}

static bool usable(const wc_dtc_t *dtc)
{
    WC_ASSERT((dtc != NULL) && dtc->initialised);
    return (dtc != NULL) && dtc->initialised;
}

/* A free entry, or the one to displace (wc_dtc.h), or WC_DTC_NO_ENTRY. */
static uint32_t entry_for(const wc_dtc_t *dtc, uint32_t index)
{
    const uint8_t priority = dtc->config.definitions[index].priority;
    uint32_t best = WC_DTC_NO_ENTRY;
    for (uint32_t e = 0u; e < WC_DTC_MAX_ENTRIES; ++e) {
        const uint32_t d = dtc->entries[e].definition;
        if (d == WC_DTC_NO_ENTRY) { return e; }
        const uint8_t p = dtc->config.definitions[d].priority;
        if (p < priority) { continue; }  /* more important than the new one: kept */
        if (best == WC_DTC_NO_ENTRY) {
            best = e;
            continue;
        }
        const uint32_t b = dtc->entries[best].definition;
        const bool failing = (dtc->state[d].status & WC_DTC_TF) != 0u;
        const bool best_failing = (dtc->state[b].status & WC_DTC_TF) != 0u;
        const uint8_t bp = dtc->config.definitions[b].priority;
        const bool better = (failing != best_failing) ? !failing
                          : ((p != bp) ? (p > bp) : (dtc->entries[e].sequence < dtc->entries[best].sequence));
        if (better) { best = e; }
    }
    return best;
}

static void store_entry(wc_dtc_t *dtc, uint32_t index)
{
    const uint32_t e = entry_for(dtc, index);
    if (e == WC_DTC_NO_ENTRY) {
        if (dtc->overflows < COUNT_MAX) { dtc->overflows++; }
        return;
    }
    wc_dtc_entry_t *entry = &dtc->entries[e];
    if (entry->definition != WC_DTC_NO_ENTRY) {  /* displaced */
        wc_dtc_state_t *old = &dtc->state[entry->definition];
        old->entry = WC_DTC_NO_ENTRY;
        old->status &= (uint8_t)~(WC_DTC_CONFIRMED | WC_DTC_WIR);
        old->aging_cycles = 0u;
    }
    entry->definition = (uint8_t)index;
    entry->sequence = dtc->next_sequence;
    dtc->next_sequence++;
    if (dtc->config.environment != NULL) {
        float v[WC_DTC_SNAPSHOT_FLOATS];
        snapshot_floats(dtc->config.environment, v);
        snapshot_from_floats(&entry->snapshot, v);
        entry->snapshot.shift_phase = dtc->config.environment->shift_phase;
        entry->snapshot.gear = dtc->config.environment->gear;
    } else {
        memset(&entry->snapshot, 0, sizeof entry->snapshot);
    }
    dtc->state[index].entry = (uint8_t)e;
}

/* A qualified failure (D.2: bits 0, 1, 2, 5 set, 4 and 6 cleared). */
static void qualify_failed(wc_dtc_t *dtc, uint32_t index)
{
    const wc_dtc_definition_t *d = &dtc->config.definitions[index];
    wc_dtc_state_t *st = &dtc->state[index];
    const uint8_t was = st->status;
    st->status = (uint8_t)((was | WC_DTC_TF | WC_DTC_TFTOC | WC_DTC_PENDING | WC_DTC_TFSLC) &
                           ~(WC_DTC_TNCSLC | WC_DTC_TNCTOC));
    if ((was & WC_DTC_TF) == 0u) {
        if (st->fault_count < COUNT_MAX) { st->fault_count++; }
        dtc->changed = true;
    }
    if ((was & WC_DTC_TFTOC) == 0u) {  /* the first failure in this cycle */
        if (st->failed_cycles < CYCLES_MAX) { st->failed_cycles++; }
        st->aging_cycles = 0u;
        dtc->changed = true;
    }
    if (st->failed_cycles >= d->confirm_cycles) { st->status |= WC_DTC_CONFIRMED; }
    if (((st->status & WC_DTC_CONFIRMED) != 0u) && d->warning_indicator) { st->status |= WC_DTC_WIR; }
    if (st->entry == WC_DTC_NO_ENTRY) {  /* the first failure since it had none: the snapshot */
        store_entry(dtc, index);
        dtc->changed = true;
    }
    if (st->status != was) { dtc->changed = true; }
}

/* A qualified pass (D.2: bit 0 cleared, 4 and 6 cleared: the test completed). */
static void qualify_passed(wc_dtc_t *dtc, uint32_t index)
{
    wc_dtc_state_t *st = &dtc->state[index];
    const uint8_t was = st->status;
    st->status = (uint8_t)(was & ~(WC_DTC_TF | WC_DTC_TNCSLC | WC_DTC_TNCTOC));
    if (st->status != was) { dtc->changed = true; }
}

void wc_dtc_report(wc_dtc_t *dtc, uint32_t index, bool failed)
{
    if (!usable(dtc) || (index >= dtc->config.count)) { return; }
    const wc_dtc_definition_t *d = &dtc->config.definitions[index];
    wc_dtc_state_t *st = &dtc->state[index];
    const int32_t counter = (int32_t)st->debounce;  /* in [pass_threshold, fail_threshold] */
    if (failed) {
        const int32_t up = counter + (int32_t)d->fail_step;
        const bool qualified = up >= (int32_t)d->fail_threshold;
        st->debounce = qualified ? d->fail_threshold : (int16_t)up;
        if (qualified) { qualify_failed(dtc, index); }
    } else {
        const int32_t down = counter - (int32_t)d->pass_step;
        const bool qualified = down <= (int32_t)d->pass_threshold;
        st->debounce = qualified ? d->pass_threshold : (int16_t)down;
        if (qualified) { qualify_passed(dtc, index); }
    }
}

void wc_dtc_cycle_start(wc_dtc_t *dtc)
{
    if (!usable(dtc)) { return; }
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < dtc->config.count); ++i) {
        wc_dtc_state_t *st = &dtc->state[i];
        const uint8_t was = st->status;
        st->status = (uint8_t)((was & ~WC_DTC_TFTOC) | WC_DTC_TNCTOC);  /* D.2 bits 1 and 6 */
        st->debounce = 0;
        if (st->status != was) { dtc->changed = true; }
    }
    if (dtc->memory_lost_pending) {  /* the memory is whole again: that test passes */
        dtc->memory_lost_pending = false;
        qualify_passed(dtc, dtc->config.memory_lost);
    }
}

void wc_dtc_cycle_end(wc_dtc_t *dtc)
{
    if (!usable(dtc)) { return; }
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < dtc->config.count); ++i) {
        wc_dtc_state_t *st = &dtc->state[i];
        const uint8_t was = st->status;
        const bool tested = (was & WC_DTC_TNCTOC) == 0u;
        const bool failed_this_cycle = (was & WC_DTC_TFTOC) != 0u;
        if (tested && !failed_this_cycle) {  /* D.2 bit 2: no longer pending; bit 7: healed */
            st->status &= (uint8_t)~(WC_DTC_PENDING | WC_DTC_WIR);
            if ((st->status & WC_DTC_CONFIRMED) == 0u) { st->failed_cycles = 0u; }
        }
        const bool kept = (st->entry != WC_DTC_NO_ENTRY) || ((st->status & WC_DTC_CONFIRMED) != 0u);
        if (kept && !failed_this_cycle && ((was & WC_DTC_TF) == 0u)) {
            if (st->aging_cycles < CYCLES_MAX) { st->aging_cycles++; }
            dtc->changed = true;
            if (st->aging_cycles >= dtc->config.aging_cycles) {  /* aged out */
                if (st->entry != WC_DTC_NO_ENTRY) { dtc->entries[st->entry].definition = WC_DTC_NO_ENTRY; }
                st->entry = WC_DTC_NO_ENTRY;
                st->status &= (uint8_t)~(WC_DTC_CONFIRMED | WC_DTC_PENDING | WC_DTC_WIR);
                st->aging_cycles = 0u;
                st->failed_cycles = 0u;
            }
        }
        if (st->status != was) { dtc->changed = true; }
    }
}

bool wc_dtc_clear(wc_dtc_t *dtc, uint32_t group)
{
    if (!usable(dtc)) { return false; }
    if (group == WC_DTC_GROUP_ALL) {
        empty_memory(dtc);
        dtc->changed = true;
        return true;
    }
    const uint32_t index = wc_dtc_find(dtc, group);
    if (index == WC_DTC_NONE) { return false; }
    clear_one(dtc, index);
    dtc->changed = true;
    return true;
}

uint32_t wc_dtc_find(const wc_dtc_t *dtc, uint32_t number)
{
    if (!usable(dtc)) { return WC_DTC_NONE; }
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < dtc->config.count); ++i) {
        if (dtc->config.definitions[i].number == number) { return i; }
    }
    return WC_DTC_NONE;
}

uint8_t wc_dtc_status(const wc_dtc_t *dtc, uint32_t index)
{
    return (usable(dtc) && (index < dtc->config.count)) ? dtc->state[index].status : 0u;
}

const wc_dtc_snapshot_t *wc_dtc_snapshot(const wc_dtc_t *dtc, uint32_t index)
{
    if (!usable(dtc) || (index >= dtc->config.count) || (dtc->state[index].entry == WC_DTC_NO_ENTRY)) { return NULL; }
    return &dtc->entries[dtc->state[index].entry].snapshot;
}

uint32_t wc_dtc_fault_count(const wc_dtc_t *dtc, uint32_t index)
{
    return (usable(dtc) && (index < dtc->config.count)) ? dtc->state[index].fault_count : 0u;
}

bool wc_dtc_changed(const wc_dtc_t *dtc) { return usable(dtc) && dtc->changed; }

/* --------------------------------------------------------------- image */

size_t wc_dtc_image_write(wc_dtc_t *dtc, uint8_t *image, size_t capacity)
{
    if (!usable(dtc) || (image == NULL) || (capacity < (size_t)WC_DTC_IMAGE_BYTES)) { return 0u; }
    uint8_t *p = &image[WC_IMAGE_HEADER_BYTES];  /* encoded in place, then sealed (wc_image_seal) */
    memset(p, 0, WC_DTC_IMAGE_PAYLOAD_BYTES);
    wc_image_put_u32(&p[0], dtc->next_sequence);
    wc_image_put_u32(&p[4], dtc->overflows);
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < dtc->config.count); ++i) {
        uint8_t *slot = &p[SLOTS_AT + WC_DTC_SLOT_BYTES * i];
        const wc_dtc_state_t *st = &dtc->state[i];
        wc_image_put_u32(&slot[0], dtc->config.definitions[i].number);
        wc_image_put_u32(&slot[4], st->fault_count);
        slot[8] = st->status;
        slot[9] = st->failed_cycles;
        slot[10] = st->aging_cycles;
    }
    for (uint32_t e = 0u; e < WC_DTC_MAX_ENTRIES; ++e) {
        const wc_dtc_entry_t *entry = &dtc->entries[e];
        if (entry->definition == WC_DTC_NO_ENTRY) { continue; }
        uint8_t *q = &p[ENTRIES_AT + WC_DTC_ENTRY_BYTES * e];
        wc_image_put_u32(&q[0], dtc->config.definitions[entry->definition].number);
        wc_image_put_u32(&q[4], entry->sequence);
        float v[WC_DTC_SNAPSHOT_FLOATS];
        snapshot_floats(&entry->snapshot, v);
        for (uint32_t k = 0u; k < WC_DTC_SNAPSHOT_FLOATS; ++k) { wc_image_put_f32(&q[8u + 4u * k], v[k]); }
        q[8u + 4u * WC_DTC_SNAPSHOT_FLOATS] = entry->snapshot.shift_phase;
        q[9u + 4u * WC_DTC_SNAPSHOT_FLOATS] = entry->snapshot.gear;
    }
    const size_t written = wc_image_seal(image, capacity, WC_DTC_IMAGE_MAGIC, WC_DTC_IMAGE_VERSION,
                                         WC_DTC_IMAGE_PAYLOAD_BYTES);
    if (written > 0u) { dtc->changed = false; }
    return written;
}

static void restore(wc_dtc_t *dtc, const uint8_t *p)
{
    dtc->next_sequence = wc_image_get_u32(&p[0]);
    dtc->overflows = wc_image_get_u32(&p[4]);
    for (uint32_t s = 0u; s < WC_DTC_MAX_DEFINITIONS; ++s) {
        const uint8_t *slot = &p[SLOTS_AT + WC_DTC_SLOT_BYTES * s];
        const uint32_t i = wc_dtc_find(dtc, wc_image_get_u32(&slot[0]));
        if (i == WC_DTC_NONE) { continue; }  /* unused, or a DTC this table no longer has */
        wc_dtc_state_t *st = &dtc->state[i];
        st->fault_count = wc_image_get_u32(&slot[4]);
        st->status = slot[8];
        st->failed_cycles = slot[9];
        st->aging_cycles = slot[10];
    }
    for (uint32_t e = 0u; e < WC_DTC_MAX_ENTRIES; ++e) {
        const uint8_t *q = &p[ENTRIES_AT + WC_DTC_ENTRY_BYTES * e];
        const uint32_t i = wc_dtc_find(dtc, wc_image_get_u32(&q[0]));
        if ((i == WC_DTC_NONE) || (dtc->state[i].entry != WC_DTC_NO_ENTRY)) { continue; }  /* unknown or twice */
        wc_dtc_entry_t *entry = &dtc->entries[e];
        entry->definition = (uint8_t)i;
        entry->sequence = wc_image_get_u32(&q[4]);
        float v[WC_DTC_SNAPSHOT_FLOATS];
        for (uint32_t k = 0u; k < WC_DTC_SNAPSHOT_FLOATS; ++k) { v[k] = wc_image_get_f32(&q[8u + 4u * k]); }
        snapshot_from_floats(&entry->snapshot, v);
        entry->snapshot.shift_phase = q[8u + 4u * WC_DTC_SNAPSHOT_FLOATS];
        entry->snapshot.gear = q[9u + 4u * WC_DTC_SNAPSHOT_FLOATS];
        dtc->state[i].entry = (uint8_t)e;
    }
}

uint32_t wc_dtc_image_load(wc_dtc_t *dtc, const uint8_t *image, size_t length)
{
    if (!usable(dtc)) { return (uint32_t)WC_IMAGE_MISSING; }
    const uint8_t *payload = NULL;
    const wc_image_status_t result = wc_image_read(image, length, WC_DTC_IMAGE_MAGIC, WC_DTC_IMAGE_VERSION,
                                                   WC_DTC_IMAGE_PAYLOAD_BYTES, &payload);
    empty_memory(dtc);
    dtc->changed = false;
    if ((result == WC_IMAGE_OK) && (payload != NULL)) {
        restore(dtc, payload);
    } else if ((result != WC_IMAGE_MISSING) && (dtc->config.memory_lost != WC_DTC_NONE)) {
        /* the memory was lost: its DTC fails at once, confirmed and stored (wc_dtc.h) */
        const uint32_t lost = dtc->config.memory_lost;
        dtc->state[lost].failed_cycles = (uint8_t)(dtc->config.definitions[lost].confirm_cycles - 1u);
        qualify_failed(dtc, lost);  /* failed_cycles reaches confirm_cycles: confirmed */
        dtc->memory_lost_pending = true;
        dtc->changed = true;
    }
    return (uint32_t)result;
}
