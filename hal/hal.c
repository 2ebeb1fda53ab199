/* Thin wrappers of the HAL contracts: an operation a backend leaves NULL
 * answers LS_EUNSUPPORTED, so callers never test for NULL themselves. */
#include <stddef.h>
#include <string.h>

#include "hal/hal_arm.h"
#include "hal/hal_can.h"
#include "hal/hal_clock.h"
#include "hal/hal_dio.h"
#include "hal/hal_manual.h"

#define HAL_CALL(obj, op, ...)                                                                                         \
    (((obj) != NULL && (obj)->ops != NULL && (obj)->ops->op != NULL) ? (obj)->ops->op((obj)->self, __VA_ARGS__)        \
                                                                     : LS_EUNSUPPORTED)
#define HAL_CALL0(obj, op)                                                                                             \
    (((obj) != NULL && (obj)->ops != NULL && (obj)->ops->op != NULL) ? (obj)->ops->op((obj)->self) : LS_EUNSUPPORTED)

#define NO_FD (-1) /* poll_fd: no descriptor to wait on (hal_can.h, hal_dio.h) */

int hal_can_send(hal_can_link_t *link, const hal_can_frame_t *frame)
{
    return HAL_CALL(link, send, frame);
}
int hal_can_recv(hal_can_link_t *link, hal_can_frame_t *frame)
{
    return HAL_CALL(link, recv, frame);
}
int hal_can_poll_fd(hal_can_link_t *link)
{
    int fd = HAL_CALL0(link, poll_fd);
    return fd == LS_EUNSUPPORTED ? NO_FD : fd;
}
int hal_can_status(hal_can_link_t *link, hal_can_status_t *out)
{
    return HAL_CALL(link, status, out);
}
void hal_can_close(hal_can_link_t *link)
{
    if (link != NULL && link->ops != NULL && link->ops->close != NULL) {
        link->ops->close(link->self);
    }
}

int hal_can_hold_open(hal_can_link_t *link, bool hold)
{
    return HAL_CALL(link, hold_open, hold);
}

bool hal_can_tx_pending(hal_can_link_t *link)
{
    return link != NULL && link->ops != NULL && link->ops->tx_pending != NULL && link->ops->tx_pending(link->self);
}

uint64_t hal_can_next_due_us(hal_can_link_t *link)
{
    if (link == NULL || link->ops == NULL || link->ops->next_due_us == NULL) {
        return UINT64_MAX;
    }
    return link->ops->next_due_us(link->self);
}

int hal_dio_unit_count(hal_dio_t *dio)
{
    return HAL_CALL0(dio, unit_count);
}
int hal_dio_describe(hal_dio_t *dio, uint16_t unit, hal_dio_unit_info_t *out)
{
    return HAL_CALL(dio, describe, unit, out);
}
int hal_dio_read(hal_dio_t *dio, uint16_t unit, uint32_t *bits)
{
    return HAL_CALL(dio, read, unit, bits);
}
int hal_dio_write(hal_dio_t *dio, uint16_t unit, uint32_t on, uint32_t off)
{
    return HAL_CALL(dio, write, unit, on, off);
}
int hal_dio_poll_fd(hal_dio_t *dio)
{
    int fd = HAL_CALL0(dio, poll_fd);
    return fd == LS_EUNSUPPORTED ? NO_FD : fd;
}
int hal_dio_drain_events(hal_dio_t *dio)
{
    return HAL_CALL0(dio, drain_events);
}
void hal_dio_close(hal_dio_t *dio)
{
    if (dio != NULL && dio->ops != NULL && dio->ops->close != NULL) {
        dio->ops->close(dio->self);
    }
}

int hal_arm_info(hal_arm_t *arm, hal_arm_info_t *out)
{
    if (out != NULL) {
        memset(out, 0, sizeof *out); /* what a backend leaves unset is 0 */
    }
    return HAL_CALL(arm, info, out);
}
int hal_arm_enable(hal_arm_t *arm, bool on)
{
    return HAL_CALL(arm, enable, on);
}
int hal_arm_command(hal_arm_t *arm, const double *q_rad, const double *qd_rad_s)
{
    return HAL_CALL(arm, command, q_rad, qd_rad_s);
}
int hal_arm_read(hal_arm_t *arm, double *q_rad, double *qd_rad_s)
{
    return HAL_CALL(arm, read, q_rad, qd_rad_s);
}
void hal_arm_close(hal_arm_t *arm)
{
    if (arm != NULL && arm->ops != NULL && arm->ops->close != NULL) {
        arm->ops->close(arm->self);
    }
}
int hal_arm_status(hal_arm_t *arm, bool enabled, uint8_t n_joints, hal_joint_status_t *out)
{
    if (out == NULL || n_joints > HAL_ARM_MAX_JOINTS) {
        return LS_EINVAL;
    }
    if (arm != NULL && arm->ops != NULL && arm->ops->status != NULL) {
        return arm->ops->status(arm->self, out);
    }
    for (uint8_t j = 0; j < n_joints; j++) {
        memset(&out[j], 0, sizeof out[j]);
        out[j].state = enabled ? HAL_JOINT_ENABLED : HAL_JOINT_OFF;
    }
    return LS_OK;
}
int hal_arm_next_event(hal_arm_t *arm, hal_arm_event_t *out)
{
    if (arm != NULL && arm->ops != NULL && arm->ops->next_event != NULL) {
        return arm->ops->next_event(arm->self, out);
    }
    return 0;
}
int hal_arm_home(hal_arm_t *arm, uint32_t joint_mask)
{
    return HAL_CALL(arm, home, joint_mask);
}
int hal_arm_readout(hal_arm_t *arm, hal_arm_readout_t *out)
{
    return HAL_CALL(arm, readout, out);
}
const char *hal_home_name(hal_home_t home)
{
    switch (home) {
    case HAL_HOME_NOT_HOMED: return "not_homed";
    case HAL_HOME_HOMING: return "homing";
    case HAL_HOME_HOMED: return "homed";
    case HAL_HOME_FAILED: return "failed";
    }
    return "?";
}
int hal_arm_update(hal_arm_t *arm, uint64_t now_us)
{
    if (arm != NULL && arm->ops != NULL && arm->ops->update != NULL) {
        return arm->ops->update(arm->self, now_us);
    }
    return LS_OK;
}

const char *hal_manual_button_name(unsigned index)
{
    /* in the order of the HAL_MANUAL_BTN_* bits */
    static const char *const names[HAL_MANUAL_BTN_COUNT] = { "enable",     "panic", "speed_up",
                                                             "speed_down", "frame", "joint" };
    return index < HAL_MANUAL_BTN_COUNT ? names[index] : NULL;
}

const char *hal_manual_axis_name(unsigned index)
{
    static const char *const names[6] = { "vx", "vy", "vz", "wx", "wy", "wz" };
    return index < 6u ? names[index] : NULL;
}

int hal_manual_read(const hal_manual_t *dev, hal_manual_state_t *out)
{
    if (out == NULL) {
        return LS_EINVAL;
    }
    if (dev == NULL || dev->read == NULL) {
        memset(out, 0, sizeof *out);
        return LS_EUNSUPPORTED;
    }
    int st = dev->read(dev->self, out);
    if (st < 0) {
        memset(out, 0, sizeof *out);
    }
    return st;
}

uint64_t hal_clock_now_us(const hal_clock_t *clock)
{
    return clock->now_us(clock->self);
}
