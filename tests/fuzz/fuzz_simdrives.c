/* The simulated drives (hal/sim/drives) under any bus traffic and any
 * control commands: the bytes are a script of frames (aimed at the
 * drives' COB-IDs most of the time), control datagrams and time steps, run
 * against two nodes on a fresh world. Nothing may crash, read out of bounds
 * or overflow (ASan/UBSan), and every frame the nodes send is a valid CAN
 * frame on an 11-bit COB-ID. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hal_sim_drives.h"
#include "hal_sim_world.h"
#include "ls_canopen.h"
#include "ls_robot_model_sim.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int check_send(void *self, const hal_can_frame_t *f)
{
    (void)self;
    if (f->len > 8u || f->id > LS_CO_COB_MASK || f->flags != 0u) {
        abort();
    }
    return LS_OK;
}
static int no_recv(void *self, hal_can_frame_t *f)
{
    (void)self;
    (void)f;
    return LS_EAGAIN;
}
static const hal_can_ops_t k_ops = { .send = check_send, .recv = no_recv };
static hal_can_link_t g_link = { .ops = &k_ops };

/* Function codes of the predefined connection set, and the nodes. */
static const uint32_t k_fc[] = { LS_CO_COB_NMT,
                                 LS_CO_COB_SYNC,
                                 LS_CO_COB_TPDO1,
                                 LS_CO_COB_RPDO1,
                                 LS_CO_COB_RPDO1 + 0x100u,
                                 LS_CO_COB_RPDO1 + 0x200u,
                                 LS_CO_COB_RPDO1 + 0x300u,
                                 LS_CO_COB_SDO_TX,
                                 LS_CO_COB_SDO_RX,
                                 LS_CO_COB_HEARTBEAT };
static const uint32_t k_node[] = { 0u, 0x21u, 0x22u, 0x7Fu };

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hal_sim_arm_model_t am;
    ls_robot_model_to_sim(&ls_robot_model_default, &am);
    hal_sim_world_config_t wc = { .arm = &am };
    char msg[200];
    if (hal_sim_world_open(&wc, msg, sizeof msg) != LS_OK) {
        abort();
    }
    hal_sim_drives_config_t dc = { .link = &g_link, .n_drives = 2, .counts_per_rad = 2086075.67 };
    dc.drives[0] = (hal_sim_drive_config_t){ 0x21, 0, 0 };
    dc.drives[1] = (hal_sim_drive_config_t){ 0x22, 1, INT32_MAX - 1000 };
    uint64_t now = 1000000u;
    if (hal_sim_drives_open(&dc, now, msg, sizeof msg) != LS_OK) {
        abort();
    }
    size_t i = 0;
    while (i < size) {
        uint8_t op = data[i++];
        switch (op % 4u) {
        case 0:
        case 1: { /* a frame: function code + node, length, data */
            if (i + 2 > size) {
                i = size;
                break;
            }
            hal_can_frame_t f = { 0 };
            f.id = op & 0x80u ? (uint32_t)(data[i] << 8 | data[i + 1]) & LS_CO_COB_MASK
                              : k_fc[data[i] % (sizeof k_fc / sizeof k_fc[0])] +
                                    k_node[data[i + 1] % (sizeof k_node / sizeof k_node[0])];
            if (f.id == LS_CO_COB_SYNC + 0u && (data[i + 1] & 3u) != 0u) {
                f.id = LS_CO_COB_SYNC; /* SYNC carries no node id */
            }
            i += 2;
            f.len = (uint8_t)(i < size ? data[i++] % 9u : 0u);
            size_t n = f.len <= size - i ? f.len : size - i;
            memcpy(f.data, data + i, n);
            i += n;
            f.flags = (op & 0x40u) ? HAL_CAN_F_RTR : 0u;
            (void)hal_sim_drives_rx(&f, now);
            break;
        }
        case 2: { /* a control datagram */
            size_t n = i < size ? data[i++] : 0u;
            n = n <= size - i ? n : size - i;
            (void)hal_sim_drives_control((const char *)data + i, n, now);
            i += n;
            break;
        }
        default: /* time passes */
            now += (uint64_t)(op >> 2) * 1000u;
            (void)hal_sim_drives_poll(now);
            break;
        }
    }
    hal_sim_drives_close();
    hal_sim_world_close();
    return 0;
}
