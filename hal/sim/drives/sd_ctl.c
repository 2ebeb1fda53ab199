/* The control socket's command parser (sd_ctl.h). Numbers are parsed here,
 * not with strtoul, which takes signs and blanks this protocol does not. */
#include "sd_ctl.h"

#include <stdbool.h>
#include <string.h>

#include "hal_sim_drives.h"
#include "ls_canopen.h"
#include "ls_err.h"

#define MAX_FIELDS 4

typedef struct {
    const char *p;
    size_t n;
} tok_t;

#define NOT_HEX (-1) /* a character that is no hexadecimal digit */

static bool is_blank(char c)
{
    return c == ' ' || c == '\t';
}

static bool tok_is(tok_t t, const char *word)
{
    size_t n = strlen(word);
    return t.n == n && memcmp(t.p, word, n) == 0;
}

/* C notation: 0x then 1-8 hex digits, or 1-10 decimal digits; <= max. */
static bool parse_num(tok_t t, uint32_t max, uint32_t *out)
{
    uint64_t v = 0;
    if (t.n > 2 && t.p[0] == '0' && (t.p[1] == 'x' || t.p[1] == 'X')) {
        if (t.n > 10) {
            return false;
        }
        for (size_t i = 2; i < t.n; i++) {
            char c = t.p[i];
            int d = c >= '0' && c <= '9'   ? c - '0'
                    : c >= 'a' && c <= 'f' ? c - 'a' + 10
                    : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                           : NOT_HEX;
            if (d == NOT_HEX) {
                return false;
            }
            v = v << 4 | (uint64_t)d;
        }
    } else {
        if (t.n == 0 || t.n > 10) {
            return false;
        }
        for (size_t i = 0; i < t.n; i++) {
            if (t.p[i] < '0' || t.p[i] > '9') {
                return false;
            }
            v = v * 10u + (uint64_t)(t.p[i] - '0');
        }
    }
    if (v > max) {
        return false;
    }
    *out = (uint32_t)v;
    return true;
}

static bool parse_node(tok_t t, uint8_t *node)
{
    uint32_t v = 0;
    if (!parse_num(t, LS_CO_NODE_MAX, &v) || v < LS_CO_NODE_MIN) {
        return false;
    }
    *node = (uint8_t)v;
    return true;
}

/* Commands: word, number of fields after it (min, max), node first? */
static const struct {
    const char *word;
    sd_ctl_kind_t kind;
    int min, max;
    bool node;
} k_cmds[] = {
    { "emcy", SD_CTL_EMCY, 2, 2, true },
    { "silence", SD_CTL_SILENCE, 1, 1, true },
    { "freeze-tpdo", SD_CTL_FREEZE_TPDO, 1, 1, true },
    { "sticky-fault", SD_CTL_STICKY, 2, 2, true },
    { "no-boot", SD_CTL_NO_BOOT, 1, 1, true },
    { "identity", SD_CTL_IDENTITY, 3, 3, true },
    { "sto", SD_CTL_STO, 2, 2, true },
    { "bus-off", SD_CTL_BUS_OFF, 0, 1, false },
    { "reset", SD_CTL_RESET, 0, 0, false },
};

int sd_ctl_parse(const char *text, size_t len, sd_ctl_cmd_t *out)
{
    if (text == NULL || out == NULL || len > HAL_SIM_DRIVES_CTL_MAX_MSG) {
        return LS_EINVAL;
    }
    if (len > 0 && text[len - 1] == '\n') {
        len--;
    }
    tok_t f[MAX_FIELDS + 1];
    int nf = 0;
    size_t i = 0;
    while (i < len) {
        while (i < len && is_blank(text[i])) {
            i++;
        }
        if (i == len) {
            break;
        }
        if (nf == MAX_FIELDS + 1) {
            return LS_EINVAL;
        }
        size_t start = i;
        while (i < len && !is_blank(text[i])) {
            if (text[i] == '\0' || text[i] == '\n' || text[i] == '\r') {
                return LS_EINVAL;
            }
            i++;
        }
        f[nf++] = (tok_t){ text + start, i - start };
    }
    if (nf == 0) {
        return LS_EINVAL;
    }
    for (size_t c = 0; c < sizeof k_cmds / sizeof k_cmds[0]; c++) {
        if (!tok_is(f[0], k_cmds[c].word)) {
            continue;
        }
        int args = nf - 1;
        if (args < k_cmds[c].min || args > k_cmds[c].max) {
            return LS_EINVAL;
        }
        sd_ctl_cmd_t cmd = { .kind = k_cmds[c].kind, .node = 0, .a = 0, .b = 0 };
        if (k_cmds[c].node && !parse_node(f[1], &cmd.node)) {
            return LS_EINVAL;
        }
        bool ok = true;
        switch (cmd.kind) {
        case SD_CTL_EMCY: ok = parse_num(f[2], 0xFFFFu, &cmd.a) && cmd.a != LS_CO_EMCY_NO_ERROR; break;
        case SD_CTL_STICKY: ok = parse_num(f[2], SD_CTL_STICKY_MAX, &cmd.a); break;
        case SD_CTL_IDENTITY: ok = parse_num(f[2], UINT32_MAX, &cmd.a) && parse_num(f[3], UINT32_MAX, &cmd.b); break;
        case SD_CTL_STO:
            ok = tok_is(f[2], "on") || tok_is(f[2], "off");
            cmd.a = tok_is(f[2], "on") ? 1u : 0u;
            break;
        case SD_CTL_BUS_OFF:
            cmd.a = HAL_SIM_DRIVES_BUS_OFF_DEFAULT_MS;
            ok = args == 0 || (parse_num(f[1], SD_CTL_BUS_OFF_MAX_MS, &cmd.a) && cmd.a > 0u);
            break;
        case SD_CTL_SILENCE:
        case SD_CTL_FREEZE_TPDO:
        case SD_CTL_NO_BOOT:
        case SD_CTL_RESET: break;
        }
        if (!ok) {
            return LS_EINVAL;
        }
        *out = cmd;
        return LS_OK;
    }
    return LS_EINVAL;
}
