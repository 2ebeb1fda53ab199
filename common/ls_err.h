/* The one error space of the C code (firmware, HAL, tools): zero or positive
 * is success (often a count), negative is one of these. Every module returns
 * these names and no other negative status; what a module can return is in
 * its header. Header and ls_err.c only: includes nothing, allocates nothing. */
#ifndef LS_ERR_H
#define LS_ERR_H

#ifdef __cplusplus
extern "C" {
#endif

#define LS_OK 0
/* Devices (the HAL and its backends). */
#define LS_EUNSUPPORTED (-1) /* the backend does not offer this operation or device */
#define LS_EAGAIN (-2)       /* nothing now (no frame, TX queue full): try again later */
#define LS_EIO (-3)          /* the device failed; see the backend's last message */
#define LS_EINVAL (-4)       /* an argument is invalid: NULL, non-finite, out of range, bad configuration */
#define LS_ENODEV (-5)       /* the device (interface, chip, line) does not exist */
#define LS_EPERM (-6)        /* no permission (run as root or fix udev rules) */
#define LS_EBUSOFF (-7)      /* CAN controller is bus-off */
#define LS_ENOAFCAN (-8)     /* the kernel has no AF_CAN (no CONFIG_CAN / can module) */
/* ISO-TP. */
#define LS_EBUSY (-9) /* a transmission is already in progress */
#define LS_ELEN (-10) /* length 0 or beyond the largest message */
/* Trajectories and motion planning. */
#define LS_ETIME (-11)        /* requested duration shorter than the axis's minimum time */
#define LS_EUNREACHABLE (-12) /* the pose is outside the reachable space */
#define LS_ESINGULAR (-13)    /* shoulder singularity: q1 undetermined */
#define LS_ELIMITS (-14)      /* reachable, but no branch within the joint limits */
#define LS_ERANGE (-15)       /* a joint, velocity or workspace limit, or unreachable */
#define LS_EGEOM (-16)        /* degenerate geometry: collinear or coinciding arc points */
/* Field buses (CANopen drives). */
#define LS_ETIMEDOUT (-17) /* the peer did not answer within its time-out (SDO, boot-up, heartbeat) */
#define LS_EABORTED (-18)  /* the peer refused the transfer (an SDO abort code says why) */
#define LS_EPROTO (-19)    /* the peer broke the protocol (a frame that does not fit the exchange) */
/* Any module. */
#define LS_ESTATE (-20) /* not valid in the module's present state (started twice, resumed while not paused) */
#define LS_ENOSPC (-21) /* a fixed-size table is full (links, RSVPs, queues): nothing was added */
#define LS_ENOENT (-22) /* no entry of that name (a key id, a challenge) */
/* Security. */
#define LS_EAUTH (-23) /* a signature does not verify (wrong key, forged or altered message) */

/* The code's name ("LS_EAGAIN"), "LS_OK" for zero or positive, "LS_E?" for a
 * negative value that is none of the above. Never NULL; O(1); any context. */
const char *ls_err_name(int status);

/* What the code means in a few words, for a log line ("try again"). Never
 * NULL; O(1); any context. */
const char *ls_err_text(int status);

#ifdef __cplusplus
}
#endif

#endif /* LS_ERR_H */
