/* ls-simdrives' options (ls_simdrives_opts.h). */
#include "ls_simdrives_opts.h"

#include <errno.h>
#include <getopt.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "faulty_link.h"
#include "ls_canopen.h"
#include "ls_err.h"
#include "ls_math.h"

const char ls_simdrives_usage[] =
    "usage: ls-simdrives --link slcan:pty:PATH|socketcan:IFNAME [options]\n"
    "\n"
    "The simulated arm behind CiA 402 drives, one CANopen node per joint\n"
    "(hal/sim/drives/hal_sim_drives.h; the drive's EDS: ls-simdrive.eds).\n"
    "\n"
    "  --link SPEC              the drive bus: slcan:pty:PATH (a pty a master opens as\n"
    "                           an SLCAN device) or socketcan:IFNAME\n"
    "  --nodes ID,ID,...        node ids for joints 1, 2, ... (default 0x21 to 0x26)\n"
    "  --first-node ID          with --count: nodes ID, ID+1, ... for joints 1, 2, ...\n"
    "  --count N                number of drives, 1 to 6 (default 6)\n"
    "  --counts-per-rad N       position unit (default 2^17 x 100 / 2 pi: a 17-bit\n"
    "                           encoder behind a 100:1 gear)\n"
    "  --position-offset-counts V | ID=V,...\n"
    "                           the encoder count at the joint's zero, for every node\n"
    "                           or per node (e.g. 2147483000: the int32 counter wraps);\n"
    "                           repeatable, a node's own value wins\n"
    "  --control PATH           the misbehaviour socket (Unix datagrams: emcy, silence,\n"
    "                           freeze-tpdo, sticky-fault, no-boot, identity, sto,\n"
    "                           bus-off, reset)\n"
    "  --link-faults SPEC       inject faults on the link (tests; as landscaped's)\n"
    "  --rt-priority N          run at SCHED_FIFO priority N (1..99): drives answer each\n"
    "                           SYNC in time on a busy machine, as hardware does\n"
    "                           (default 0: a normal process)\n"
    "  --model FILE             the arm behind the drives: a robot model file, as\n"
    "                           landscaped's [robot] model (default: ls-sim6)\n"
    "  --substep-ms MS          the physics' sub-step, about (default 1; up to 100):\n"
    "                           longer for a machine too slow to step the arm every\n"
    "                           millisecond in real time (an emulated guest)\n"
    "  --sync-stats             at exit, log the SYNC period as received: median,\n"
    "                           p99, min, max (tests and benchmarks)\n"
    "  --help                   this text\n";

static int fail(char *msg, size_t msglen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(char *msg, size_t msglen, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return LS_EINVAL;
}

/* A node id in C notation (0x21 or 33), 1..127; the end of the number in *end. */
static bool parse_node(const char *s, const char **end, uint8_t *out)
{
    if (s[0] < '0' || s[0] > '9') {
        return false;
    }
    char *e = NULL;
    errno = 0;
    unsigned long v = strtoul(s, &e, 0);
    if (errno != 0 || e == s || v < LS_CO_NODE_MIN || v > LS_CO_NODE_MAX) {
        return false;
    }
    *end = e;
    *out = (uint8_t)v;
    return true;
}

/* A count offset: a decimal int32 (signed) or 0x hex up to 32 bits (two's complement). */
static bool parse_offset(const char *s, const char **end, int32_t *out)
{
    const char *p = s[0] == '-' ? s + 1 : s;
    if (p[0] < '0' || p[0] > '9') {
        return false;
    }
    char *e = NULL;
    errno = 0;
    bool hex = p[0] == '0' && (p[1] == 'x' || p[1] == 'X');
    if (hex) {
        if (p != s) {
            return false; /* no sign on hex */
        }
        unsigned long long v = strtoull(s, &e, 16);
        if (errno != 0 || v > UINT32_MAX) {
            return false;
        }
        uint32_t u = (uint32_t)v;
        *out = u < 0x80000000u ? (int32_t)u : -(int32_t)(~u) - 1;
    } else {
        long long v = strtoll(s, &e, 10);
        if (errno != 0 || v < INT32_MIN || v > INT32_MAX) {
            return false;
        }
        *out = (int32_t)v;
    }
    *end = e;
    return true;
}

static int parse_nodes(const char *s, ls_simdrives_opts_t *o, char *msg, size_t msglen)
{
    size_t n = 0;
    const char *p = s;
    for (;;) {
        uint8_t id = 0;
        if (n == HAL_SIM_DRIVES_MAX) {
            return fail(msg, msglen, "--nodes %s: more than %d nodes (one per joint)", s, HAL_SIM_DRIVES_MAX);
        }
        if (!parse_node(p, &p, &id)) {
            return fail(msg, msglen, "--nodes %s: expected node ids 1 to 127 separated by commas, e.g. 0x21,0x22", s);
        }
        for (size_t k = 0; k < n; k++) {
            if (o->nodes[k] == id) {
                return fail(msg, msglen, "--nodes %s: node 0x%02X is listed twice", s, (unsigned)id);
            }
        }
        o->nodes[n++] = id;
        if (*p == '\0') {
            break;
        }
        if (*p != ',') {
            return fail(msg, msglen, "--nodes %s: expected node ids 1 to 127 separated by commas, e.g. 0x21,0x22", s);
        }
        p++;
    }
    o->n_nodes = n;
    return LS_OK;
}

/* "V" for all, or "ID=V,ID=V" (checked against the nodes once all options are in). */
typedef struct {
    bool all;
    int32_t all_value;
    size_t n;
    uint8_t node[HAL_SIM_DRIVES_MAX];
    int32_t value[HAL_SIM_DRIVES_MAX];
} offsets_t;

static int parse_offsets(const char *s, offsets_t *off, char *msg, size_t msglen)
{
    const char *p = s;
    int32_t v = 0;
    if (strchr(s, '=') == NULL) {
        if (!parse_offset(p, &p, &v) || *p != '\0') {
            return fail(msg, msglen,
                        "--position-offset-counts %s: expected an int32 count (e.g. -5, 2147483000) or ID=V,...", s);
        }
        off->all = true;
        off->all_value = v;
        return LS_OK;
    }
    for (;;) {
        uint8_t id = 0;
        if (!parse_node(p, &p, &id) || *p != '=' || !parse_offset(p + 1, &p, &v) || (*p != '\0' && *p != ',')) {
            return fail(msg, msglen,
                        "--position-offset-counts %s: expected ID=V pairs separated by commas, e.g. 0x21=2147483000",
                        s);
        }
        if (off->n == HAL_SIM_DRIVES_MAX) {
            return fail(msg, msglen, "--position-offset-counts %s: more than %d nodes", s, HAL_SIM_DRIVES_MAX);
        }
        off->node[off->n] = id;
        off->value[off->n] = v;
        off->n++;
        if (*p == '\0') {
            return LS_OK;
        }
        p++;
    }
}

static int copy(char *dst, size_t cap, const char *src, const char *opt, char *msg, size_t msglen)
{
    size_t n = strlen(src);
    if (n == 0 || n >= cap) {
        return fail(msg, msglen, "%s: empty or longer than %zu characters", opt, cap - 1);
    }
    memcpy(dst, src, n + 1);
    return LS_OK;
}

enum {
    OPT_LINK = 256,
    OPT_NODES,
    OPT_FIRST,
    OPT_COUNT,
    OPT_CPR,
    OPT_OFFSET,
    OPT_CONTROL,
    OPT_FAULTS,
    OPT_MODEL,
    OPT_RT,
    OPT_SUBSTEP,
    OPT_SYNC_STATS
};

int ls_simdrives_parse(int argc, char **argv, ls_simdrives_opts_t *o, char *msg, size_t msglen)
{
    static const struct option longopts[] = {
        { "link", required_argument, NULL, OPT_LINK },
        { "nodes", required_argument, NULL, OPT_NODES },
        { "first-node", required_argument, NULL, OPT_FIRST },
        { "count", required_argument, NULL, OPT_COUNT },
        { "counts-per-rad", required_argument, NULL, OPT_CPR },
        { "position-offset-counts", required_argument, NULL, OPT_OFFSET },
        { "control", required_argument, NULL, OPT_CONTROL },
        { "link-faults", required_argument, NULL, OPT_FAULTS },
        { "model", required_argument, NULL, OPT_MODEL },
        { "rt-priority", required_argument, NULL, OPT_RT },
        { "substep-ms", required_argument, NULL, OPT_SUBSTEP },
        { "sync-stats", no_argument, NULL, OPT_SYNC_STATS },
        { "help", no_argument, NULL, 'h' },
        { NULL, 0, NULL, 0 },
    };
    memset(o, 0, sizeof *o);
    o->counts_per_rad = LS_SIMDRIVES_COUNTS_PER_REV / (2.0 * LS_PI);
    o->substep_s = HAL_SIM_DRIVES_SUBSTEP_S;
    offsets_t off;
    memset(&off, 0, sizeof off);
    bool have_nodes = false, have_first = false, have_count = false;
    uint8_t first = LS_SIMDRIVES_FIRST_NODE;
    unsigned long count = HAL_SIM_DRIVES_MAX;
    int c;
    int rc = LS_OK;
    opterr = 0;
    optind = 0; /* glibc: 0 re-initialises getopt completely */
    while (rc == LS_OK && (c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        switch (c) {
        case 'h': return 1;
        case OPT_LINK:
            if (strncmp(optarg, "slcan:pty:", 10) != 0 && strncmp(optarg, "socketcan:", 10) != 0) {
                return fail(msg, msglen, "--link %s: expected slcan:pty:PATH or socketcan:IFNAME", optarg);
            }
            rc = copy(o->link, sizeof o->link, optarg, "--link", msg, msglen);
            break;
        case OPT_NODES:
            have_nodes = true;
            rc = parse_nodes(optarg, o, msg, msglen);
            break;
        case OPT_FIRST: {
            const char *e = NULL;
            if (!parse_node(optarg, &e, &first) || *e != '\0') {
                return fail(msg, msglen, "--first-node %s: expected a node id 1 to 127 (e.g. 0x21)", optarg);
            }
            have_first = true;
            break;
        }
        case OPT_COUNT: {
            char *e = NULL;
            count = strtoul(optarg, &e, 10);
            if (optarg[0] < '1' || optarg[0] > '9' || *e != '\0' || count > HAL_SIM_DRIVES_MAX) {
                return fail(msg, msglen, "--count %s: expected 1 to %d drives", optarg, HAL_SIM_DRIVES_MAX);
            }
            have_count = true;
            break;
        }
        case OPT_CPR: {
            char *e = NULL;
            errno = 0;
            double v = strtod(optarg, &e);
            if (optarg[0] < '0' || optarg[0] > '9' || *e != '\0' || errno != 0 || !(v > 0.0 && v <= 1e9)) {
                return fail(msg, msglen, "--counts-per-rad %s: expected a number above 0, at most 1e9", optarg);
            }
            o->counts_per_rad = v;
            break;
        }
        case OPT_OFFSET: rc = parse_offsets(optarg, &off, msg, msglen); break;
        case OPT_CONTROL: rc = copy(o->control, sizeof o->control, optarg, "--control", msg, msglen); break;
        case OPT_MODEL: rc = copy(o->model, sizeof o->model, optarg, "--model", msg, msglen); break;
        case OPT_RT: {
            char *e = NULL;
            errno = 0;
            const long v = strtol(optarg, &e, 10);
            if (optarg[0] < '0' || optarg[0] > '9' || *e != '\0' || errno != 0 || v > 99) {
                return fail(msg, msglen, "--rt-priority %s: expected 0..99 (0: a normal process)", optarg);
            }
            o->rt_priority = (int)v;
            break;
        }
        case OPT_FAULTS: {
            hal_sim_fault_config_t fc;
            char why[200];
            if (hal_sim_fault_parse(optarg, &fc, why, sizeof why) != LS_OK) {
                return fail(msg, msglen, "--link-faults %s: %s", optarg, why);
            }
            rc = copy(o->link_faults, sizeof o->link_faults, optarg, "--link-faults", msg, msglen);
            break;
        }
        case OPT_SUBSTEP: {
            char *e = NULL;
            errno = 0;
            double v = strtod(optarg, &e);
            if (optarg[0] < '0' || optarg[0] > '9' || *e != '\0' || errno != 0 ||
                !(v > 0.0 && v <= HAL_SIM_DRIVES_SUBSTEP_MAX_S * 1000.0)) {
                return fail(msg, msglen, "--substep-ms %s: expected milliseconds above 0, at most %g", optarg,
                            HAL_SIM_DRIVES_SUBSTEP_MAX_S * 1000.0);
            }
            o->substep_s = v / 1000.0;
            break;
        }
        case OPT_SYNC_STATS: o->sync_stats = true; break;
        case ':': return fail(msg, msglen, "%s: missing value (see --help)", argv[optind - 1]);
        default: return fail(msg, msglen, "unknown option '%s' (see --help)", argv[optind - 1]);
        }
    }
    if (rc != LS_OK) {
        return rc;
    }
    if (optind < argc) {
        return fail(msg, msglen, "unexpected argument '%s' (see --help)", argv[optind]);
    }
    if (o->link[0] == '\0') {
        return fail(msg, msglen, "--link is required: slcan:pty:PATH or socketcan:IFNAME (see --help)");
    }
    if (have_nodes && (have_first || have_count)) {
        return fail(msg, msglen, "--nodes lists the nodes: give it, or --first-node and --count, not both");
    }
    if (!have_nodes) {
        if (first + count - 1u > LS_CO_NODE_MAX) {
            return fail(msg, msglen, "--first-node 0x%02X with --count %lu goes past node 0x7F", (unsigned)first,
                        count);
        }
        o->n_nodes = count;
        for (size_t i = 0; i < count; i++) {
            o->nodes[i] = (uint8_t)(first + i);
        }
    }
    for (size_t i = 0; i < o->n_nodes; i++) {
        o->offsets[i] = off.all ? off.all_value : 0;
    }
    for (size_t k = 0; k < off.n; k++) {
        size_t i = 0;
        while (i < o->n_nodes && o->nodes[i] != off.node[k]) {
            i++;
        }
        if (i == o->n_nodes) {
            return fail(msg, msglen, "--position-offset-counts: node 0x%02X is not one of the drives",
                        (unsigned)off.node[k]);
        }
        o->offsets[i] = off.value[k];
    }
    return 0;
}
