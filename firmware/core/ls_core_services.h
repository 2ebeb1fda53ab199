/* What a command handler may use: the core's types and its services
 * (docs/architecture.md "Core layers"), nothing of the layer above (the
 * sessions, the dispatcher, the tick), which calls the handlers. Every
 * firmware/core/cmd_*.c includes this header, not ls_core.h. */
#ifndef LS_CORE_SERVICES_H
#define LS_CORE_SERVICES_H

#include "ls_core_types.h"
#include "ls_fault.h"
#include "ls_log.h"
#include "ls_rsvp.h"
#include "ls_run.h"
#include "ls_send.h"
#include "ls_units.h"

#endif
