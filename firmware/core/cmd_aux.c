/* A path's auxiliary commands (docs/protocol.md "Auxiliary commands"):
 * their parser (pathLoad checks every command it stores), and running them
 * as the executor reaches their point: a DIO write the loop carries out, a
 * wait for inputs, an event, an RSVP. The path waits at the point until the
 * command is done; a failed one ends the path there. Comms thread only. */
#include <math.h>
#include <string.h>
#include <stdlib.h>

#include "cmd_motion.h"
#include "landscape.h"
#include "ls_core_events.h"
#include "ls_control.h"
#include "ls_fmt.h"
#include "ls_kin.h"
#include "ls_units.h"

static bool parse_u32(const char *tok, int base, uint32_t *out)
{
    if (tok == NULL || *tok == '\0' || *tok == '-') {
        return false;
    }
    char *end = NULL;
    unsigned long v = strtoul(tok, &end, base);
    if (*end != '\0' || v > 0xFFFFFFFFul) {
        return false;
    }
    *out = (uint32_t)v;
    return true;
}

static bool parse_timeout(const char *tok, double *out)
{
    if (tok == NULL) {
        return false;
    }
    char *end = NULL;
    double v = ls_fmt_parse_double(tok, &end);
    if (*end != '\0' || !isfinite(v) || v <= 0.0 || v > 3600.0) {
        return false;
    }
    *out = v;
    return true;
}

/* The NAME of `event NAME` and `rsvp NAME` becomes a notice's event id: one
 * longer than the id holds would reach the supervisor cut, so a client
 * waiting for that name would never see it. */
static bool aux_name_fits(const char *name, char *why, size_t whylen)
{
    const size_t max = sizeof(((ls_Notice *)0)->event_id) - 1u;
    if (strlen(name) <= max) {
        return true;
    }
    ls_fmt_print(why, whylen,
                 "NAME is %u bytes, a notice's event id holds at most %u (describe: downlink_limits): use a "
                 "shorter name",
                 (unsigned)strlen(name), (unsigned)max);
    return false;
}

/* Syntax (docs/protocol.md "Auxiliary commands"):
 *   dio UNIT ON OFF          ON/OFF hex masks (0x optional)
 *   wait UNIT MASK TIMEOUT_S MASK hex, TIMEOUT_S in (0, 3600]
 *   event NAME               NAME at most Notice.event_id's bytes
 *   rsvp NAME TIMEOUT_S */
int ls_aux_parse(const char *text, ls_aux_t *a, char *why, size_t whylen)
{
    char buf[LS_MOTION_AUX_LEN];
    ls_fmt_print(buf, sizeof buf, "%s", text);
    char *tok[5] = { 0 };
    int n = 0;
    for (char *c = buf; *c != '\0';) {
        while (*c == ' ' || *c == '\t') {
            *c++ = '\0';
        }
        if (*c == '\0') {
            break;
        }
        if (n == 5) {
            n = 6; /* too many words */
            break;
        }
        tok[n++] = c;
        while (*c != '\0' && *c != ' ' && *c != '\t') {
            c++;
        }
    }
    memset(a, 0, sizeof *a);
    uint32_t unit = 0;
    if (n == 4 && strcmp(tok[0], "dio") == 0) {
        a->kind = LS_AUX_DIO;
        if (parse_u32(tok[1], 10, &unit) && unit < LS_CTL_MAX_DIO_UNITS && parse_u32(tok[2], 16, &a->on) &&
            parse_u32(tok[3], 16, &a->off)) {
            a->unit = (uint16_t)unit;
            return LS_OK;
        }
        ls_fmt_print(why, whylen, "expected 'dio UNIT ON OFF' with UNIT 0..%d and hex masks", LS_CTL_MAX_DIO_UNITS - 1);
        return LS_EINVAL;
    }
    if (n == 4 && strcmp(tok[0], "wait") == 0) {
        a->kind = LS_AUX_WAIT;
        if (parse_u32(tok[1], 10, &unit) && unit < LS_CTL_MAX_DIO_UNITS && parse_u32(tok[2], 16, &a->on) &&
            a->on != 0 && parse_timeout(tok[3], &a->timeout_s)) {
            a->unit = (uint16_t)unit;
            return LS_OK;
        }
        ls_fmt_print(why, whylen, "expected 'wait UNIT MASK TIMEOUT_S', MASK hex != 0, TIMEOUT_S in (0, 3600]");
        return LS_EINVAL;
    }
    if (n == 2 && strcmp(tok[0], "event") == 0) {
        a->kind = LS_AUX_EVENT;
        ls_fmt_print(a->name, sizeof a->name, "%s", tok[1]);
        return aux_name_fits(tok[1], why, whylen) ? LS_OK : LS_EINVAL;
    }
    if (n == 3 && strcmp(tok[0], "rsvp") == 0) {
        a->kind = LS_AUX_RSVP;
        ls_fmt_print(a->name, sizeof a->name, "%s", tok[1]);
        if (!aux_name_fits(tok[1], why, whylen)) {
            return LS_EINVAL;
        }
        if (parse_timeout(tok[2], &a->timeout_s)) {
            return LS_OK;
        }
        ls_fmt_print(why, whylen, "expected 'rsvp NAME TIMEOUT_S', TIMEOUT_S in (0, 3600]");
        return LS_EINVAL;
    }
    ls_fmt_print(why, whylen, "unknown auxiliary command: use dio, wait, event or rsvp");
    return LS_EINVAL;
}

/* The I/O an auxiliary command names exists on this controller: a `dio`
 * unit with those output bits, a `wait` unit with those input bits. */
int ls_aux_check_io(const ls_core_t *core, const ls_aux_t *a, char *why, size_t whylen)
{
    if (a->kind != LS_AUX_DIO && a->kind != LS_AUX_WAIT) {
        return LS_OK;
    }
    if (a->unit >= core->dio_units) {
        if (core->dio_units == 0) {
            ls_fmt_print(why, whylen, "this controller has no DIO units (start landscaped with a DIO backend)");
        } else {
            ls_fmt_print(why, whylen, "DIO unit %u does not exist: units 0..%u", (unsigned)a->unit,
                         (unsigned)core->dio_units - 1u);
        }
        return LS_EINVAL;
    }
    const hal_dio_unit_info_t *u = &core->dio_info[a->unit];
    if (a->kind == LS_AUX_DIO) {
        const uint32_t bad = (a->on | a->off) & ~u->output_mask;
        if (bad != 0u) {
            ls_fmt_print(why, whylen, "bits 0x%X of unit %u are not outputs (outputs: 0x%X)", (unsigned)bad,
                         (unsigned)a->unit, (unsigned)u->output_mask);
            return LS_EINVAL;
        }
        if ((a->on & a->off) != 0u) {
            ls_fmt_print(why, whylen, "bits 0x%X are both set and cleared", (unsigned)(a->on & a->off));
            return LS_EINVAL;
        }
        return LS_OK;
    }
    const uint32_t bad = a->on & ~u->input_mask;
    if (bad != 0u) {
        ls_fmt_print(why, whylen, "bits 0x%X of unit %u are not inputs (inputs: 0x%X)", (unsigned)bad,
                     (unsigned)a->unit, (unsigned)u->input_mask);
        return LS_EINVAL;
    }
    return LS_OK;
}

static void aux_done(ls_core_t *core)
{
    if (core->ctl == NULL || !ls_mcmd_post(core, LS_CTL_AUX_DONE, core->run.ref_seq)) {
        /* The loop's queue is full: the path would wait for ever, so fail loudly. */
        ls_core_fault(core, "auxiliary command finished but the control loop's queue was full", core->motion.now_us);
    }
}

/* The path ended at a point because an auxiliary command failed: the arm is
 * at rest there (the executor waits for the command), so the path is
 * dropped and the device stays RESTING, ready for the next motion. */
static void aux_failed(ls_core_t *core, int point, const char *text)
{
    if (!core->run.active) {
        return;
    }
    (void)ls_mcmd_post(core, LS_CTL_ABORT, core->run.ref_seq);
    char d1[24], d2[72];
    ls_fmt_print(d1, sizeof d1, "at_point=%d", point);
    ls_fmt_print(d2, sizeof d2, "fault=%.*s", (int)sizeof d2 - 7, text); /* cut: the notice holds 64 */
    const char *extra[] = { d1, d2 };
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_ERROR_CHOICE);
    }
    ls_run_finish(core, LS_RUN_END_AUX_FAILED, extra, 2);
}

/* A path's `rsvp` (docs/protocol.md "RSVP"): accept continues the path,
 * decline drops it (the arm is at rest at the point), no answer continues. */
#define LS_PATH_RSVP_ACCEPT "continue"
#define LS_PATH_RSVP_DECLINE "abort"
#define LS_PATH_RSVP_DEFAULT LS_PATH_RSVP_ACCEPT
static const char *rsvp_done(struct ls_core *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us)
{
    (void)ctx;
    (void)now_us;
    if (!core->run.active) {
        return "none"; /* the path ended meanwhile */
    }
    if (!timed_out && ret_code < 0) {
        /* The supervisor declined: drop the path (it asked us not to go on);
         * the arm is at rest at the point. */
        (void)ls_mcmd_post(core, LS_CTL_ABORT, core->run.ref_seq);
        char d1[32];
        ls_fmt_print(d1, sizeof d1, "answer=%d", (int)ret_code);
        const char *extra[] = { d1 };
        if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
            core->state = ls_State_RESTING;
            ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_COMMAND_CHOICE);
        }
        ls_run_finish(core, LS_RUN_END_RSVP_DECLINED, extra, 1);
        return LS_PATH_RSVP_DECLINE;
    }
    aux_done(core); /* answered, or timed out: the default action is to continue */
    return timed_out ? LS_PATH_RSVP_DEFAULT : LS_PATH_RSVP_ACCEPT;
}

void ls_aux_run(ls_core_t *core, const ls_motion_event_t *ev)
{
    ls_aux_t a;
    char why[96];
    if (ls_aux_parse(ev->text, &a, why, sizeof why) != LS_OK) {
        /* pathLoad checked it: only a corrupted program gets here. */
        char t[96];
        ls_fmt_print(t, sizeof t, "bad auxiliary command '%.40s'", ev->text);
        aux_failed(core, (int)ev->index, t);
        return;
    }
    char d1[8 + LS_MOTION_NAME_LEN], d2[24];
    ls_fmt_print(d1, sizeof d1, "path=%s", core->run.point);
    ls_fmt_print(d2, sizeof d2, "point=%d", (int)ev->index);
    const char *data[] = { d1, d2 };
    switch (a.kind) {
    case LS_AUX_DIO: {
        ls_ctl_cmd_t c;
        memset(&c, 0, sizeof c);
        c.kind = LS_CTL_DIO_WRITE;
        c.ref_seq = core->run.ref_seq;
        c.dio.unit = a.unit;
        c.dio.on = a.on;
        c.dio.off = a.off;
        if (!ls_control_post(core->ctl, &c)) {
            aux_failed(core, (int)ev->index, "dio: the control loop's queue was full");
            return;
        }
        /* Go on only once the loop has carried the write out (ls_core_motion_tick);
         * a refusal comes back as LS_CEV_CMD_FAILED (ls_core_motion_failed). */
        core->run.dio_pending = true;
        core->run.dio_point = (int)ev->index;
        core->run.dio_cycle = ls_mcmd_snapshot(core, &core->motion.snap) ? core->motion.snap.cycle : 0;
        core->run.dio_seen = false;
        return;
    }
    case LS_AUX_WAIT:
        core->run.wait_active = true;
        core->run.wait_unit = a.unit;
        core->run.wait_mask = a.on;
        core->run.wait_deadline_us = core->motion.now_us + (uint64_t)(a.timeout_s * 1e6);
        core->run.wait_point = (int)ev->index;
        ls_fmt_print(core->run.wait_text, sizeof core->run.wait_text, "%.*s", (int)sizeof core->run.wait_text - 1,
                     ev->text);
        ls_core_motion_tick(core, core->motion.now_us);
        return;
    case LS_AUX_EVENT:
        ls_core_notify_named_to(core, core->run.addr, core->run.epoch, ls_NoticeKind_EVENT, a.name, core->run.ref_seq,
                                false, data, 2);
        aux_done(core);
        return;
    case LS_AUX_RSVP:
        if (ls_core_rsvp(core, core->run.sup, core->run.ref_seq, ls_NoticeKind_EVENT_RSVP, a.name, data, 2,
                         (uint32_t)(a.timeout_s * 1000.0), LS_PATH_RSVP_DEFAULT, rsvp_done, NULL,
                         core->motion.now_us) < 0) {
            aux_done(core); /* nobody to ask (or the table is full): take the default */
        }
        return;
    default: return;
    }
}

void ls_core_motion_tick(ls_core_t *core, uint64_t now_us)
{
    core->motion.now_us = now_us;
    if (!core->run.active || core->run.react || core->ctl == NULL) {
        return;
    }
    ls_ctl_snapshot_t snap;
    ls_control_snapshot(core->ctl, &snap);
    if (core->run.dio_pending) {
        /* The loop took the write two cycles ago: a refusal was pushed before
         * that snapshot, so it has been drained by the next turn. */
        if (core->run.dio_seen) {
            core->run.dio_pending = false;
            aux_done(core);
        } else if (snap.cycle >= core->run.dio_cycle + 2u) {
            core->run.dio_seen = true;
        }
        return;
    }
    if (!core->run.wait_active) {
        return;
    }
    if ((snap.dio[core->run.wait_unit] & core->run.wait_mask) == core->run.wait_mask) {
        core->run.wait_active = false;
        aux_done(core);
    } else if (now_us >= core->run.wait_deadline_us) {
        core->run.wait_active = false;
        char t[64];
        ls_fmt_print(t, sizeof t, "wait: inputs 0x%X of unit %u not all set in time", (unsigned)core->run.wait_mask,
                     (unsigned)core->run.wait_unit);
        aux_failed(core, core->run.wait_point, t);
    }
}

void ls_core_motion_failed(ls_core_t *core, uint32_t ref_seq, const char *text)
{
    if (!core->run.active || core->run.react || ref_seq == 0 || ref_seq != core->run.ref_seq) {
        return;
    }
    if (core->run.dio_pending) {
        core->run.dio_pending = false;
        aux_failed(core, core->run.dio_point, text);
        return;
    }
    if (core->halt.active) {
        return; /* the halt ends it */
    }
    /* The loop could not start it (drives off, manual control, a motion
     * still held): nothing moved. */
    char d[80];
    ls_fmt_print(d, sizeof d, "fault=%s", text);
    const char *extra[] = { d };
    if (core->state == ls_State_MOVING || core->state == ls_State_PAUSED) {
        core->state = ls_State_RESTING;
        ls_core_set_motion_state(core, LANDSCAPE_STATUS_ST_MOTION_ROBOT_STOPPED_ON_ERROR_CHOICE);
    }
    ls_run_finish(core, LS_RUN_END_FAULT, extra, 1);
}
