/* Names and texts of the one error space (ls_err.h). */
#include "ls_err.h"

const char *ls_err_name(int status)
{
    switch (status) {
    case LS_EUNSUPPORTED: return "LS_EUNSUPPORTED";
    case LS_EAGAIN: return "LS_EAGAIN";
    case LS_EIO: return "LS_EIO";
    case LS_EINVAL: return "LS_EINVAL";
    case LS_ENODEV: return "LS_ENODEV";
    case LS_EPERM: return "LS_EPERM";
    case LS_EBUSOFF: return "LS_EBUSOFF";
    case LS_ENOAFCAN: return "LS_ENOAFCAN";
    case LS_EBUSY: return "LS_EBUSY";
    case LS_ELEN: return "LS_ELEN";
    case LS_ETIME: return "LS_ETIME";
    case LS_EUNREACHABLE: return "LS_EUNREACHABLE";
    case LS_ESINGULAR: return "LS_ESINGULAR";
    case LS_ELIMITS: return "LS_ELIMITS";
    case LS_ERANGE: return "LS_ERANGE";
    case LS_EGEOM: return "LS_EGEOM";
    case LS_ETIMEDOUT: return "LS_ETIMEDOUT";
    case LS_EABORTED: return "LS_EABORTED";
    case LS_EPROTO: return "LS_EPROTO";
    case LS_ESTATE: return "LS_ESTATE";
    case LS_ENOSPC: return "LS_ENOSPC";
    case LS_ENOENT: return "LS_ENOENT";
    case LS_EAUTH: return "LS_EAUTH";
    default: return status >= 0 ? "LS_OK" : "LS_E?";
    }
}

const char *ls_err_text(int status)
{
    switch (status) {
    case LS_EUNSUPPORTED: return "not supported by this backend";
    case LS_EAGAIN: return "try again";
    case LS_EIO: return "device I/O error";
    case LS_EINVAL: return "invalid argument for this device";
    case LS_ENODEV: return "no such device";
    case LS_EPERM: return "permission denied";
    case LS_EBUSOFF: return "CAN bus-off";
    case LS_ENOAFCAN: return "kernel has no AF_CAN support";
    case LS_EBUSY: return "a transmission is in progress";
    case LS_ELEN: return "bad message length";
    case LS_ETIME: return "duration shorter than the minimum";
    case LS_EUNREACHABLE: return "pose out of reach";
    case LS_ESINGULAR: return "shoulder singularity";
    case LS_ELIMITS: return "beyond the joint limits";
    case LS_ERANGE: return "beyond a limit";
    case LS_EGEOM: return "degenerate geometry";
    case LS_ETIMEDOUT: return "no answer within the time-out";
    case LS_EABORTED: return "the peer refused the transfer";
    case LS_EPROTO: return "the peer broke the protocol";
    case LS_ESTATE: return "not valid in the present state";
    case LS_ENOSPC: return "a fixed-size table is full";
    case LS_ENOENT: return "no such entry";
    case LS_EAUTH: return "the signature does not verify";
    default: return status >= 0 ? "ok" : "unknown error";
    }
}
