/* A classic CAN frame as the portable loop sees it (no OS types). */
#ifndef WC_CAN_FRAME_H
#define WC_CAN_FRAME_H

#include <stdint.h>

#define WC_CAN_FLAG_EXTENDED 0x1u  /* 29-bit identifier */
#define WC_CAN_FLAG_REMOTE   0x2u  /* remote transmission request */
#define WC_CAN_FLAG_ERROR    0x4u  /* error frame */

typedef struct {
    uint32_t id;       /* identifier without flag bits */
    uint8_t dlc;       /* data length, 0..8 */
    uint8_t flags;     /* WC_CAN_FLAG_* */
    uint8_t data[8];
} wc_can_frame_t;

#endif /* WC_CAN_FRAME_H */
