/* The master's side of the XCP session that the Cortex-M4F probe measures
 * the slave in (wc_xcp.h): the command frames a calibration tool (CANape,
 * INCA, pyxcp) sends, built byte by byte as ASAM XCP part 2 lays them out.
 * Every frame is an XcpCommand frame padded to DLC 8. */
#ifndef WC_ARM_XCP_H
#define WC_ARM_XCP_H

#include <stdint.h>

#include <wetclutch_can/wc_xcp.h>

/* The DAQ list of the probe: 8 float signals of wc_loop_t.last, one per ODT
 * (the first ODT carries the 2-byte timestamp too), event 0 (the control
 * step), prescaler 1, timestamps on. */
#define WC_ARM_XCP_DAQ_SIGNALS 8u
/* FREE_DAQ, ALLOC_DAQ, ALLOC_ODT, ALLOC_ODT_ENTRY per ODT, SET_DAQ_PTR + WRITE_DAQ
 * per signal, SET_DAQ_LIST_MODE, START_STOP_DAQ_LIST (select), START_STOP_SYNCH (start) */
#define WC_ARM_XCP_DAQ_SETUP_FRAMES (3u + 3u * WC_ARM_XCP_DAQ_SIGNALS + 3u)

/* A command frame: bytes[0..length) then zeros. */
wc_can_frame_t wc_arm_xcp_frame(const uint8_t *bytes, uint32_t length);

wc_can_frame_t wc_arm_xcp_connect(void);
wc_can_frame_t wc_arm_xcp_set_mta(uint32_t address);
wc_can_frame_t wc_arm_xcp_build_checksum(uint32_t length);
/* DOWNLOAD of length (1..6) bytes at the MTA. */
wc_can_frame_t wc_arm_xcp_download(const uint8_t *bytes, uint32_t length);

/* The configuration of the probe's DAQ list, in the order a master sends
 * it; loop_base: the loop region's XCP address (wc_xcp_config_t.loop_base).
 * Returns the number of frames. */
uint32_t wc_arm_xcp_daq_setup(uint32_t loop_base, wc_can_frame_t frames[WC_ARM_XCP_DAQ_SETUP_FRAMES]);

/* Offset in wc_loop_t of DAQ signal i (a float of wc_loop_t.last). */
uint32_t wc_arm_xcp_signal_offset(uint32_t i);

#endif /* WC_ARM_XCP_H */
