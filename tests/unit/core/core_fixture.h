/* The fixture the core's unit tests share (tests/unit/core/test_core_*.c): the
 * controller core, black box: encoded uplinks in, decoded downlinks out.
 *
 * The io captures every downlink and decodes it with nanopb (and fails a test on
 * a notice the schema does not declare). There is no control loop: the core's
 * calls of ls_control_snapshot and ls_control_post are redirected here at link
 * time (-Wl,--wrap, see CMakeLists.txt), so a test sets the snapshot (joints, DIO
 * levels, sensors, cycle) and sees what was posted, whether or not the real
 * ls_control is linked too. */
#ifndef CORE_FIXTURE_H
#define CORE_FIXTURE_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <pb_decode.h>
#include <pb_encode.h>

#include "cmd_sensor.h"
#include "ls_control.h"
#include "ls_core.h"
#include "ls_core_events.h"
#include "ls_kin.h"
#include "ls_robot_urdf.h"
#include "ls_math.h"
#include "ls_units.h"
#include "ls_utf8.h"

#define assert_near(a, b, eps) assert_near_((a), (b), (eps), #a, __FILE__, __LINE__)
#define HOST_A 0x21
#define HOST_B 0x22
#define MAX_RX 64

void assert_near_(double a, double b, double eps, const char *expr, const char *file, int line);
extern ls_control_t g_ctl;
extern ls_ctl_snapshot_t g_snap;
extern ls_ctl_cmd_t g_posted[16];
extern size_t g_nposted;
extern bool g_post_ok;
extern hal_arm_readout_t g_readout;
extern int g_readout_rc;
extern ls_core_t g_core;
extern ls_Downlink g_rx[MAX_RX];
extern uint8_t g_rx_raw[MAX_RX][LS_DOWNLINK_MAX]; /* each downlink's bytes as sent */
extern size_t g_rx_len[MAX_RX];
extern uint8_t g_rx_addr[MAX_RX];
extern size_t g_nrx;
extern uint64_t g_now;
extern uint32_t g_seq;
extern ls_Request g_rq;
extern ls_Uplink g_up;
extern uint8_t g_buf[LS_UPLINK_MAX + 64];
extern const char *const k_path_event_names[];
void assert_notice_declared(const ls_Notice *n);
int fake_send(void *ctx, uint8_t addr, const uint8_t *buf, size_t len);
extern const hal_sensor_t g_sensors[2];
ls_Request *req(pb_size_t tag);
void send_uplink(uint8_t addr);
const ls_Response *send_req(uint8_t addr);
const ls_Response *must(uint8_t addr);
void send_rsvp_reply(uint8_t addr, uint32_t id, int32_t code);
uint64_t nonce_of(uint8_t addr);
void beat(uint8_t addr, uint64_t now_us);
/* A connect request from addr as connect_host sends it (this schema, its
 * nonce, "test-AA"), left in g_rq for the caller to change and send. */
ls_ConnectReq *connect_req(uint8_t addr);
void connect_host(uint8_t addr);
extern ls_DisconnectAction g_cfg_action;
extern uint32_t g_cfg_timeout_ms;
void setup_bare_core(ls_auth_t *auth);
void setup_core(ls_State state);
int setup_locked(void **state);
const ls_Notice *nth_notice(size_t from, size_t k);
size_t count_notices(size_t from);
extern const ls_State k_states[6];
void set_units(ls_LinearUnit lu, ls_AngularUnit au);
int32_t set_speed(ls_SpeedType t, double v, const char **msg);
int32_t set_accel(ls_AccelType t, double v, const char **msg);
const ls_Response *set_dio(const char *type, int32_t unit, uint32_t on, uint32_t off);
uint32_t signal_dio(uint8_t addr, uint32_t bits, int32_t timeout_ms, int32_t cycle_ms, ls_CallbackType cb,
                    int32_t *code);
void assert_data(const ls_Notice *n, const char *d0, const char *d1, const char *d2, const char *d3);
extern int32_t g_done_code;
extern bool g_done_timed_out;
extern int g_done_calls;
const char *done_cb(ls_core_t *core, void *ctx, int32_t ret_code, bool timed_out, uint64_t now_us);
void send_rsvp_reply_data(uint8_t addr, uint32_t id, int32_t code, const char *d0);
const ls_RsvpAck *the_ack(size_t from, uint8_t addr);
const char *events_text(void);
const ls_Notice *dio_rsvp(uint32_t *watch, uint32_t *req_seq);
int watches_in(ls_watch_phase_t phase);
extern const double k_home[6];
size_t resend_same_seq(uint8_t addr, size_t *first);
uint32_t start_move(void);
void loop_stopped(void);
const ls_Notice *the_final(size_t from, uint32_t seq, size_t *count);
bool has_data(const ls_Notice *n, const char *item);
void loop_posts(ls_motion_event_kind_t kind, uint32_t ref_seq);
void loop_posts_event(ls_cev_kind_t kind, uint32_t ref_seq, const char *text);
const ls_Response *send_command_from(uint8_t addr, const char *input);
const ls_Response *response_to(uint32_t seq);
extern int g_halt_posts;
void count_halt(void *ctx);
size_t alarms_to(size_t from, uint8_t addr, const char *event_id, const ls_Notice **last);
const ls_Response *connect_as(uint8_t addr, uint64_t nonce, const char *name);
const ls_Response *connect_with(uint8_t addr, uint32_t period_ms, ls_DisconnectAction action);
void make_room(int n);
void get_units_of(uint8_t addr, const char *linear, const char *angular);
extern int g_drive_calls;
extern bool g_drives_on;
extern int g_stop_calls;
int fake_drives(void *ctx, bool on);
void fake_stop(void *ctx);
const ls_Notice *owner_lost_alarm(size_t from);
const char *fault_log_text(void);
const ls_Response *expect_answer(uint8_t addr, ls_RetCode code, const char *text);
uint32_t start_dio_path(void);
uint32_t start_tagged_path(bool give_cycles, int32_t cycles, const char **msg);
void finish_path(uint32_t seq, const ls_Notice **tag, const ls_Notice **fin);

#endif
