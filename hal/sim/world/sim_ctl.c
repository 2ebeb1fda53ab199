/* The control socket of the simulated world (protocol in hal_sim_world.h) and
 * the DIO unit and manual device it drives. Numbers are parsed here rather
 * than with strtod/strtoul: those accept signs, blanks and locale-dependent
 * decimal points we do not want, and strtod may allocate on long input. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "sim_world_internal.h"

/* Upper bound of datagrams handled per drain, so that a flood cannot stretch
 * a control cycle; the rest stay queued and poll_fd stays readable. */
#define SIM_CTL_MAX_PER_DRAIN 64

typedef struct {
    const char *p;
    size_t n;
} tok_t;

static void set_msg(char *msg, size_t msglen, const char *text, const char *detail)
{
    if (msg != NULL && msglen > 0) {
        snprintf(msg, msglen, "%s%s%s", text, detail != NULL ? ": " : "", detail != NULL ? detail : "");
    }
}

int sim_ctl_open(sim_ctl_t *ctl, const char *path, char *msg, size_t msglen)
{
    memset(ctl, 0, sizeof *ctl);
    ctl->fd = -1;
    ctl->manual_generation = 1;
    if (path == NULL) {
        ctl->open = true;
        return LS_OK;
    }
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    size_t len = strlen(path);
    if (len == 0 || len >= sizeof addr.sun_path || len >= sizeof ctl->path) {
        set_msg(msg, msglen, "DIO socket path is empty or longer than 107 bytes; use a shorter path", path);
        return LS_EINVAL;
    }
    memcpy(addr.sun_path, path, len);
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISSOCK(st.st_mode)) {
            set_msg(msg, msglen, "DIO socket path exists and is not a socket; remove it or pick another path", path);
            return LS_EINVAL;
        }
        (void)unlink(path); /* stale socket of an earlier run */
    }
    int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        set_msg(msg, msglen, "cannot create the DIO socket", strerror(errno));
        return LS_EIO;
    }
    if (bind(fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        set_msg(msg, msglen, "cannot bind the DIO socket (check the directory exists and is writable)",
                strerror(errno));
        (void)close(fd);
        return LS_EIO;
    }
    ctl->fd = fd;
    memcpy(ctl->path, path, len + 1);
    ctl->open = true;
    return LS_OK;
}

void sim_ctl_close(sim_ctl_t *ctl)
{
    if (ctl->fd >= 0) {
        (void)close(ctl->fd);
        (void)unlink(ctl->path);
    }
    memset(ctl, 0, sizeof *ctl);
    ctl->fd = -1;
}

bool sim_ctl_jog_active(const sim_ctl_t *ctl)
{
    for (int i = 0; i < 6; i++) {
        if (ctl->twist[i] != 0.0) {
            return true;
        }
    }
    return false;
}

static bool tok_is(tok_t t, const char *word)
{
    size_t n = strlen(word);
    return t.n == n && memcmp(t.p, word, n) == 0;
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return LS_EINVAL;
}

/* 1..8 hex digits with an optional 0x. */
static bool parse_hex(tok_t t, uint32_t *out)
{
    const char *p = t.p;
    size_t n = t.n;
    if (n >= 2 && p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        p += 2;
        n -= 2;
    }
    if (n == 0 || n > 8) {
        return false;
    }
    uint32_t v = 0;
    for (size_t i = 0; i < n; i++) {
        int d = hex_digit(p[i]);
        if (d < 0) {
            return false;
        }
        v = (v << 4) | (uint32_t)d;
    }
    *out = v;
    return true;
}

/* [+-]digits[.digits][(e|E)[+-]digits], at least one mantissa digit; finite. */
static bool parse_decimal(tok_t t, double *out)
{
    const char *p = t.p;
    const char *end = t.p + t.n;
    if (t.n == 0 || t.n > 40) {
        return false;
    }
    bool neg = false;
    if (*p == '+' || *p == '-') {
        neg = *p == '-';
        p++;
    }
    double mant = 0.0;
    int scale = 0;
    int digits = 0;
    while (p < end && *p >= '0' && *p <= '9') {
        mant = mant * 10.0 + (double)(*p - '0');
        digits++;
        p++;
    }
    if (p < end && *p == '.') {
        p++;
        while (p < end && *p >= '0' && *p <= '9') {
            mant = mant * 10.0 + (double)(*p - '0');
            scale--;
            digits++;
            p++;
        }
    }
    if (digits == 0) {
        return false;
    }
    if (p < end && (*p == 'e' || *p == 'E')) {
        p++;
        bool eneg = false;
        if (p < end && (*p == '+' || *p == '-')) {
            eneg = *p == '-';
            p++;
        }
        int e = 0;
        int edigits = 0;
        while (p < end && *p >= '0' && *p <= '9' && edigits < 4) {
            e = e * 10 + (*p - '0');
            edigits++;
            p++;
        }
        if (edigits == 0) {
            return false;
        }
        scale += eneg ? -e : e;
    }
    if (p != end) {
        return false;
    }
    double v = mant * pow(10.0, (double)scale);
    if (!isfinite(v)) {
        return false;
    }
    *out = neg ? -v : v;
    return true;
}

static double clamp1(double v)
{
    return v > 1.0 ? 1.0 : (v < -1.0 ? -1.0 : v);
}

static int tokenize(const char *text, size_t len, tok_t *toks, int max_toks)
{
    /* One optional line ending, nothing else outside printable ASCII. */
    if (len > 0 && text[len - 1] == '\n') {
        len--;
    }
    if (len > 0 && text[len - 1] == '\r') {
        len--;
    }
    int n = 0;
    size_t i = 0;
    while (i < len) {
        char c = text[i];
        if (c == ' ' || c == '\t') {
            i++;
            continue;
        }
        if (c < 0x21 || c > 0x7e) {
            return LS_EINVAL;
        }
        if (n == max_toks) {
            return LS_EINVAL;
        }
        size_t start = i;
        while (i < len && text[i] != ' ' && text[i] != '\t') {
            if (text[i] < 0x21 || text[i] > 0x7e) {
                return LS_EINVAL;
            }
            i++;
        }
        toks[n].p = text + start;
        toks[n].n = i - start;
        n++;
    }
    return n;
}

static int malformed(sim_ctl_t *ctl)
{
    ctl->malformed++;
    return LS_EINVAL;
}

int sim_ctl_apply(sim_ctl_t *ctl, const char *text, size_t len)
{
    tok_t t[8];
    if (len == 0 || len > SIM_CTL_MAX_MSG) {
        return malformed(ctl);
    }
    int n = tokenize(text, len, t, 8);
    if (n < 1) {
        return malformed(ctl);
    }
    if (tok_is(t[0], "in") && n == 3) {
        uint32_t on = 0;
        uint32_t off = 0;
        if (!parse_hex(t[1], &on) || !parse_hex(t[2], &off) || ((on | off) & ~SIM_DIO_INPUT_MASK) != 0) {
            return malformed(ctl);
        }
        uint32_t before = ctl->dio_bits;
        ctl->dio_bits = (ctl->dio_bits | on) & ~off;
        return ctl->dio_bits != before ? 1 : 0;
    }
    if (tok_is(t[0], "jog") && n == 7) {
        double v[6];
        for (int i = 0; i < 6; i++) {
            if (!parse_decimal(t[i + 1], &v[i])) {
                return malformed(ctl);
            }
        }
        int changed = 0;
        for (int i = 0; i < 6; i++) {
            double c = clamp1(v[i]);
            if (c != ctl->twist[i]) {
                changed = 1;
            }
            ctl->twist[i] = c;
        }
        return changed;
    }
    if (tok_is(t[0], "jog-stop") && n == 1) {
        int changed = sim_ctl_jog_active(ctl) ? 1 : 0;
        memset(ctl->twist, 0, sizeof ctl->twist);
        return changed;
    }
    if (tok_is(t[0], "buttons") && n == 2) {
        uint32_t b = 0;
        if (!parse_hex(t[1], &b)) {
            return malformed(ctl);
        }
        int changed = b != ctl->buttons ? 1 : 0;
        ctl->buttons = b;
        return changed;
    }
    if ((tok_is(t[0], "unplug") || tok_is(t[0], "plug")) && n == 1) {
        const bool unplug = tok_is(t[0], "unplug");
        if (unplug == ctl->unplugged) {
            return 0;
        }
        ctl->unplugged = unplug;
        if (!unplug) {
            ctl->manual_generation++; /* a new device: what it held before is forgotten */
        }
        memset(ctl->twist, 0, sizeof ctl->twist);
        ctl->buttons = 0;
        return 1;
    }
    return malformed(ctl);
}

int sim_ctl_drain(sim_ctl_t *ctl)
{
    if (ctl->fd < 0) {
        return 0;
    }
    char buf[SIM_CTL_MAX_MSG + 1];
    int changed = 0;
    for (int k = 0; k < SIM_CTL_MAX_PER_DRAIN; k++) {
        /* MSG_TRUNC: the datagram's real length, so over-long ones are caught. */
        ssize_t r = recv(ctl->fd, buf, sizeof buf, MSG_DONTWAIT | MSG_TRUNC);
        if (r < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                break;
            }
            return changed > 0 ? changed : LS_EIO;
        }
        if (sim_ctl_apply(ctl, buf, (size_t)r) > 0) {
            changed++;
        }
    }
    return changed;
}

/* ---- DIO unit ---- */

static sim_ctl_t *ctl_of(void *self)
{
    sim_ctl_t *ctl = self;
    return (ctl != NULL && ctl->open) ? ctl : NULL;
}

static int dio_unit_count(void *self)
{
    return ctl_of(self) != NULL ? 1 : LS_ENODEV;
}

static int dio_describe(void *self, uint16_t unit, hal_dio_unit_info_t *out)
{
    if (ctl_of(self) == NULL) {
        return LS_ENODEV;
    }
    if (unit != 0 || out == NULL) {
        return LS_EINVAL;
    }
    out->input_mask = SIM_DIO_INPUT_MASK;
    out->output_mask = SIM_DIO_OUTPUT_MASK;
    return LS_OK;
}

static int dio_read(void *self, uint16_t unit, uint32_t *bits)
{
    sim_ctl_t *ctl = ctl_of(self);
    if (ctl == NULL) {
        return LS_ENODEV;
    }
    if (unit != 0 || bits == NULL) {
        return LS_EINVAL;
    }
    *bits = ctl->dio_bits;
    return LS_OK;
}

static int dio_write(void *self, uint16_t unit, uint32_t on, uint32_t off)
{
    sim_ctl_t *ctl = ctl_of(self);
    if (ctl == NULL) {
        return LS_ENODEV;
    }
    if (unit != 0 || ((on | off) & ~SIM_DIO_OUTPUT_MASK) != 0) {
        return LS_EINVAL;
    }
    ctl->dio_bits = (ctl->dio_bits | on) & ~off;
    return LS_OK;
}

static int dio_poll_fd(void *self)
{
    sim_ctl_t *ctl = ctl_of(self);
    if (ctl == NULL) {
        return LS_ENODEV;
    }
    return ctl->fd >= 0 ? ctl->fd : LS_EUNSUPPORTED;
}

static int dio_drain_events(void *self)
{
    sim_ctl_t *ctl = ctl_of(self);
    if (ctl == NULL) {
        return LS_ENODEV;
    }
    return sim_ctl_drain(ctl);
}

static void dio_close(void *self)
{
    (void)self; /* the world owns the socket: hal_sim_world_close() */
}

const hal_dio_ops_t sim_dio_ops = {
    .unit_count = dio_unit_count,
    .describe = dio_describe,
    .read = dio_read,
    .write = dio_write,
    .poll_fd = dio_poll_fd,
    .drain_events = dio_drain_events,
    .close = dio_close,
};

/* ---- manual device ---- */

int sim_manual_read(void *self, hal_manual_state_t *out)
{
    if (out == NULL) {
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    sim_ctl_t *ctl = ctl_of(self);
    if (ctl == NULL) {
        return LS_ENODEV;
    }
    out->generation = ctl->manual_generation;
    if (ctl->unplugged) {
        return LS_OK;
    }
    out->present = true;
    memcpy(out->twist, ctl->twist, sizeof ctl->twist);
    out->buttons = ctl->buttons & HAL_MANUAL_BTN_ALL;
    out->age_us = 0; /* the socket's state holds until changed: always current */
    return LS_OK;
}
