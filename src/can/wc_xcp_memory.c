/* The XCP slave's memory map (wc_xcp.h, "Memory the master may touch"):
 * the regions, the read-only pages a transmission adds (the gearbox, each
 * element's clutch) and the resolution of an address to its bytes. */
#include "wc_xcp_internal.h"

#include "wetclutch/wetclutch.h"
#include "wetclutch_can/wc_gearbox_image.h"

void wc_xcp_regions(const wc_xcp_t *xcp, wc_xcp_region_t regions[WC_XCP_REGIONS])
{
    WC_ASSERT((xcp != NULL) && (regions != NULL));
    if ((xcp == NULL) || (regions == NULL)) { return; }
    regions[0] = (wc_xcp_region_t){ xcp->config.cal_base, wc_cal_image_payload_bytes };
    regions[1] = (wc_xcp_region_t){ xcp->config.loop_base, (uint32_t)sizeof(wc_loop_t) };
    regions[2] = (wc_xcp_region_t){ xcp->config.status_base, (uint32_t)sizeof(wc_xcp_status_t) };
    regions[3] = (wc_xcp_region_t){ xcp->config.id_base, WC_XCP_ID_BYTES };
    regions[4] = (wc_xcp_region_t){ xcp->config.gearbox_base, wc_gearbox_image_payload_bytes };
    for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
        regions[WC_XCP_FIRST_ELEMENT_REGION + e] =
            (wc_xcp_region_t){ xcp->config.element_base + e * WC_XCP_ELEMENT_STRIDE, wc_cal_image_payload_bytes };
    }
}

void wc_xcp_set_element(wc_xcp_t *xcp, uint32_t element, const uint8_t *element_payload)
{
    WC_ASSERT(xcp != NULL);
    if ((xcp != NULL) && (element < WC_GEARBOX_ELEMENTS_MAX)) { xcp->element_page[element] = element_payload; }
}

void wc_xcp_set_gearbox(wc_xcp_t *xcp, const uint8_t *gearbox_payload)
{
    WC_ASSERT(xcp != NULL);
    if (xcp != NULL) { xcp->gearbox_page = gearbox_payload; }
}

uint32_t wc_xcp_resolve(wc_xcp_t *x, uint32_t address, uint32_t extension, uint32_t length, bool write,
                        uint8_t **bytes)
{
    if (extension != 0u) { return WC_XCP_ERR_ACCESS_DENIED; }
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(x, regions);
    uint8_t *base[WC_XCP_REGIONS] = {  /* cppcheck-suppress constVariable ; written through (DOWNLOAD) */
        (x->xcp_page == 0u) ? x->working_page : (uint8_t *)(uintptr_t)x->reference_page,
        (uint8_t *)x->loop, (uint8_t *)&x->status, (uint8_t *)x->id, (uint8_t *)(uintptr_t)x->gearbox_page };
    for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
        base[WC_XCP_FIRST_ELEMENT_REGION + e] = (uint8_t *)(uintptr_t)x->element_page[e];
    }
    for (uint32_t r = 0u; r < WC_XCP_REGIONS; ++r) {
        const uint32_t offset = address - regions[r].base;  /* wraps for an address below the base */
        if ((address >= regions[r].base) && (offset <= regions[r].size) && (length <= regions[r].size - offset)) {
            if (base[r] == NULL) { return WC_XCP_ERR_ACCESS_DENIED; }  /* no gearbox or element given */
            if (write && ((r != 0u) || (x->xcp_page != 0u))) { return WC_XCP_ERR_WRITE_PROTECTED; }
            *bytes = base[r] + offset;
            return XCP_OK;
        }
    }
    return WC_XCP_ERR_ACCESS_DENIED;
}
