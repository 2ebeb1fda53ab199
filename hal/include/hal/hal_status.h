/* HAL status codes: zero or positive is success, negative is an error of the
 * one C error space (ls_err.h: LS_EUNSUPPORTED, LS_EAGAIN, LS_EIO, LS_EINVAL,
 * LS_ENODEV, LS_EPERM, LS_EBUSOFF, LS_ENOAFCAN; ls_err_text names them).
 * Every HAL operation is optional: a device whose ops table leaves an entry
 * NULL answers LS_EUNSUPPORTED through the thin wrappers. */
#ifndef HAL_STATUS_H
#define HAL_STATUS_H

#include "ls_err.h"

#endif
