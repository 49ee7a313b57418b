/* The XCP master's command frames for the Cortex-M4F probe (wc_arm_xcp.h). */
#include "wc_arm_xcp.h"

#include <stddef.h>

#include <wetclutch_can/wc_can.h>

/* The 8 floats of the step's output a calibration engineer watches: the
 * command, the pressures, the force, the temperature, the torque model. */
static const uint32_t signal_offset[WC_ARM_XCP_DAQ_SIGNALS] = {
    (uint32_t)offsetof(wc_loop_t, last.current_mA),
    (uint32_t)offsetof(wc_loop_t, last.pressure_command_Pa),
    (uint32_t)offsetof(wc_loop_t, last.pressure_model_Pa),
    (uint32_t)offsetof(wc_loop_t, last.force_command_N),
    (uint32_t)offsetof(wc_loop_t, last.theta_degC),
    (uint32_t)offsetof(wc_loop_t, last.contact_force_N),
    (uint32_t)offsetof(wc_loop_t, last.model.torque_Nm),
    (uint32_t)offsetof(wc_loop_t, last.model.mu_f),
};

uint32_t wc_arm_xcp_signal_offset(uint32_t i)
{
    return (i < WC_ARM_XCP_DAQ_SIGNALS) ? signal_offset[i] : 0u;
}

wc_can_frame_t wc_arm_xcp_frame(const uint8_t *bytes, uint32_t length)
{
    wc_can_frame_t frame = {WC_CAN_XCP_COMMAND_FRAME_ID, 8u, 0u, {0u}};
    for (uint32_t i = 0u; (i < length) && (i < 8u); ++i) { frame.data[i] = bytes[i]; }
    return frame;
}

static void put_u32(uint8_t *dst, uint32_t value)
{
    for (uint32_t i = 0u; i < 4u; ++i) { dst[i] = (uint8_t)((value >> (8u * i)) & 0xFFu); }
}

wc_can_frame_t wc_arm_xcp_connect(void)
{
    const uint8_t cmd[2] = {WC_XCP_CONNECT, 0x00u};  /* mode: normal */
    return wc_arm_xcp_frame(cmd, sizeof cmd);
}

wc_can_frame_t wc_arm_xcp_set_mta(uint32_t address)
{
    uint8_t cmd[8] = {WC_XCP_SET_MTA, 0u, 0u, 0u /* extension */};
    put_u32(&cmd[4], address);
    return wc_arm_xcp_frame(cmd, sizeof cmd);
}

wc_can_frame_t wc_arm_xcp_build_checksum(uint32_t length)
{
    uint8_t cmd[8] = {WC_XCP_BUILD_CHECKSUM};
    put_u32(&cmd[4], length);  /* block size */
    return wc_arm_xcp_frame(cmd, sizeof cmd);
}

wc_can_frame_t wc_arm_xcp_download(const uint8_t *bytes, uint32_t length)
{
    uint8_t cmd[8] = {WC_XCP_DOWNLOAD, (uint8_t)length};
    for (uint32_t i = 0u; (i < length) && (i < 6u); ++i) { cmd[2u + i] = bytes[i]; }
    return wc_arm_xcp_frame(cmd, sizeof cmd);
}

uint32_t wc_arm_xcp_daq_setup(uint32_t loop_base, wc_can_frame_t frames[WC_ARM_XCP_DAQ_SETUP_FRAMES])
{
    uint32_t n = 0u;
    const uint8_t free_daq[1] = {WC_XCP_FREE_DAQ};
    frames[n++] = wc_arm_xcp_frame(free_daq, sizeof free_daq);
    const uint8_t alloc_daq[4] = {WC_XCP_ALLOC_DAQ, 0u, 1u, 0u};  /* 1 list */
    frames[n++] = wc_arm_xcp_frame(alloc_daq, sizeof alloc_daq);
    const uint8_t alloc_odt[5] = {WC_XCP_ALLOC_ODT, 0u, 0u, 0u, (uint8_t)WC_ARM_XCP_DAQ_SIGNALS};  /* list 0 */
    frames[n++] = wc_arm_xcp_frame(alloc_odt, sizeof alloc_odt);
    for (uint32_t odt = 0u; odt < WC_ARM_XCP_DAQ_SIGNALS; ++odt) {
        const uint8_t alloc_entry[6] = {WC_XCP_ALLOC_ODT_ENTRY, 0u, 0u, 0u, (uint8_t)odt, 1u};  /* 1 entry */
        frames[n++] = wc_arm_xcp_frame(alloc_entry, sizeof alloc_entry);
    }
    for (uint32_t odt = 0u; odt < WC_ARM_XCP_DAQ_SIGNALS; ++odt) {
        const uint8_t set_ptr[6] = {WC_XCP_SET_DAQ_PTR, 0u, 0u, 0u, (uint8_t)odt, 0u};  /* list 0, entry 0 */
        frames[n++] = wc_arm_xcp_frame(set_ptr, sizeof set_ptr);
        uint8_t write[8] = {WC_XCP_WRITE_DAQ, 0xFFu /* no bit offset */, 4u /* size */, 0u /* extension */};
        put_u32(&write[4], loop_base + signal_offset[odt]);
        frames[n++] = wc_arm_xcp_frame(write, sizeof write);
    }
    /* mode TIMESTAMP, list 0, event 0, prescaler 1, priority 0 */
    const uint8_t list_mode[8] = {WC_XCP_SET_DAQ_LIST_MODE, 0x10u, 0u, 0u, 0u, 0u, 1u, 0u};
    frames[n++] = wc_arm_xcp_frame(list_mode, sizeof list_mode);
    const uint8_t select[4] = {WC_XCP_START_STOP_DAQ_LIST, 2u /* select */, 0u, 0u};
    frames[n++] = wc_arm_xcp_frame(select, sizeof select);
    const uint8_t start[2] = {WC_XCP_START_STOP_SYNCH, 1u /* start selected */};
    frames[n++] = wc_arm_xcp_frame(start, sizeof start);
    return n;
}
