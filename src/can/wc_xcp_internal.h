/* Private to the XCP slave (wc_xcp.c, wc_xcp_memory.c). */
#ifndef WC_XCP_INTERNAL_H
#define WC_XCP_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "wetclutch_can/wc_xcp.h"

#define XCP_OK 0x100u   /* a handler's positive result (error codes are < 0x100) */

/* The bytes at [address, address + length) when they lie inside one region:
 * *bytes points at them. write: the working page only, and only while the
 * XCP page is the working page; a read-only page not given (the gearbox, an
 * element): ERR_ACCESS_DENIED. Returns XCP_OK or the error. */
uint32_t wc_xcp_resolve(wc_xcp_t *x, uint32_t address, uint32_t extension, uint32_t length, bool write,
                        uint8_t **bytes);

#endif /* WC_XCP_INTERNAL_H */
