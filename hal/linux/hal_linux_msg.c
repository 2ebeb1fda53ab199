#include "hal_linux_msg.h"

#include <stdarg.h>
#include <stdio.h>

int hal_linux_msg(int status, char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg != NULL && msglen > 0) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
    return status;
}
