/* HAL status codes: zero or positive is success, negative is an error.
 * Every HAL operation is optional: a device whose ops table leaves an entry
 * NULL answers HAL_EUNSUPPORTED through the thin wrappers. */
#ifndef HAL_STATUS_H
#define HAL_STATUS_H

#define HAL_OK 0
#define HAL_EUNSUPPORTED (-1) /* the backend does not offer this operation or device */
#define HAL_EAGAIN (-2)       /* nothing now (no frame, TX queue full): try again later */
#define HAL_EIO (-3)          /* the device failed; see the backend's last message */
#define HAL_EINVAL (-4)       /* an argument is out of range for this device */
#define HAL_ENODEV (-5)       /* the device (interface, chip, line) does not exist */
#define HAL_EPERM (-6)        /* no permission (run as root or fix udev rules) */
#define HAL_EBUSOFF (-7)      /* CAN controller is bus-off */
#define HAL_ENOAFCAN (-8)     /* the kernel has no AF_CAN (no CONFIG_CAN / can module) */

/* A human-readable name of a status code, never NULL. */
const char *hal_strerror(int status);

#endif
