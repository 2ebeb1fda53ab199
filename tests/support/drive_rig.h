/* The drive arm (firmware/drives/ls_drives) against the simulated CiA 402
 * drives (hal/sim/drives) in one process: two in-memory CAN links joined
 * back to back, time driven by the caller, nothing sleeps. For the drive
 * arm's unit tests (tests/unit/drives/test_drives_sim.c) and its fuzzer
 * (tests/fuzz/fuzz_drives.c). One rig per process: the world and the
 * simulated drives are static. */
#ifndef DRIVE_RIG_H
#define DRIVE_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_arm.h"
#include "ls_drives.h"

#define DRIVE_RIG_JOINTS 6
#define DRIVE_RIG_CPR 100000.0     /* counts per radian, both sides */
#define DRIVE_RIG_HOME_OFFSET 5000 /* joint 2's 0x607C: 0.05 rad after homing */

/* Six simulated drives (nodes 0x21..0x26) as ls_drive_setup derives them
 * from their EDS: every readout mapped (brake, STO, temperature, torque,
 * velocity), joint 2 to be homed with "home here" (37) to
 * DRIVE_RIG_HOME_OFFSET, the mode in the PDOs of every joint when
 * map_mode (else homing changes modes over SDO). */
ls_drives_config_t drive_rig_config(bool map_mode);

/* The world, the simulated drives and the arm of `c` (whose link the rig
 * sets), booted: LS_OK with *arm the drives' arm and *now_us the time, or
 * a negative status with msg naming what failed (everything closed). */
int drive_rig_open(const ls_drives_config_t *c, ls_drives_t *d, hal_arm_t *arm, uint64_t *now_us, char *msg,
                   size_t msglen);

/* `ms` milliseconds: per ms the arm's update() at the new time, then the
 * simulated drives' poll (while attached). */
void drive_rig_step(hal_arm_t *arm, uint64_t *now_us, unsigned ms);

/* The simulated drives and the world closed; the arm's frames go nowhere
 * and drive_rig_inject is its only peer from now on. */
void drive_rig_detach(void);

/* Close what is open (idempotent). */
void drive_rig_close(void);

/* A frame to the arm as if from its bus; both queues emptied. */
void drive_rig_inject(const hal_can_frame_t *f);
void drive_rig_clear(void);

/* Frames the arm sent that are no 11-bit data frame of 0..8 bytes. */
unsigned drive_rig_bad_frames(void);

#endif
