/* libFuzzer target: the drive arm (firmware/drives/ls_drives) under any
 * frames of its drives' services and any sequence of the HAL arm's calls.
 *
 * Once per process the arm boots against the simulated drives in this
 * process (tests/support/drive_rig.h) with every readout mapped and joint 2
 * homing with the mode in its PDOs, enables, and is saved. Each input starts from that saved arm (its pointers point
 * into itself, so a copy back is the same arm), with the simulated drives
 * gone: the input is the only peer. Its bytes are a script:
 *   0: a frame: a service (TPDO1/TPDO2 with any bytes and length, EMCY,
 *      heartbeat, boot-up, an SDO answer), a node, a length and data
 *   1: time: 1..64 ms, one update() per ms (SYNCs, RPDOs, time-outs)
 *   2: enable(on/off)
 *   3: home(mask)
 *   4: command() with set-points from the input
 *   5: status(), readout() and every event taken
 * Checked: nothing crashes or trips ASan/UBSan; every frame the arm sends is
 * an 11-bit data frame of 0..8 bytes; status() and readout() say what they
 * promise (states in range, a text that ends, static names that are
 * strings, a homing state in range). */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drive_rig.h"
#include "ls_canopen.h"
#include "ls_drives.h"

#define NJ DRIVE_RIG_JOINTS

static ls_drives_t g_d, g_saved;
static uint64_t g_saved_now, g_now;
static hal_arm_t g_arm;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    /* joint 2 homes with the mode in its PDOs, the others over SDO; signs
     * and an inverted STO bit vary the decoding */
    ls_drives_config_t c = drive_rig_config(false);
    c.joint[1].map_mode = true;
    for (int j = 1; j < NJ; j += 2) {
        c.joint[j].scale.sign = -1;
    }
    c.joint[3].sto.inverted = true;
    char msg[200] = "";
    if (drive_rig_open(&c, &g_d, &g_arm, &g_now, msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "fuzz_drives: %s\n", msg);
        abort();
    }
    (void)hal_arm_enable(&g_arm, true);
    drive_rig_step(&g_arm, &g_now, 100);
    /* from here on the input is the drives' only voice */
    drive_rig_detach();
    g_saved = g_d;
    g_saved_now = g_now;
    return 0;
}

static const uint32_t k_services[] = { LS_CO_COB_TPDO1, LS_CO_COB_TPDO1 + 0x100u, LS_CO_COB_EMCY, LS_CO_COB_HEARTBEAT,
                                       LS_CO_COB_SDO_TX };

static void check_views(void)
{
    hal_joint_status_t st[NJ];
    if (hal_arm_status(&g_arm, true, NJ, st) != LS_OK) {
        abort();
    }
    for (int j = 0; j < NJ; j++) {
        if ((unsigned)st[j].state > (unsigned)HAL_JOINT_LOST || (unsigned)st[j].home > (unsigned)HAL_HOME_FAILED ||
            memchr(st[j].text, '\0', sizeof st[j].text) == NULL) {
            abort();
        }
    }
    hal_arm_readout_t r;
    (void)hal_arm_readout(&g_arm, &r);
    if (r.n_joints > HAL_ARM_MAX_JOINTS || r.n_counters > HAL_READOUT_COUNTERS) {
        abort();
    }
    for (uint8_t j = 0; j < r.n_joints; j++) {
        const hal_drive_readout_t *o = &r.joint[j];
        if (o->state == NULL || o->error_name == NULL || strlen(o->state) > 32u ||
            (unsigned)o->home > (unsigned)HAL_HOME_FAILED) {
            abort();
        }
    }
    hal_arm_event_t ev;
    for (int k = 0; k < 64 && hal_arm_next_event(&g_arm, &ev) == 1; k++) {
        if (memchr(ev.text, '\0', sizeof ev.text) == NULL || memchr(ev.meaning, '\0', sizeof ev.meaning) == NULL) {
            abort();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    g_d = g_saved;
    g_now = g_saved_now;
    drive_rig_clear();
    ls_drives_arm(&g_d, &g_arm);
    size_t i = 0;
    while (i < size) {
        const uint8_t op = data[i++] % 6u;
        const uint8_t a = i < size ? data[i++] : 0u;
        switch (op) {
        case 0: {
            hal_can_frame_t f;
            memset(&f, 0, sizeof f);
            const uint8_t node = (uint8_t)(0x21 + (a >> 4) % 8u); /* two ids beyond the arm's */
            f.id = k_services[(a & 0x0Fu) % (sizeof k_services / sizeof k_services[0])] + node;
            f.len = i < size ? (uint8_t)(data[i++] % 9u) : 0u;
            for (uint8_t k = 0; k < f.len && i < size; k++) {
                f.data[k] = data[i++];
            }
            drive_rig_inject(&f);
            break;
        }
        case 1: drive_rig_step(&g_arm, &g_now, 1u + (unsigned)(a % 64u)); break;
        case 2: (void)hal_arm_enable(&g_arm, (a & 1u) != 0u); break;
        case 3: (void)hal_arm_home(&g_arm, a); break;
        case 4: {
            double q[NJ], qd[NJ];
            (void)hal_arm_read(&g_arm, q, qd);
            for (int j = 0; j < NJ; j++) {
                q[j] += ((double)(int8_t)a) * 1e-3 * (double)(j + 1);
            }
            (void)hal_arm_command(&g_arm, q, qd);
            break;
        }
        default: check_views(); break;
        }
    }
    check_views();
    if (drive_rig_bad_frames() != 0u) {
        abort(); /* the arm sends 11-bit data frames only */
    }
    return 0;
}
