/* Where the static RAM goes (bench 7): compiled for the target with the
 * image's flags, never linked. Each object below is a .bss array whose size
 * is one part of the firmware's static state, so `arm-none-eabi-nm -S` of
 * this object reads the sizes as the target's compiler lays the structs out
 * (bench/b_footprint.py turns them into the table of docs/performance.md
 * section 7). The fp_limit_* arrays carry the value of each limit that sizes
 * a part (a limit of 0 would not compile: none is 0).
 *
 * Naming: fp_<object>__<part>; fp_<object>__rest is what the listed parts
 * leave of the whole. */
#include <stddef.h>

#include "ls_control.h"
#include "ls_core.h"
#include "ls_net.h"

#define MEMBER_SIZE(type, member) sizeof(((type *)0)->member)
#define SIZE(name, bytes) char fp_##name[bytes];
#define LIMIT(name) char fp_limit_##name[name];

/* ls_core_t (g_core): sessions, path queues, the program being run, scratch messages */
SIZE(core, sizeof(ls_core_t))
SIZE(core__paths, MEMBER_SIZE(ls_core_t, motion.paths))
SIZE(core__prog, MEMBER_SIZE(ls_core_t, motion.prog))
SIZE(core__sessions, MEMBER_SIZE(ls_core_t, sessions))
SIZE(core__up, MEMBER_SIZE(ls_core_t, up))
SIZE(core__down_note, MEMBER_SIZE(ls_core_t, down) + MEMBER_SIZE(ls_core_t, note))
SIZE(core__enc, MEMBER_SIZE(ls_core_t, enc) + MEMBER_SIZE(ls_core_t, note_enc))
SIZE(core__logs, MEMBER_SIZE(ls_core_t, event_log) + MEMBER_SIZE(ls_core_t, fault_log))
SIZE(core__sensor, MEMBER_SIZE(ls_core_t, sensor))
SIZE(core__rest, sizeof(ls_core_t) - MEMBER_SIZE(ls_core_t, motion.paths) - MEMBER_SIZE(ls_core_t, motion.prog) -
                     MEMBER_SIZE(ls_core_t, sessions) - MEMBER_SIZE(ls_core_t, up) - MEMBER_SIZE(ls_core_t, down) -
                     MEMBER_SIZE(ls_core_t, note) - MEMBER_SIZE(ls_core_t, enc) - MEMBER_SIZE(ls_core_t, note_enc) -
                     MEMBER_SIZE(ls_core_t, event_log) - MEMBER_SIZE(ls_core_t, fault_log) -
                     MEMBER_SIZE(ls_core_t, sensor))
SIZE(path_point, sizeof(ls_path_point_t))
SIZE(motion_seg, sizeof(ls_motion_seg_t))
SIZE(session, sizeof(ls_session_t))

/* ls_net_t (g_net): one ISO-TP link and one downlink queue per peer */
SIZE(net, sizeof(ls_net_t))
SIZE(net__isotp, LS_NET_MAX_PEERS *MEMBER_SIZE(ls_net_peer_t, isotp))
SIZE(net__outq, LS_NET_MAX_PEERS *MEMBER_SIZE(ls_net_peer_t, q))
SIZE(net__rxbuf, MEMBER_SIZE(ls_net_t, rxbuf))
SIZE(net__rest, sizeof(ls_net_t) - LS_NET_MAX_PEERS * MEMBER_SIZE(ls_net_peer_t, isotp) -
                    LS_NET_MAX_PEERS * MEMBER_SIZE(ls_net_peer_t, q) - MEMBER_SIZE(ls_net_t, rxbuf))
SIZE(isotp_link, sizeof(ls_isotp_link_t))
SIZE(net_msg, sizeof(ls_net_msg_t))

/* ls_control_t (g_ctl): the loop's queues, its executors and their plans */
SIZE(ctl, sizeof(ls_control_t))
SIZE(ctl__rings, MEMBER_SIZE(ls_control_t, cmd_ring) + MEMBER_SIZE(ls_control_t, ev_ring))
SIZE(ctl__motion, MEMBER_SIZE(ls_control_t, plan_slot) + MEMBER_SIZE(ls_control_t, motion))
SIZE(ctl__react, MEMBER_SIZE(ls_control_t, react_slot) + MEMBER_SIZE(ls_control_t, react))
SIZE(ctl__rest, sizeof(ls_control_t) - MEMBER_SIZE(ls_control_t, cmd_ring) - MEMBER_SIZE(ls_control_t, ev_ring) -
                    MEMBER_SIZE(ls_control_t, plan_slot) - MEMBER_SIZE(ls_control_t, motion) -
                    MEMBER_SIZE(ls_control_t, react_slot) - MEMBER_SIZE(ls_control_t, react))

LIMIT(LS_PATH_MAX)
LIMIT(LS_PATH_MAX_POINTS)
LIMIT(LS_MOTION_MAX_SEGS)
LIMIT(LS_MAX_SUPERVISORS)
LIMIT(LS_DOWNLINK_MAX)
LIMIT(LS_NET_MAX_PEERS)
LIMIT(LS_NET_OUTQ)
LIMIT(LS_ISOTP_MAX_PAYLOAD)
LIMIT(LS_CTL_QUEUE_LEN)
LIMIT(LS_EVENT_LOG_LEN)
LIMIT(LS_FAULT_LOG_LEN)
