/* RSVPs (seed 2.3, docs/protocol.md "RSVP"): notices that wait, without
 * blocking, for the supervisor's reply, and the acknowledgement of every
 * reply (taken, late or unknown).
 *
 * Services layer of firmware/core (docs/architecture.md "Core layers"):
 * above ls_send and ls_log. Comms thread only; no allocation; a table of
 * LS_MAX_RSVP waiting and LS_RSVP_ENDED_LEN ended ones.*/
#ifndef LS_RSVP_H
#define LS_RSVP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ls_core_types.h"

/* Send an RSVP notice to session `sup` about the request `ref_seq` (of
 * that session: the notice carries its seq and epoch) and wait (without
 * blocking) for the reply; `done` runs once: with the reply's ret_code, or
 * after timeout_ms with timed_out = true (then the caller takes
 * `default_action`, which the notice announces). The reply is answered with
 * an RsvpAck naming the action `done` returned, and logged with its data.
 * Returns the rsvp id (> 0), LS_EINVAL (`sup` has no session, `done` is NULL,
 * the notice does not encode) or LS_ENOSPC (LS_MAX_RSVP are waiting). */
int32_t ls_core_rsvp(ls_core_t *core, int sup, uint32_t ref_seq, ls_NoticeKind kind, const char *event_id,
                     const char *const *data, size_t n_data, uint32_t timeout_ms, const char *default_action,
                     ls_rsvp_done_fn done, void *ctx, uint64_t now_us);

/* Time out the RSVPs whose deadline has passed: each `done` runs with
 * timed_out (the default action), and the outcome is logged. Every comms
 * loop turn; O(LS_MAX_RSVP). */
void ls_rsvp_tick(ls_core_t *core, uint64_t now_us);

/* A supervisor's RsvpReply from `addr`: runs the RSVP's `done` once and
 * answers an RsvpAck naming the action, or refuses a late, repeated or
 * unknown reply with an RsvpAck saying which. O(LS_MAX_RSVP + LS_RSVP_ENDED_LEN). */
void ls_rsvp_on_reply(ls_core_t *core, uint8_t addr, const ls_RsvpReply *reply, uint64_t now_us);

/* A reply from `addr` that the device cannot take (it did not decode, a
 * string is not UTF-8): refused with an RsvpAck CMD_PARAM_ERR saying why
 * (printf-style), carrying the waiting RSVP's ref_seq and epoch when
 * `rsvp_id` names one; that RSVP still waits for a valid reply. The caller
 * counts the message in rx_malformed. O(LS_MAX_RSVP). */
void ls_rsvp_refuse(ls_core_t *core, uint8_t addr, uint32_t rsvp_id, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

#endif
