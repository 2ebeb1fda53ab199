#include "hal_linux_gpiod.h"

#include <errno.h>
#include <fcntl.h>
#include <gpiod.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/epoll.h>
#include <unistd.h>

#include "hal_linux_msg.h"

typedef struct {
    bool in_use;
    struct gpiod_chip *chip;
    int epfd;
    uint8_t n_in, n_out;
    unsigned in_off[HAL_LINUX_GPIOD_MAX_INPUTS];
    unsigned out_off[HAL_LINUX_GPIOD_MAX_OUTPUTS];
    struct gpiod_line *in[HAL_LINUX_GPIOD_MAX_INPUTS];
    struct gpiod_line *out[HAL_LINUX_GPIOD_MAX_OUTPUTS];
    atomic_uint_least32_t in_bits;  /* bits 0..n_in-1 */
    atomic_uint_least32_t out_bits; /* bits 16..16+n_out-1 */
} gd_unit_t;

static gd_unit_t g_units[HAL_LINUX_GPIOD_MAX_UNITS];
static pthread_mutex_t g_pool_lock = PTHREAD_MUTEX_INITIALIZER;

/* Events taken per line per drain_events call, so a chattering input cannot
 * hold the caller; the rest stays readable for the next call. */
#define GD_MAX_EVENTS_PER_LINE 64

static uint32_t in_mask(const gd_unit_t *u)
{
    return (uint32_t)((1ul << u->n_in) - 1ul);
}
static uint32_t out_mask(const gd_unit_t *u)
{
    return (uint32_t)(((1ul << u->n_out) - 1ul) << HAL_LINUX_GPIOD_OUTPUT_SHIFT);
}

static int gd_unit_count(void *self)
{
    (void)self;
    return 1;
}

static int gd_describe(void *self, uint16_t unit, hal_dio_unit_info_t *out)
{
    const gd_unit_t *u = self;
    if (unit != 0u || out == NULL) {
        return LS_EINVAL;
    }
    out->input_mask = in_mask(u);
    out->output_mask = out_mask(u);
    return LS_OK;
}

static int gd_read(void *self, uint16_t unit, uint32_t *bits)
{
    gd_unit_t *u = self;
    if (unit != 0u || bits == NULL) {
        return LS_EINVAL;
    }
    *bits = (uint32_t)(atomic_load(&u->in_bits) | atomic_load(&u->out_bits));
    return LS_OK;
}

static int gd_write(void *self, uint16_t unit, uint32_t on, uint32_t off)
{
    gd_unit_t *u = self;
    if (unit != 0u || ((on | off) & ~out_mask(u)) != 0u || (on & off) != 0u) {
        return LS_EINVAL; /* not an output, or asked to be both on and off */
    }
    uint32_t cur = (uint32_t)atomic_load(&u->out_bits);
    uint32_t next = (cur | on) & ~off;
    uint32_t changed = cur ^ next;
    for (uint8_t j = 0; j < u->n_out; j++) {
        uint32_t bit = 1u << (HAL_LINUX_GPIOD_OUTPUT_SHIFT + j);
        if ((changed & bit) == 0u) {
            continue;
        }
        if (gpiod_line_set_value(u->out[j], (next & bit) != 0u ? 1 : 0) < 0) {
            return LS_EIO; /* lines before j were switched; the cache says which */
        }
        cur ^= bit;
        atomic_store(&u->out_bits, cur);
    }
    return LS_OK;
}

#define NO_FD (-1) /* poll_fd: no inputs, nothing to wait on (hal_dio.h) */

static int gd_poll_fd(void *self)
{
    const gd_unit_t *u = self;
    return u->n_in > 0u ? u->epfd : NO_FD;
}

static int gd_drain_events(void *self)
{
    gd_unit_t *u = self;
    struct epoll_event evs[HAL_LINUX_GPIOD_MAX_INPUTS];
    int n = epoll_wait(u->epfd, evs, HAL_LINUX_GPIOD_MAX_INPUTS, 0);
    if (n < 0) {
        return errno == EINTR ? 0 : LS_EIO;
    }
    int edges = 0;
    for (int k = 0; k < n; k++) {
        uint32_t i = evs[k].data.u32;
        uint32_t bit = 1u << i;
        for (int m = 0; m < GD_MAX_EVENTS_PER_LINE; m++) {
            struct gpiod_line_event ev;
            if (gpiod_line_event_read(u->in[i], &ev) < 0) {
                if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
                    break;
                }
                return LS_EIO;
            }
            if (ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE) {
                atomic_fetch_or(&u->in_bits, bit);
            } else {
                atomic_fetch_and(&u->in_bits, ~bit);
            }
            edges++;
        }
    }
    return edges;
}

static void gd_release(gd_unit_t *u)
{
    if (u->chip != NULL) {
        gpiod_chip_close(u->chip); /* v1: also releases every requested line */
        u->chip = NULL;
    }
    if (u->epfd >= 0) {
        (void)close(u->epfd);
        u->epfd = -1;
    }
}

static void gd_close(void *self)
{
    gd_unit_t *u = self;
    (void)pthread_mutex_lock(&g_pool_lock);
    if (u->in_use) {
        gd_release(u);
        u->in_use = false;
    }
    (void)pthread_mutex_unlock(&g_pool_lock);
}

static const hal_dio_ops_t gd_ops = {
    .unit_count = gd_unit_count,
    .describe = gd_describe,
    .read = gd_read,
    .write = gd_write,
    .poll_fd = gd_poll_fd,
    .drain_events = gd_drain_events,
    .close = gd_close,
};

/* ---- open ------------------------------------------------------------------ */

static int chip_open(const char *name, struct gpiod_chip **out, char *msg, size_t msglen)
{
    errno = 0;
    struct gpiod_chip *c = gpiod_chip_open_lookup(name);
    if (c != NULL) {
        *out = c;
        return LS_OK;
    }
    int e = errno;
    if (e == EACCES || e == EPERM) {
        return hal_linux_msg(LS_EPERM, msg, msglen,
                             "no permission to open GPIO chip '%s': run as root, or add a udev rule "
                             "(SUBSYSTEM==\"gpio\", KERNEL==\"gpiochip*\", GROUP=\"gpio\", MODE=\"0660\") "
                             "and put the user in group 'gpio'",
                             name);
    }
    if (e == ENOTTY || e == ENODEV || e == EINVAL) {
        if (strncmp(name, "/dev/", 5) == 0 && access(name, F_OK) == 0) {
            return hal_linux_msg(LS_ENODEV, msg, msglen,
                                 "'%s' is not a GPIO character device (ls /dev/gpiochip*; this kernel may lack "
                                 "CONFIG_GPIOLIB)",
                                 name);
        }
    }
    if (e == ENOENT || e == ENODEV || e == ENOTTY || e == EINVAL || e == 0) {
        return hal_linux_msg(LS_ENODEV, msg, msglen,
                             "no GPIO chip '%s' (ls /dev/gpiochip*; this kernel may lack CONFIG_GPIOLIB)", name);
    }
    return hal_linux_msg(LS_EIO, msg, msglen, "cannot open GPIO chip '%s': %s", name, strerror(e));
}

static int check_config(const hal_linux_gpiod_config_t *cfg, char *msg, size_t msglen)
{
    if (cfg->n_inputs > HAL_LINUX_GPIOD_MAX_INPUTS || cfg->n_outputs > HAL_LINUX_GPIOD_MAX_OUTPUTS) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "%u inputs and %u outputs asked; at most %d of each",
                             (unsigned)cfg->n_inputs, (unsigned)cfg->n_outputs, HAL_LINUX_GPIOD_MAX_INPUTS);
    }
    unsigned all[HAL_LINUX_GPIOD_MAX_INPUTS + HAL_LINUX_GPIOD_MAX_OUTPUTS];
    size_t n = 0;
    for (uint8_t i = 0; i < cfg->n_inputs; i++) {
        all[n++] = cfg->input_offsets[i];
    }
    for (uint8_t j = 0; j < cfg->n_outputs; j++) {
        all[n++] = cfg->output_offsets[j];
    }
    for (size_t a = 0; a < n; a++) {
        for (size_t b = a + 1; b < n; b++) {
            if (all[a] == all[b]) {
                return hal_linux_msg(LS_EINVAL, msg, msglen, "GPIO line %u is configured twice", all[a]);
            }
        }
    }
    return LS_OK;
}

static int line_get(gd_unit_t *u, const char *chip, unsigned off, struct gpiod_line **line, char *msg, size_t msglen)
{
    *line = gpiod_chip_get_line(u->chip, off);
    if (*line == NULL) {
        unsigned n = gpiod_chip_num_lines(u->chip);
        if (off >= n) {
            return hal_linux_msg(LS_EINVAL, msg, msglen, "GPIO chip '%s' has lines 0..%u; there is no line %u", chip,
                                 n == 0u ? 0u : n - 1u, off);
        }
        return hal_linux_msg(LS_EIO, msg, msglen, "cannot get line %u of GPIO chip '%s': %s", off, chip,
                             strerror(errno));
    }
    return LS_OK;
}

static int request_failed(struct gpiod_line *line, const char *chip, unsigned off, const char *what, char *msg,
                          size_t msglen)
{
    int e = errno;
    if (e == EBUSY) {
        (void)gpiod_line_update(line);
        const char *who = gpiod_line_consumer(line);
        return hal_linux_msg(LS_EIO, msg, msglen,
                             "GPIO line %u of '%s' is busy (used by '%s'): stop that user or pick another line "
                             "(gpioinfo %s)",
                             off, chip, who != NULL ? who : "another process", chip);
    }
    if (e == EACCES || e == EPERM) {
        return hal_linux_msg(LS_EPERM, msg, msglen, "no permission to request GPIO line %u of '%s' as %s", off, chip,
                             what);
    }
    if (e == ENXIO || e == EINVAL || e == ENOTSUP || e == EOPNOTSUPP) {
        return hal_linux_msg(LS_EIO, msg, msglen, "GPIO line %u of '%s' cannot be used as %s: %s", off, chip, what,
                             strerror(e));
    }
    return hal_linux_msg(LS_EIO, msg, msglen, "requesting GPIO line %u of '%s' as %s failed: %s", off, chip, what,
                         strerror(e));
}

static int setup_inputs(gd_unit_t *u, const char *chip, char *msg, size_t msglen)
{
    uint32_t bits = 0;
    for (uint8_t i = 0; i < u->n_in; i++) {
        unsigned off = u->in_off[i];
        int rc = line_get(u, chip, off, &u->in[i], msg, msglen);
        if (rc != LS_OK) {
            return rc;
        }
        if (gpiod_line_request_both_edges_events(u->in[i], HAL_LINUX_GPIOD_CONSUMER) < 0) {
            return request_failed(u->in[i], chip, off, "an input with edge events", msg, msglen);
        }
        int fd = gpiod_line_event_get_fd(u->in[i]);
        int fl = fd < 0 ? fd : fcntl(fd, F_GETFL);
        if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0) {
            return hal_linux_msg(LS_EIO, msg, msglen, "cannot make the event fd of GPIO line %u non-blocking: %s", off,
                                 strerror(errno));
        }
        struct epoll_event ev = { .events = EPOLLIN, .data.u32 = i };
        if (epoll_ctl(u->epfd, EPOLL_CTL_ADD, fd, &ev) < 0) {
            return hal_linux_msg(LS_EIO, msg, msglen, "epoll_ctl for GPIO line %u failed: %s", off, strerror(errno));
        }
        /* Read after the event request so no edge falls between the two. */
        int v = gpiod_line_get_value(u->in[i]);
        if (v < 0) {
            return hal_linux_msg(LS_EIO, msg, msglen, "cannot read GPIO line %u of '%s': %s", off, chip,
                                 strerror(errno));
        }
        if (v != 0) {
            bits |= 1u << i;
        }
    }
    atomic_store(&u->in_bits, bits);
    return LS_OK;
}

static int setup_outputs(gd_unit_t *u, const char *chip, char *msg, size_t msglen)
{
    for (uint8_t j = 0; j < u->n_out; j++) {
        unsigned off = u->out_off[j];
        int rc = line_get(u, chip, off, &u->out[j], msg, msglen);
        if (rc != LS_OK) {
            return rc;
        }
        if (gpiod_line_request_output(u->out[j], HAL_LINUX_GPIOD_CONSUMER, 0) < 0) {
            return request_failed(u->out[j], chip, off, "an output", msg, msglen);
        }
    }
    atomic_store(&u->out_bits, 0u);
    return LS_OK;
}

static gd_unit_t *pool_take(void)
{
    gd_unit_t *found = NULL;
    (void)pthread_mutex_lock(&g_pool_lock);
    for (size_t i = 0; i < HAL_LINUX_GPIOD_MAX_UNITS; i++) {
        if (!g_units[i].in_use) {
            found = &g_units[i];
            memset(found, 0, sizeof *found);
            found->epfd = -1;
            found->in_use = true;
            break;
        }
    }
    (void)pthread_mutex_unlock(&g_pool_lock);
    return found;
}

int hal_linux_gpiod_open(hal_dio_t *out, const hal_linux_gpiod_config_t *cfg, char *msg, size_t msglen)
{
    if (out == NULL || cfg == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "hal_linux_gpiod_open: out and cfg must not be NULL");
    }
    out->ops = NULL;
    out->self = NULL;
    out->name[0] = '\0';
    const char *chip = cfg->chip != NULL ? cfg->chip : "gpiochip0";
    int rc = check_config(cfg, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    gd_unit_t *u = pool_take();
    if (u == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen,
                             "all %d GPIO DIO units are in use: close one or raise HAL_LINUX_GPIOD_MAX_UNITS",
                             HAL_LINUX_GPIOD_MAX_UNITS);
    }
    u->n_in = cfg->n_inputs;
    u->n_out = cfg->n_outputs;
    memcpy(u->in_off, cfg->input_offsets, sizeof u->in_off);
    memcpy(u->out_off, cfg->output_offsets, sizeof u->out_off);

    rc = chip_open(chip, &u->chip, msg, msglen);
    if (rc == LS_OK) {
        u->epfd = epoll_create1(EPOLL_CLOEXEC);
        if (u->epfd < 0) {
            rc = hal_linux_msg(LS_EIO, msg, msglen, "epoll_create1 failed: %s", strerror(errno));
        }
    }
    if (rc == LS_OK) {
        rc = setup_inputs(u, chip, msg, msglen);
    }
    if (rc == LS_OK) {
        rc = setup_outputs(u, chip, msg, msglen);
    }
    if (rc != LS_OK) {
        gd_close(u);
        return rc;
    }
    out->ops = &gd_ops;
    out->self = u;
    (void)snprintf(out->name, sizeof out->name, "gpiod:%s", gpiod_chip_name(u->chip));
    return hal_linux_msg(LS_OK, msg, msglen, "%s open: %u inputs, %u outputs", out->name, (unsigned)u->n_in,
                         (unsigned)u->n_out);
}

int hal_linux_gpiod_probe(const char *chip, char *msg, size_t msglen)
{
    const char *name = chip != NULL ? chip : "gpiochip0";
    struct gpiod_chip *c = NULL;
    int rc = chip_open(name, &c, msg, msglen);
    if (rc != LS_OK) {
        return rc;
    }
    rc = hal_linux_msg(LS_OK, msg, msglen, "%s [%s] %u lines", gpiod_chip_name(c), gpiod_chip_label(c),
                       gpiod_chip_num_lines(c));
    gpiod_chip_close(c);
    return rc;
}
