/* ls_cia402: the statusword decoder against the CiA 402 state table, the
 * stepper against a drive model written here from the standard's
 * transitions (every statusword built from ls_canopen.h's bits, not from
 * the stepper's tables), and the scaling across the int32 wrap in both
 * directions. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "alloc_counter.h"
#include "ls_canopen.h"
#include "ls_cia402.h"
#include "ls_math.h"

/* ---- Statuswords of each state, with the usual extra bits -------------- */

#define SW_VOLT LS_CO_SW_VOLTAGE_ENABLED
#define SW_QS LS_CO_SW_QUICK_STOP /* 1 = no quick stop */
#define SW_REM LS_CO_SW_REMOTE

static const uint16_t SW_NOT_READY = SW_REM;
static const uint16_t SW_SOD = LS_CO_SW_SWITCH_ON_DISABLED | SW_REM;
static const uint16_t SW_READY = LS_CO_SW_READY_TO_SWITCH_ON | SW_QS | SW_VOLT | SW_REM;
static const uint16_t SW_SON = LS_CO_SW_READY_TO_SWITCH_ON | LS_CO_SW_SWITCHED_ON | SW_QS | SW_VOLT | SW_REM;
static const uint16_t SW_OE = LS_CO_SW_READY_TO_SWITCH_ON | LS_CO_SW_SWITCHED_ON | LS_CO_SW_OPERATION_ENABLED | SW_QS |
                              SW_VOLT | SW_REM | LS_CO_SW_OMS12;
static const uint16_t SW_QSA =
    LS_CO_SW_READY_TO_SWITCH_ON | LS_CO_SW_SWITCHED_ON | LS_CO_SW_OPERATION_ENABLED | SW_VOLT | SW_REM;
static const uint16_t SW_FRA =
    LS_CO_SW_READY_TO_SWITCH_ON | LS_CO_SW_SWITCHED_ON | LS_CO_SW_OPERATION_ENABLED | LS_CO_SW_FAULT | SW_VOLT | SW_REM;
static const uint16_t SW_FAULT = LS_CO_SW_FAULT | SW_REM;

/* The state table of CiA 402 (bits 0-3, 5, 6 as xxxx written out), read bit by bit. */
static ls_402_state_t reference_state(uint16_t sw)
{
    const int rtso = (sw >> 0) & 1, so = (sw >> 1) & 1, oe = (sw >> 2) & 1, f = (sw >> 3) & 1;
    const int qs = (sw >> 5) & 1, sod = (sw >> 6) & 1;
    if (!rtso && !so && !oe && !f && !sod) {
        return LS_402_NOT_READY_TO_SWITCH_ON;
    }
    if (!rtso && !so && !oe && !f && sod) {
        return LS_402_SWITCH_ON_DISABLED;
    }
    if (rtso && !so && !oe && !f && qs && !sod) {
        return LS_402_READY_TO_SWITCH_ON;
    }
    if (rtso && so && !oe && !f && qs && !sod) {
        return LS_402_SWITCHED_ON;
    }
    if (rtso && so && oe && !f && qs && !sod) {
        return LS_402_OPERATION_ENABLED;
    }
    if (rtso && so && oe && !f && !qs && !sod) {
        return LS_402_QUICK_STOP_ACTIVE;
    }
    if (rtso && so && oe && f && !sod) {
        return LS_402_FAULT_REACTION_ACTIVE;
    }
    if (!rtso && !so && !oe && f && !sod) {
        return LS_402_FAULT;
    }
    return LS_402_UNKNOWN;
}

static void test_every_statusword_decodes_as_the_standards_table_says(void **state)
{
    (void)state;
    for (uint32_t sw = 0; sw <= 0xFFFFu; sw++) {
        if (ls_402_state((uint16_t)sw) != reference_state((uint16_t)sw)) {
            fail_msg("statusword 0x%04X: got %s, want %s", (unsigned)sw, ls_402_state_name(ls_402_state((uint16_t)sw)),
                     ls_402_state_name(reference_state((uint16_t)sw)));
        }
    }
    assert_int_equal(ls_402_state(SW_NOT_READY), LS_402_NOT_READY_TO_SWITCH_ON);
    assert_int_equal(ls_402_state(SW_SOD), LS_402_SWITCH_ON_DISABLED);
    assert_int_equal(ls_402_state(SW_READY), LS_402_READY_TO_SWITCH_ON);
    assert_int_equal(ls_402_state(SW_SON), LS_402_SWITCHED_ON);
    assert_int_equal(ls_402_state(SW_OE), LS_402_OPERATION_ENABLED);
    assert_int_equal(ls_402_state(SW_QSA), LS_402_QUICK_STOP_ACTIVE);
    assert_int_equal(ls_402_state(SW_FRA), LS_402_FAULT_REACTION_ACTIVE);
    assert_int_equal(ls_402_state(SW_FAULT), LS_402_FAULT);
    /* bit 5 is outside the short mask: SWITCH ON DISABLED with it set */
    assert_int_equal(ls_402_state(0x0060u), LS_402_SWITCH_ON_DISABLED);
    assert_int_equal(ls_402_state(0x0001u), LS_402_UNKNOWN);
}

static void test_states_and_commands_have_the_standards_names(void **state)
{
    (void)state;
    assert_string_equal(ls_402_state_name(LS_402_SWITCH_ON_DISABLED), "SWITCH ON DISABLED");
    assert_string_equal(ls_402_state_name(LS_402_OPERATION_ENABLED), "OPERATION ENABLED");
    assert_string_equal(ls_402_state_name(LS_402_FAULT_REACTION_ACTIVE), "FAULT REACTION ACTIVE");
    assert_string_equal(ls_402_state_name(LS_402_UNKNOWN), "UNKNOWN");
    assert_string_equal(ls_402_state_name((ls_402_state_t)99), "UNKNOWN");
    for (int s = 0; s < LS_402_STATE_COUNT; s++) {
        assert_non_null(ls_402_state_name((ls_402_state_t)s));
    }
    assert_string_equal(ls_402_command_name(LS_CO_CW_CMD_SHUTDOWN), "shutdown");
    assert_string_equal(ls_402_command_name(LS_CO_CW_CMD_SWITCH_ON), "switch on");
    assert_string_equal(ls_402_command_name(LS_CO_CW_CMD_ENABLE_OPERATION | LS_CO_CW_HALT), "enable operation");
    assert_string_equal(ls_402_command_name(LS_CO_CW_CMD_DISABLE_VOLTAGE), "disable voltage");
    assert_string_equal(ls_402_command_name(LS_CO_CW_CMD_QUICK_STOP), "quick stop");
    assert_string_equal(ls_402_command_name(LS_CO_CW_FAULT_RESET), "fault reset");
    assert_string_equal(ls_402_command_name(0x0003u), "controlword");
}

/* ---- A drive model: CiA 402's transitions, applied when a controlword
 * arrives, seen by the master `latency` cycles later ------------------- */

#define MAX_LATENCY 8

typedef struct {
    uint16_t sw;                    /* the drive's true statusword */
    uint16_t seen[MAX_LATENCY + 1]; /* what the master reads, oldest first */
    int latency;                    /* cycles between a controlword and its statusword */
    uint16_t last_cw;
    bool refuse;          /* the drive ignores every command (stuck) */
    bool fault_sticks;    /* a fault reset does not clear the fault */
    bool fault_on_enable; /* entering OPERATION ENABLED faults at once */
    int edges_seen;       /* rising edges of bit 7 */
} drive_t;

static void drive_init(drive_t *d, uint16_t sw, int latency)
{
    memset(d, 0, sizeof *d);
    d->sw = sw;
    d->latency = latency;
    for (int i = 0; i <= MAX_LATENCY; i++) {
        d->seen[i] = sw;
    }
}

static bool cmd_is(uint16_t cw, uint16_t mask, uint16_t value)
{
    return (cw & mask) == value;
}

/* CiA 402 table 36: the commands by their bit patterns (bit 7 = 0). */
#define IS_SHUTDOWN(cw) cmd_is(cw, 0x0087u, 0x0006u)
#define IS_SWITCH_ON(cw) cmd_is(cw, 0x008Fu, 0x0007u)
#define IS_ENABLE_OP(cw) cmd_is(cw, 0x008Fu, 0x000Fu)
#define IS_DISABLE_VOLTAGE(cw) cmd_is(cw, 0x0082u, 0x0000u)
#define IS_QUICK_STOP(cw) cmd_is(cw, 0x0086u, 0x0002u)

static void drive_apply(drive_t *d, uint16_t cw)
{
    const bool edge = (cw & LS_CO_CW_FAULT_RESET) != 0u && (d->last_cw & LS_CO_CW_FAULT_RESET) == 0u;
    d->last_cw = cw;
    if (edge) {
        d->edges_seen++;
    }
    if (d->refuse) {
        return;
    }
    switch (ls_402_state(d->sw)) {
    case LS_402_NOT_READY_TO_SWITCH_ON: d->sw = SW_SOD; break;
    case LS_402_FAULT_REACTION_ACTIVE: d->sw = SW_FAULT; break;
    case LS_402_FAULT:
        if (edge && !d->fault_sticks) {
            d->sw = SW_SOD;
        }
        break;
    case LS_402_SWITCH_ON_DISABLED:
        if (IS_SHUTDOWN(cw)) {
            d->sw = SW_READY;
        }
        break;
    case LS_402_READY_TO_SWITCH_ON:
        if (IS_SWITCH_ON(cw)) {
            d->sw = SW_SON;
        } else if (IS_DISABLE_VOLTAGE(cw) || IS_QUICK_STOP(cw)) {
            d->sw = SW_SOD;
        }
        break;
    case LS_402_SWITCHED_ON:
        if (IS_ENABLE_OP(cw)) {
            d->sw = d->fault_on_enable ? SW_FRA : SW_OE;
        } else if (IS_SHUTDOWN(cw)) {
            d->sw = SW_READY;
        } else if (IS_DISABLE_VOLTAGE(cw) || IS_QUICK_STOP(cw)) {
            d->sw = SW_SOD;
        }
        break;
    case LS_402_OPERATION_ENABLED:
        if (IS_SWITCH_ON(cw)) {
            d->sw = SW_SON;
        } else if (IS_SHUTDOWN(cw)) {
            d->sw = SW_READY;
        } else if (IS_QUICK_STOP(cw)) {
            d->sw = SW_QSA;
        } else if (IS_DISABLE_VOLTAGE(cw)) {
            d->sw = SW_SOD;
        }
        break;
    case LS_402_QUICK_STOP_ACTIVE: /* quick stop option code 5-8: it stays */
        if (IS_DISABLE_VOLTAGE(cw)) {
            d->sw = SW_SOD;
        }
        break;
    case LS_402_UNKNOWN:
    case LS_402_STATE_COUNT:
    default: break;
    }
}

/* The statusword the master reads this cycle. */
static uint16_t drive_seen(const drive_t *d)
{
    return d->seen[0];
}

/* After the master's controlword of this cycle: the drive acts, and its
 * statusword reaches the master `latency` cycles later. */
static void drive_cycle(drive_t *d, uint16_t cw)
{
    drive_apply(d, cw);
    for (int i = 0; i < d->latency - 1; i++) {
        d->seen[i] = d->seen[i + 1];
    }
    d->seen[d->latency - 1] = d->sw;
}

typedef struct {
    uint16_t cw[4096];
    ls_402_state_t state[4096];
    int n;
} trace_t;

/* Runs `cycles` cycles; checks on every cycle that the controlword changes
 * only when the statusword it answers changed (or the want did), so each
 * step waits for the previous one's confirmation. Returns the last out. */
static ls_402_out_t run(ls_402_axis_t *ax, drive_t *d, ls_402_want_t want, bool allow, int cycles, trace_t *t)
{
    ls_402_out_t out = { 0 };
    for (int k = 0; k < cycles; k++) {
        const uint16_t sw = drive_seen(d);
        const uint16_t prev_cw = ax->cw;
        const ls_402_state_t prev_state = ax->state;
        const ls_402_want_t prev_want = ax->want;
        assert_int_equal(ls_402_step(ax, sw, want, allow, &out), LS_OK);
        const bool in_fault = ls_402_state(sw) == LS_402_FAULT;
        if (!in_fault && out.controlword != prev_cw && prev_want == want && k > 0) {
            if (ls_402_state(sw) == prev_state) {
                fail_msg("cycle %d: controlword 0x%04X -> 0x%04X while the drive stays in %s", k, (unsigned)prev_cw,
                         (unsigned)out.controlword, ls_402_state_name(prev_state));
            }
        }
        if (t != NULL && t->n < 4096) {
            t->cw[t->n] = out.controlword;
            t->state[t->n] = out.state;
            t->n++;
        }
        drive_cycle(d, out.controlword);
    }
    return out;
}

static ls_402_axis_t new_axis(uint32_t timeout, uint8_t edges)
{
    ls_402_axis_t ax;
    const ls_402_config_t cfg = { .step_timeout_cycles = timeout, .fault_reset_edges = edges };
    assert_int_equal(ls_402_init(&ax, &cfg), LS_OK);
    return ax;
}

/* Distinct controlwords in order of appearance. */
static int steps_of(const trace_t *t, uint16_t *steps, int cap)
{
    int n = 0;
    for (int i = 0; i < t->n; i++) {
        if (n == 0 || steps[n - 1] != t->cw[i]) {
            if (n < cap) {
                steps[n] = t->cw[i];
            }
            n++;
        }
    }
    return n;
}

static void test_enabling_steps_shutdown_switch_on_enable_each_once_confirmed(void **state)
{
    (void)state;
    for (int latency = 1; latency <= 4; latency++) {
        ls_402_axis_t ax = new_axis(100, 3);
        drive_t d;
        drive_init(&d, SW_SOD, latency);
        static trace_t t;
        t.n = 0;
        ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, false, 40, &t);
        uint16_t steps[8];
        assert_int_equal(steps_of(&t, steps, 8), 3);
        assert_int_equal(steps[0], LS_CO_CW_CMD_SHUTDOWN);
        assert_int_equal(steps[1], LS_CO_CW_CMD_SWITCH_ON);
        assert_int_equal(steps[2], LS_CO_CW_CMD_ENABLE_OPERATION);
        assert_true(out.enabled);
        assert_true(out.at_target);
        assert_int_equal(out.error, LS_402_OK);
        /* each step is held while the drive's answer travels back */
        int shutdown_cycles = 0;
        for (int i = 0; i < t.n; i++) {
            shutdown_cycles += t.cw[i] == LS_CO_CW_CMD_SHUTDOWN;
        }
        assert_int_equal(shutdown_cycles, latency);
        /* "enabled" comes only with the statusword that shows it */
        for (int i = 0; i < t.n; i++) {
            if (t.state[i] != LS_402_OPERATION_ENABLED) {
                continue;
            }
            assert_int_equal(t.cw[i], LS_CO_CW_CMD_ENABLE_OPERATION);
        }
    }
}

static void test_enabled_is_reported_only_from_an_operation_enabled_statusword(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(100, 3);
    ls_402_out_t out;
    assert_int_equal(ls_402_step(&ax, SW_SON, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_int_equal(out.controlword, LS_CO_CW_CMD_ENABLE_OPERATION);
    assert_false(out.enabled); /* asked, not confirmed */
    assert_int_equal(ls_402_step(&ax, SW_SON, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_false(out.enabled);
    assert_int_equal(ls_402_step(&ax, SW_OE, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_true(out.enabled);
}

typedef struct {
    uint16_t sw;
    ls_402_want_t want;
    uint16_t cw;
    bool at_target;
} transition_t;

static void test_every_state_and_want_gives_the_standards_command(void **state)
{
    (void)state;
    static const transition_t table[] = {
        /* ENABLED: 2, 3, 4, hold; quick stop active -12-> switch on disabled */
        { SW_SOD, LS_402_WANT_ENABLED, LS_CO_CW_CMD_SHUTDOWN, false },
        { SW_READY, LS_402_WANT_ENABLED, LS_CO_CW_CMD_SWITCH_ON, false },
        { SW_SON, LS_402_WANT_ENABLED, LS_CO_CW_CMD_ENABLE_OPERATION, false },
        { SW_OE, LS_402_WANT_ENABLED, LS_CO_CW_CMD_ENABLE_OPERATION, true },
        { SW_QSA, LS_402_WANT_ENABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        { SW_NOT_READY, LS_402_WANT_ENABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        { SW_FRA, LS_402_WANT_ENABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        /* DISABLED: 8 and 6 to READY; switch on disabled and ready hold */
        { SW_OE, LS_402_WANT_DISABLED, LS_CO_CW_CMD_SHUTDOWN, false },
        { SW_SON, LS_402_WANT_DISABLED, LS_CO_CW_CMD_SHUTDOWN, false },
        { SW_READY, LS_402_WANT_DISABLED, LS_CO_CW_CMD_SHUTDOWN, true },
        { SW_SOD, LS_402_WANT_DISABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, true },
        { SW_QSA, LS_402_WANT_DISABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        /* QUICK_STOP: 11; 7 and 10 to switch on disabled; stopped states hold */
        { SW_OE, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_QUICK_STOP, false },
        { SW_QSA, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_QUICK_STOP, true },
        { SW_SON, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_QUICK_STOP, false },
        { SW_READY, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_QUICK_STOP, false },
        { SW_SOD, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_QUICK_STOP, true },
        /* FAULT without a reset allowed: nothing but bit 7 low */
        { SW_FAULT, LS_402_WANT_ENABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        { SW_FAULT, LS_402_WANT_DISABLED, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
        { SW_FAULT, LS_402_WANT_QUICK_STOP, LS_CO_CW_CMD_DISABLE_VOLTAGE, false },
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        ls_402_axis_t ax = new_axis(100, 3);
        ls_402_out_t out;
        assert_int_equal(ls_402_step(&ax, table[i].sw, table[i].want, false, &out), LS_OK);
        if (out.controlword != table[i].cw || out.at_target != table[i].at_target) {
            fail_msg("%s, want %d: got 0x%04X (at target %d), expected 0x%04X (%d)", ls_402_state_name(out.state),
                     (int)table[i].want, (unsigned)out.controlword, out.at_target, (unsigned)table[i].cw,
                     table[i].at_target);
        }
    }
}

static void test_disabling_an_enabled_drive_is_one_shutdown(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(100, 3);
    drive_t d;
    drive_init(&d, SW_OE, 2);
    static trace_t t;
    t.n = 0;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_DISABLED, false, 10, &t);
    uint16_t steps[4];
    assert_int_equal(steps_of(&t, steps, 4), 1);
    assert_int_equal(steps[0], LS_CO_CW_CMD_SHUTDOWN);
    assert_int_equal(out.state, LS_402_READY_TO_SWITCH_ON);
    assert_true(out.at_target);
    assert_false(out.enabled);
}

static void test_quick_stop_holds_and_enabling_again_goes_through_switch_on_disabled(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(100, 3);
    drive_t d;
    drive_init(&d, SW_OE, 1);
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_QUICK_STOP, false, 10, NULL);
    assert_int_equal(out.state, LS_402_QUICK_STOP_ACTIVE);
    assert_int_equal(out.controlword, LS_CO_CW_CMD_QUICK_STOP);
    assert_true(out.at_target);
    static trace_t t;
    t.n = 0;
    out = run(&ax, &d, LS_402_WANT_ENABLED, false, 20, &t);
    uint16_t steps[8];
    assert_int_equal(steps_of(&t, steps, 8), 4);
    assert_int_equal(steps[0], LS_CO_CW_CMD_DISABLE_VOLTAGE);
    assert_int_equal(steps[1], LS_CO_CW_CMD_SHUTDOWN);
    assert_int_equal(steps[2], LS_CO_CW_CMD_SWITCH_ON);
    assert_int_equal(steps[3], LS_CO_CW_CMD_ENABLE_OPERATION);
    assert_true(out.enabled);
}

static void test_fault_reset_is_a_rising_edge_after_a_cycle_with_bit_7_low(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(100, 3);
    drive_t d;
    drive_init(&d, SW_FAULT, 1);
    d.last_cw = LS_CO_CW_FAULT_RESET; /* an earlier master left bit 7 high */
    static trace_t t;
    t.n = 0;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, true, 30, &t);
    assert_int_equal(t.cw[0], LS_CO_CW_CMD_DISABLE_VOLTAGE); /* bit 7 low first */
    assert_int_equal(t.cw[1], LS_CO_CW_FAULT_RESET);         /* then the edge */
    assert_int_equal(d.edges_seen, 1);
    assert_int_equal(t.state[2], LS_402_SWITCH_ON_DISABLED);
    assert_int_equal(t.cw[2], LS_CO_CW_CMD_SHUTDOWN);
    assert_true(out.enabled);
    assert_int_equal(out.error, LS_402_OK);
}

static void test_no_reset_edge_is_sent_unless_allowed(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(5, 3);
    drive_t d;
    drive_init(&d, SW_FAULT, 1);
    static trace_t t;
    t.n = 0;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, false, 50, &t);
    for (int i = 0; i < t.n; i++) {
        assert_int_equal(t.cw[i] & LS_CO_CW_FAULT_RESET, 0);
    }
    assert_true(out.fault);
    assert_int_equal(out.state, LS_402_FAULT);
    assert_int_equal(out.error, LS_402_OK); /* a fault is a flag, not a stuck step */
    /* allowing it now resets at once (bit 7 has been low all along) */
    assert_int_equal(ls_402_step(&ax, SW_FAULT, LS_402_WANT_ENABLED, true, &out), LS_OK);
    assert_int_equal(out.controlword, LS_CO_CW_FAULT_RESET);
}

static void test_a_drive_that_stays_in_fault_is_reported_after_the_configured_edges(void **state)
{
    (void)state;
    const uint32_t timeout = 4;
    ls_402_axis_t ax = new_axis(timeout, 3);
    drive_t d;
    drive_init(&d, SW_FAULT, 1);
    d.fault_sticks = true;
    static trace_t t;
    t.n = 0;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, true, 100, &t);
    assert_int_equal(d.edges_seen, 3);
    assert_int_equal(out.error, LS_402_STAYS_IN_FAULT);
    assert_int_equal(out.stuck_in, LS_402_FAULT);
    assert_int_equal(out.controlword, LS_CO_CW_CMD_DISABLE_VOLTAGE);
    /* every edge follows a low cycle, and is held for the time-out */
    int high_run = 0;
    for (int i = 0; i < t.n; i++) {
        if (t.cw[i] & LS_CO_CW_FAULT_RESET) {
            assert_true(i > 0);
            high_run++;
        } else {
            assert_true(high_run == 0 || high_run == (int)timeout + 1);
            high_run = 0;
        }
    }
    char line[160];
    assert_true(ls_402_describe(&out, line, sizeof line) > 0);
    assert_string_equal(line, "stays in FAULT after 3 fault resets (statusword 0x0208)");
    /* a new request (allowed again after not being allowed) tries anew */
    assert_int_equal(ls_402_step(&ax, SW_FAULT, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_int_equal(ls_402_step(&ax, SW_FAULT, LS_402_WANT_ENABLED, true, &out), LS_OK);
    assert_int_equal(out.error, LS_402_OK);
    assert_int_equal(out.controlword, LS_CO_CW_FAULT_RESET);
}

static void test_a_drive_that_faults_on_every_enable_ends_as_staying_in_fault(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(20, 2);
    drive_t d;
    drive_init(&d, SW_SOD, 1);
    d.fault_on_enable = true;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, true, 200, NULL);
    assert_int_equal(d.edges_seen, 2);
    assert_int_equal(out.error, LS_402_STAYS_IN_FAULT);
    assert_false(out.enabled);
}

static void test_a_step_the_drive_does_not_follow_is_stuck_in_its_state(void **state)
{
    (void)state;
    const uint32_t timeout = 10;
    ls_402_axis_t ax = new_axis(timeout, 3);
    drive_t d;
    drive_init(&d, SW_READY, 1);
    d.refuse = true;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, false, (int)timeout, NULL);
    assert_int_equal(out.error, LS_402_OK); /* cycles 0..timeout-1: still in time */
    out = run(&ax, &d, LS_402_WANT_ENABLED, false, 1, NULL);
    assert_int_equal(out.error, LS_402_STUCK);
    assert_int_equal(out.stuck_in, LS_402_READY_TO_SWITCH_ON);
    assert_int_equal(out.stuck_command, LS_CO_CW_CMD_SWITCH_ON);
    assert_int_equal(out.controlword, LS_CO_CW_CMD_SWITCH_ON); /* still asking */
    char line[160];
    ls_402_describe(&out, line, sizeof line);
    assert_string_equal(line, "stuck in READY TO SWITCH ON: switch on (0x0007) not followed within 10 cycles "
                              "(statusword 0x0231)");
    /* the error stays until the want changes */
    out = run(&ax, &d, LS_402_WANT_ENABLED, false, 5, NULL);
    assert_int_equal(out.error, LS_402_STUCK);
    out = run(&ax, &d, LS_402_WANT_DISABLED, false, 1, NULL);
    assert_int_equal(out.error, LS_402_OK);
    assert_true(out.at_target);
}

static void test_a_drive_that_never_leaves_not_ready_is_stuck_there(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(3, 3);
    drive_t d;
    drive_init(&d, SW_NOT_READY, 1);
    d.refuse = true;
    ls_402_out_t out = run(&ax, &d, LS_402_WANT_ENABLED, false, 4, NULL);
    assert_int_equal(out.error, LS_402_STUCK);
    assert_int_equal(out.stuck_in, LS_402_NOT_READY_TO_SWITCH_ON);
    char line[160];
    ls_402_describe(&out, line, sizeof line);
    assert_string_equal(line, "stuck in NOT READY TO SWITCH ON: not left by itself within 3 cycles "
                              "(statusword 0x0200)");
}

static void test_the_statusword_flags_are_reported(void **state)
{
    (void)state;
    ls_402_axis_t ax = new_axis(100, 3);
    ls_402_out_t out;
    assert_int_equal(ls_402_step(&ax, SW_OE | LS_CO_SW_WARNING | LS_CO_SW_OMS13, LS_402_WANT_ENABLED, false, &out),
                     LS_OK);
    assert_true(out.warning);
    assert_true(out.following_error);
    assert_false(out.target_ignored);
    assert_true(out.remote);
    assert_false(out.fault);
    char line[160];
    ls_402_describe(&out, line, sizeof line);
    assert_string_equal(line, "OPERATION ENABLED, warning, following error (statusword 0x32B7)");
    assert_int_equal(ls_402_step(&ax, (uint16_t)(SW_OE & ~LS_CO_SW_OMS12 & ~SW_REM), LS_402_WANT_ENABLED, false, &out),
                     LS_OK);
    assert_true(out.target_ignored);
    assert_false(out.following_error);
    assert_false(out.remote);
    ls_402_describe(&out, line, sizeof line);
    assert_string_equal(line, "OPERATION ENABLED, target ignored (statusword 0x0037); the drive is under local "
                              "control (statusword bit 9 = 0)");
    /* bits 12 and 13 mean nothing outside OPERATION ENABLED */
    assert_int_equal(ls_402_step(&ax, SW_SON | LS_CO_SW_OMS13, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_false(out.following_error);
    assert_false(out.target_ignored);
    assert_int_equal(ls_402_step(&ax, SW_FRA, LS_402_WANT_ENABLED, false, &out), LS_OK);
    assert_true(out.fault);
    /* a short buffer is cut, NUL-terminated */
    char tiny[8];
    assert_true(ls_402_describe(&out, tiny, sizeof tiny) <= 7);
    assert_int_equal(strlen(tiny), 7);
}

static void test_bad_input_is_refused_and_leaves_everything_untouched(void **state)
{
    (void)state;
    ls_402_config_t bad = { .step_timeout_cycles = 0, .fault_reset_edges = 3 };
    ls_402_axis_t ax;
    memset(&ax, 0xA5, sizeof ax);
    ls_402_axis_t copy = ax;
    assert_int_equal(ls_402_init(&ax, &bad), LS_EINVAL);
    bad = (ls_402_config_t){ .step_timeout_cycles = 5, .fault_reset_edges = 0 };
    assert_int_equal(ls_402_init(&ax, &bad), LS_EINVAL);
    assert_memory_equal(&ax, &copy, sizeof ax);
    assert_int_equal(ls_402_init(NULL, NULL), LS_EINVAL);
    assert_int_equal(ls_402_init(&ax, NULL), LS_OK);
    assert_int_equal(ax.cfg.step_timeout_cycles, LS_402_STEP_TIMEOUT_MS);
    copy = ax;
    ls_402_out_t out;
    memset(&out, 0x5A, sizeof out);
    ls_402_out_t out_copy = out;
    assert_int_equal(ls_402_step(&ax, SW_SOD, LS_402_WANT_COUNT, false, &out), LS_EINVAL);
    assert_int_equal(ls_402_step(&ax, SW_SOD, (ls_402_want_t)-1, false, &out), LS_EINVAL);
    assert_int_equal(ls_402_step(NULL, SW_SOD, LS_402_WANT_ENABLED, false, &out), LS_EINVAL);
    assert_int_equal(ls_402_step(&ax, SW_SOD, LS_402_WANT_ENABLED, false, NULL), LS_EINVAL);
    assert_memory_equal(&ax, &copy, sizeof ax);
    assert_memory_equal(&out, &out_copy, sizeof out);
    char buf[4];
    assert_int_equal(ls_402_describe(NULL, buf, sizeof buf), LS_EINVAL);
    assert_int_equal(ls_402_describe(&out, buf, 0), LS_EINVAL);
}

static void test_the_default_time_out_is_a_second_of_cycles(void **state)
{
    (void)state;
    ls_402_config_t c;
    ls_402_default_config(&c, 1000);
    assert_int_equal(c.step_timeout_cycles, 1000);
    assert_int_equal(c.fault_reset_edges, LS_402_FAULT_RESET_EDGES);
    ls_402_default_config(&c, 4000);
    assert_int_equal(c.step_timeout_cycles, 250);
    ls_402_default_config(&c, 3000);
    assert_int_equal(c.step_timeout_cycles, 334); /* rounded up */
}

/* ---- Scaling ----------------------------------------------------------- */

static void test_unwrapping_crosses_the_int32_wrap_upward(void **state)
{
    (void)state;
    ls_402_unwrap_t u;
    ls_402_unwrap_reset(&u);
    const int64_t start = INT32_MAX - 25000;
    int64_t truth = start;
    for (int k = 0; k < 100; k++) {
        /* the drive's counter wraps: its reading is truth modulo 2^32 */
        int64_t m = ((truth + 2147483648LL) % 4294967296LL + 4294967296LL) % 4294967296LL - 2147483648LL;
        assert_int_equal(ls_402_unwrap(&u, (int32_t)m), truth);
        truth += 997;
    }
    assert_true(truth > (int64_t)INT32_MAX + 70000); /* it did cross */
}

static void test_unwrapping_crosses_the_int32_wrap_downward(void **state)
{
    (void)state;
    ls_402_unwrap_t u;
    ls_402_unwrap_reset(&u);
    int64_t truth = (int64_t)INT32_MIN + 30000;
    for (int k = 0; k < 100; k++) {
        int64_t m = ((truth + 2147483648LL) % 4294967296LL + 4294967296LL) % 4294967296LL - 2147483648LL;
        assert_int_equal(ls_402_unwrap(&u, (int32_t)m), truth);
        truth -= 1511;
    }
    assert_true(truth < (int64_t)INT32_MIN - 100000);
    /* and a single jump over the wrap both ways */
    ls_402_unwrap_reset(&u);
    assert_int_equal(ls_402_unwrap(&u, INT32_MIN), INT32_MIN);
    assert_int_equal(ls_402_unwrap(&u, INT32_MAX), (int64_t)INT32_MIN - 1);
    assert_int_equal(ls_402_unwrap(&u, INT32_MIN + 4), (int64_t)INT32_MIN + 4);
}

static void test_positions_and_velocities_scale_with_sign_and_offset(void **state)
{
    (void)state;
    ls_402_scale_t s;
    /* 1000 counts per rad, reversed, 0.5 rad where the drive reads 0 */
    assert_int_equal(ls_402_scale_init(&s, 1000.0, -1, 0.5, 0.0), LS_OK);
    assert_true(fabs(ls_402_pos_rad(&s, 2000) - (0.5 - 2.0)) < 1e-12);
    assert_true(fabs(ls_402_pos_rad(&s, 0) - 0.5) < 1e-12);
    /* velocity factor defaults to the position factor */
    int32_t raw;
    assert_int_equal(ls_402_vel_raw(&s, 2.0, &raw), LS_OK);
    assert_int_equal(raw, -2000);
    assert_true(fabs(ls_402_vel_rad_s(&s, -2000) - 2.0) < 1e-12);
    /* a drive whose velocity unit is 0.1 count/s: 10000 units per rad/s */
    assert_int_equal(ls_402_scale_init(&s, 1000.0, 1, 0.0, 10000.0), LS_OK);
    assert_int_equal(ls_402_vel_raw(&s, -0.25, &raw), LS_OK);
    assert_int_equal(raw, -2500);
    assert_true(fabs(ls_402_vel_rad_s(&s, 12345) - 1.2345) < 1e-12);
    assert_int_equal(ls_402_vel_raw(&s, 3e6, &raw), LS_ERANGE);
    assert_int_equal(ls_402_vel_raw(&s, NAN, &raw), LS_EINVAL);
    /* an encoder of 2^20 counts per turn behind a 1:100 gear */
    const double cpr = 1048576.0 * 100.0 / (2.0 * LS_PI);
    assert_int_equal(ls_402_scale_init(&s, cpr, 1, 0.0, 0.0), LS_OK);
    assert_true(fabs(ls_402_pos_rad(&s, 104857600) - 2.0 * LS_PI) < 1e-12);
}

static void test_a_target_converts_to_what_the_drive_reads_there_across_the_wrap(void **state)
{
    (void)state;
    for (int sign = -1; sign <= 1; sign += 2) {
        ls_402_scale_t s;
        assert_int_equal(ls_402_scale_init(&s, 10000.0, sign, 0.25, 0.0), LS_OK);
        ls_402_unwrap_t u;
        ls_402_unwrap_reset(&u);
        /* just below the top: +3000 counts ahead lands past the wrap */
        const int32_t raw0 = INT32_MAX - 1000;
        const int64_t c0 = ls_402_unwrap(&u, raw0);
        const double q0 = ls_402_pos_rad(&s, c0);
        int32_t raw;
        assert_int_equal(ls_402_target_raw(&s, &u, q0, &raw), LS_OK);
        assert_int_equal(raw, raw0);          /* here is here */
        const double ahead = q0 + sign * 0.3; /* +3000 counts */
        assert_int_equal(ls_402_target_raw(&s, &u, ahead, &raw), LS_OK);
        assert_int_equal(raw, INT32_MIN + 1999);
        /* the drive moves there and reports it; the tracker agrees */
        const int64_t c1 = ls_402_unwrap(&u, raw);
        assert_int_equal(c1, c0 + 3000);
        assert_true(fabs(ls_402_pos_rad(&s, c1) - ahead) < 1e-9);
        /* and back down across the wrap */
        assert_int_equal(ls_402_target_raw(&s, &u, q0 - sign * 0.5, &raw), LS_OK);
        assert_int_equal(raw, INT32_MAX - 6000);
        assert_int_equal(ls_402_unwrap(&u, raw), c0 - 5000);
        /* rounded to the nearest count */
        assert_int_equal(ls_402_target_raw(&s, &u, ls_402_pos_rad(&s, c0 - 5000) + sign * 0.00006, &raw), LS_OK);
        assert_int_equal(raw, INT32_MAX - 5999);
    }
}

static void test_a_target_too_far_or_not_a_number_is_refused(void **state)
{
    (void)state;
    ls_402_scale_t s;
    assert_int_equal(ls_402_scale_init(&s, 1e9, 1, 0.0, 0.0), LS_OK);
    ls_402_unwrap_t u;
    ls_402_unwrap_reset(&u);
    int32_t raw = 7;
    assert_int_equal(ls_402_target_raw(&s, &u, 0.0, &raw), LS_EINVAL); /* no reading yet */
    ls_402_unwrap(&u, 0);
    assert_int_equal(ls_402_target_raw(&s, &u, 2.2, &raw), LS_ERANGE); /* 2.2e9 counts away */
    assert_int_equal(ls_402_target_raw(&s, &u, -2.2, &raw), LS_ERANGE);
    assert_int_equal(ls_402_target_raw(&s, &u, INFINITY, &raw), LS_EINVAL);
    assert_int_equal(ls_402_target_raw(&s, &u, NAN, &raw), LS_EINVAL);
    assert_int_equal(raw, 7);
    assert_int_equal(ls_402_target_raw(&s, &u, 2.1, &raw), LS_OK);
    assert_int_equal(raw, 2100000000);
    ls_402_scale_t t = s;
    assert_int_equal(ls_402_scale_init(&t, 0.0, 1, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, -1.0, 1, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, NAN, 1, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, 1.0, 0, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, 1.0, 2, 0.0, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, 1.0, 1, INFINITY, 0.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(&t, 1.0, 1, 0.0, -1.0), LS_EINVAL);
    assert_int_equal(ls_402_scale_init(NULL, 1.0, 1, 0.0, 0.0), LS_EINVAL);
    assert_memory_equal(&t, &s, sizeof s);
}

/* The per-cycle calls allocate nothing (the init ones neither). */
static void test_a_drive_cycle_allocates_nothing(void **state)
{
    (void)state;
    alloc_counter_reset();
    alloc_counter_arm();
    ls_402_axis_t ax = new_axis(50, 3);
    drive_t d;
    drive_init(&d, SW_FAULT, 2);
    run(&ax, &d, LS_402_WANT_ENABLED, true, 100, NULL);
    ls_402_scale_t s;
    ls_402_scale_init(&s, 1000.0, 1, 0.0, 0.0);
    ls_402_unwrap_t u;
    ls_402_unwrap_reset(&u);
    int32_t raw;
    ls_402_unwrap(&u, 12);
    ls_402_target_raw(&s, &u, 0.1, &raw);
    ls_402_vel_raw(&s, 0.1, &raw);
    ls_402_out_t out;
    ls_402_step(&ax, SW_OE, LS_402_WANT_ENABLED, false, &out);
    char line[128];
    ls_402_describe(&out, line, sizeof line);
    alloc_counter_disarm();
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_statusword_decodes_as_the_standards_table_says),
        cmocka_unit_test(test_states_and_commands_have_the_standards_names),
        cmocka_unit_test(test_enabling_steps_shutdown_switch_on_enable_each_once_confirmed),
        cmocka_unit_test(test_enabled_is_reported_only_from_an_operation_enabled_statusword),
        cmocka_unit_test(test_every_state_and_want_gives_the_standards_command),
        cmocka_unit_test(test_disabling_an_enabled_drive_is_one_shutdown),
        cmocka_unit_test(test_quick_stop_holds_and_enabling_again_goes_through_switch_on_disabled),
        cmocka_unit_test(test_fault_reset_is_a_rising_edge_after_a_cycle_with_bit_7_low),
        cmocka_unit_test(test_no_reset_edge_is_sent_unless_allowed),
        cmocka_unit_test(test_a_drive_that_stays_in_fault_is_reported_after_the_configured_edges),
        cmocka_unit_test(test_a_drive_that_faults_on_every_enable_ends_as_staying_in_fault),
        cmocka_unit_test(test_a_step_the_drive_does_not_follow_is_stuck_in_its_state),
        cmocka_unit_test(test_a_drive_that_never_leaves_not_ready_is_stuck_there),
        cmocka_unit_test(test_the_statusword_flags_are_reported),
        cmocka_unit_test(test_bad_input_is_refused_and_leaves_everything_untouched),
        cmocka_unit_test(test_the_default_time_out_is_a_second_of_cycles),
        cmocka_unit_test(test_unwrapping_crosses_the_int32_wrap_upward),
        cmocka_unit_test(test_unwrapping_crosses_the_int32_wrap_downward),
        cmocka_unit_test(test_positions_and_velocities_scale_with_sign_and_offset),
        cmocka_unit_test(test_a_target_converts_to_what_the_drive_reads_there_across_the_wrap),
        cmocka_unit_test(test_a_target_too_far_or_not_a_number_is_refused),
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_a_drive_cycle_allocates_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
