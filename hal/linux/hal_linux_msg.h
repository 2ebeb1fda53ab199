/* Internal to hal/linux: error messages for the caller's buffer. */
#ifndef HAL_LINUX_MSG_H
#define HAL_LINUX_MSG_H

#include <stddef.h>

/* printf into msg (if msg is not NULL and msglen > 0), always terminated,
 * truncated to fit. Returns `status` so callers can `return hal_linux_msg(...)`. */
int hal_linux_msg(int status, char *msg, size_t msglen, const char *fmt, ...) __attribute__((format(printf, 4, 5)));

#endif
