/* One spec -> one CAN link backend (ls_link_open.h). */
#include "ls_link_open.h"

#include <stdio.h>
#include <string.h>

#include "hal_linux_slcan_tty.h"
#include "hal_linux_socketcan.h"
#include "slcan_pty.h"

int ls_link_open(const char *spec, uint32_t bitrate, bool allow_tty, hal_can_link_t *out, char *msg, size_t msglen)
{
    if (strncmp(spec, "slcan:pty:", 10) == 0) {
        return hal_sim_slcan_pty_open(out, spec + 10, msg, msglen);
    }
    if (strncmp(spec, "socketcan:", 10) == 0) {
        return hal_linux_socketcan_open(out, spec + 10, msg, msglen);
    }
    if (allow_tty && strncmp(spec, "slcan:tty:", 10) == 0) {
        return hal_linux_slcan_tty_open(out, spec + 10, bitrate, msg, msglen);
    }
    (void)snprintf(msg, msglen, "unknown link kind; expected %s",
                   allow_tty ? "socketcan:IFNAME, slcan:tty:PATH or slcan:pty:PATH"
                             : "slcan:pty:PATH or socketcan:IFNAME");
    return LS_EINVAL;
}
