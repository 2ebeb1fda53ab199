/* evdev manual devices (hal_linux_evdev.h): a reader thread per device, a
 * seqlock slot between it and the control loop. */
#include "hal_linux_evdev.h"

#include <errno.h>
#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

#include "hal_linux_msg.h"
#include "ls_seqlock.h"

#define READ_BATCH 64  /* input_events per read(2) */
#define SLOT_TRIES 16u /* seqlock attempts of one read() before it takes the last copy */
#define BITS_LONG (8u * sizeof(unsigned long))
#define NLONGS(n) (((n) + BITS_LONG - 1u) / BITS_LONG)

/* What the thread publishes; copied word by word under the seqlock. */
typedef struct {
    double twist[HAL_EVDEV_AXES];
    uint32_t buttons;
    uint32_t present;
    uint64_t last_us; /* CLOCK_MONOTONIC of the last report */
    uint32_t generation;
    uint32_t pad_;
} slot_t;

#define SLOT_WORDS LS_SEQLOCK_WORDS(sizeof(slot_t))

typedef struct {
    bool used;
    hal_evdev_config_t cfg;
    char path[HAL_MANUAL_NAME_LEN];
    pthread_t thread;
    int stop_fd; /* eventfd: close() wakes the thread */
    /* reader thread -> control loop */
    atomic_uint seq;
    atomic_uint words[SLOT_WORDS];
    /* control-loop private: the last consistent copy */
    slot_t last;
    /* reader-thread private */
    hal_evdev_decoder_t dec;
    int fd;
    uint32_t generation;
} evdev_t;

static evdev_t g_pool[HAL_EVDEV_MAX_DEVICES];
static pthread_mutex_t g_pool_lock = PTHREAD_MUTEX_INITIALIZER; /* open/close only */

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static bool test_bit(const unsigned long *bits, unsigned n)
{
    return (bits[n / BITS_LONG] >> (n % BITS_LONG)) & 1ul;
}

/* ---- the slot ---- */

static void publish(evdev_t *e, bool present, uint64_t last_us)
{
    slot_t s;
    memset(&s, 0, sizeof s);
    if (present) {
        hal_evdev_decoder_twist(&e->dec, s.twist);
        s.buttons = e->dec.buttons;
    }
    s.present = present ? 1u : 0u;
    s.last_us = last_us;
    s.generation = e->generation;
    ls_seqlock_write(&e->seq, e->words, SLOT_WORDS, &s, sizeof s);
}

static int evdev_read(void *self, hal_manual_state_t *out)
{
    if (out == NULL) {
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    evdev_t *e = self;
    if (e == NULL || !e->used) {
        return LS_ENODEV;
    }
    slot_t fresh;
    if (ls_seqlock_read(&e->seq, e->words, SLOT_WORDS, &fresh, sizeof fresh, SLOT_TRIES)) {
        e->last = fresh;
    }
    /* Out of attempts (the reader thread stopped mid-publish): the last copy. */
    const slot_t *s = &e->last;
    out->present = s->present != 0u;
    out->generation = s->generation;
    if (out->present) {
        memcpy(out->twist, s->twist, sizeof out->twist);
        out->buttons = s->buttons;
        const uint64_t now = mono_us();
        out->age_us = now > s->last_us ? now - s->last_us : 0u;
    }
    return LS_OK;
}

/* ---- the device ---- */

/* The axes' ranges and current values, the keys held: at open and after
 * SYN_DROPPED. false when an ioctl fails (the device went away). */
static bool sync_state(evdev_t *e)
{
    hal_evdev_decoder_t *d = &e->dec;
    for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
        if (d->map.axis[i].type == EV_ABS) {
            struct input_absinfo ai;
            if (ioctl(e->fd, EVIOCGABS((unsigned)d->map.axis[i].code), &ai) < 0) {
                memset(&d->abs[i], 0, sizeof d->abs[i]); /* an axis the device lacks reads 0 */
                d->raw[i] = 0;
                if (errno == ENODEV) {
                    return false;
                }
                continue;
            }
            d->abs[i] = ai;
            d->raw[i] = ai.value;
        } else {
            d->raw[i] = 0; /* a relative axis: at rest until it reports */
        }
    }
    unsigned long keys[NLONGS(KEY_CNT)];
    memset(keys, 0, sizeof keys);
    if (ioctl(e->fd, EVIOCGKEY(sizeof keys), keys) < 0) {
        return errno != ENODEV;
    }
    d->buttons = 0;
    for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT; i++) {
        if (d->map.button[i] != 0 && d->map.button[i] < KEY_CNT && test_bit(keys, d->map.button[i])) {
            d->buttons |= 1u << i;
        }
    }
    return true;
}

static void close_device(evdev_t *e)
{
    if (e->fd >= 0) {
        (void)close(e->fd);
        e->fd = -1;
    }
    publish(e, false, 0);
}

/* Try the path once: true with the device open and its state published. */
static bool try_open(evdev_t *e)
{
    e->fd = open(e->path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (e->fd < 0) {
        return false;
    }
    int version = 0;
    hal_evdev_decoder_init(&e->dec, &e->cfg.map);
    if (ioctl(e->fd, EVIOCGVERSION, &version) < 0 || !sync_state(e)) {
        (void)close(e->fd); /* not an input device, or gone again */
        e->fd = -1;
        return false;
    }
    e->generation++;
    publish(e, true, mono_us());
    return true;
}

/* Wait up to timeout_ms for the stop fd (and the device, when open): true
 * when asked to stop. */
static bool wait(evdev_t *e, int timeout_ms, short *dev_revents)
{
    struct pollfd p[2] = { { .fd = e->stop_fd, .events = POLLIN, .revents = 0 },
                           { .fd = e->fd, .events = POLLIN, .revents = 0 } };
    int r = poll(p, e->fd >= 0 ? 2u : 1u, timeout_ms);
    *dev_revents = r > 0 && e->fd >= 0 ? p[1].revents : 0;
    return r > 0 && (p[0].revents & POLLIN) != 0;
}

/* Read what is pending; false when the device went away. */
static bool drain(evdev_t *e)
{
    struct input_event ev[READ_BATCH];
    for (;;) {
        ssize_t n = read(e->fd, ev, sizeof ev);
        if (n < 0) {
            return errno == EAGAIN || errno == EINTR;
        }
        if (n == 0 || (size_t)n % sizeof ev[0] != 0) {
            return false;
        }
        bool report = false;
        for (size_t i = 0; i < (size_t)n / sizeof ev[0]; i++) {
            switch (hal_evdev_decoder_feed(&e->dec, &ev[i])) {
            case HAL_EVDEV_REPORT: report = true; break;
            case HAL_EVDEV_RESYNC:
                if (!sync_state(e)) {
                    return false;
                }
                report = true;
                break;
            case HAL_EVDEV_FED: break;
            }
        }
        if (report) {
            publish(e, true, mono_us());
        }
        if ((size_t)n < sizeof ev) {
            return true;
        }
    }
}

static void *reader(void *arg)
{
    evdev_t *e = arg;
    short rev = 0;
    for (;;) {
        if (e->fd < 0 && !try_open(e)) {
            if (wait(e, HAL_EVDEV_RETRY_MS, &rev)) {
                break;
            }
            continue;
        }
        if (wait(e, -1, &rev)) {
            break;
        }
        if ((rev & (POLLERR | POLLHUP | POLLNVAL)) != 0 || ((rev & POLLIN) != 0 && !drain(e))) {
            close_device(e); /* unplugged: try the path again */
        }
    }
    if (e->fd >= 0) {
        close_device(e);
    }
    return NULL;
}

int hal_linux_evdev_open(hal_manual_t *out, const hal_evdev_config_t *cfg, char *msg, size_t msglen)
{
    if (out == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "no handle to fill");
    }
    memset(out, 0, sizeof *out);
    if (cfg == NULL || cfg->path == NULL || cfg->path[0] == '\0') {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "no device path: give the device's /dev/input/by-id/... path");
    }
    if (strlen(cfg->path) >= HAL_MANUAL_NAME_LEN) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "%s: the path is longer than %d characters", cfg->path,
                             HAL_MANUAL_NAME_LEN - 1);
    }
    bool any = false;
    for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
        any = any || cfg->map.axis[i].type != 0;
    }
    if (!any) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "%s: the map has no axis: map at least one of vx..wz", cfg->path);
    }
    pthread_mutex_lock(&g_pool_lock);
    evdev_t *e = NULL;
    for (size_t i = 0; i < HAL_EVDEV_MAX_DEVICES && e == NULL; i++) {
        if (!g_pool[i].used) {
            e = &g_pool[i];
            memset(e, 0, sizeof *e);
            e->used = true;
        }
    }
    pthread_mutex_unlock(&g_pool_lock);
    if (e == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "%s: at most %d evdev devices", cfg->path, HAL_EVDEV_MAX_DEVICES);
    }
    e->cfg = *cfg;
    snprintf(e->path, sizeof e->path, "%s", cfg->path);
    e->cfg.path = e->path;
    e->fd = -1;
    e->stop_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    publish(e, false, 0);
    e->last.present = 0;
    int err = e->stop_fd < 0 ? errno : pthread_create(&e->thread, NULL, reader, e);
    if (err != 0) {
        if (e->stop_fd >= 0) {
            (void)close(e->stop_fd);
        }
        e->used = false;
        return hal_linux_msg(LS_EIO, msg, msglen, "%s: cannot start its reader thread: %s", cfg->path, strerror(err));
    }
    out->read = evdev_read;
    out->self = e;
    out->stale_ms = cfg->stale_ms;
    snprintf(out->name, sizeof out->name, "%s", e->path);
    return LS_OK;
}

void hal_linux_evdev_close(hal_manual_t *dev)
{
    if (dev == NULL || dev->read != evdev_read || dev->self == NULL) {
        return;
    }
    evdev_t *e = dev->self;
    if (e->used) {
        const uint64_t one = 1;
        (void)!write(e->stop_fd, &one, sizeof one);
        (void)pthread_join(e->thread, NULL);
        (void)close(e->stop_fd);
        pthread_mutex_lock(&g_pool_lock);
        e->used = false;
        pthread_mutex_unlock(&g_pool_lock);
    }
    memset(dev, 0, sizeof *dev);
}

/* "ABS_X ABS_Y" of the mapped axes / keys the device lacks, into out. */
static size_t missing(int fd, const hal_evdev_map_t *map, char *out, size_t cap)
{
    unsigned long abs[NLONGS(ABS_CNT)], rel[NLONGS(REL_CNT)], key[NLONGS(KEY_CNT)];
    memset(abs, 0, sizeof abs);
    memset(rel, 0, sizeof rel);
    memset(key, 0, sizeof key);
    (void)ioctl(fd, EVIOCGBIT(EV_ABS, sizeof abs), abs);
    (void)ioctl(fd, EVIOCGBIT(EV_REL, sizeof rel), rel);
    (void)ioctl(fd, EVIOCGBIT(EV_KEY, sizeof key), key);
    size_t used = 0, n = 0;
    out[0] = '\0';
    for (unsigned i = 0; i < HAL_EVDEV_AXES; i++) {
        const hal_evdev_axis_t *a = &map->axis[i];
        bool has = (a->type == EV_ABS && a->code < ABS_CNT && test_bit(abs, a->code)) ||
                   (a->type == EV_REL && a->code < REL_CNT && test_bit(rel, a->code));
        if (a->type != 0 && !has && used < cap) {
            const char *nm = libevdev_event_code_get_name(a->type, a->code);
            int w = snprintf(out + used, cap - used, "%s%s (%s)", used > 0 ? ", " : "", nm != NULL ? nm : "?",
                             hal_manual_axis_name(i));
            used += w > 0 ? (size_t)w : 0u;
            n++;
        }
    }
    for (unsigned i = 0; i < HAL_MANUAL_BTN_COUNT; i++) {
        const uint16_t c = map->button[i];
        if (c != 0 && !(c < KEY_CNT && test_bit(key, c)) && used < cap) {
            const char *nm = libevdev_event_code_get_name(EV_KEY, c);
            int w = snprintf(out + used, cap - used, "%s%s (%s)", used > 0 ? ", " : "", nm != NULL ? nm : "?",
                             hal_manual_button_name(i));
            used += w > 0 ? (size_t)w : 0u;
            n++;
        }
    }
    return n;
}

int hal_linux_evdev_probe(const char *path, const hal_evdev_map_t *map, char *msg, size_t msglen)
{
    if (path == NULL || map == NULL) {
        return hal_linux_msg(LS_EINVAL, msg, msglen, "no device path");
    }
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        if (e == ENOENT || e == ENODEV || e == ENXIO) {
            return hal_linux_msg(
                LS_ENODEV, msg, msglen,
                "%s: not there (%s): plug the device in (ls -l /dev/input/by-id/); landscaped picks it "
                "up when it appears",
                path, strerror(e));
        }
        if (e == EACCES || e == EPERM) {
            return hal_linux_msg(LS_EPERM, msg, msglen,
                                 "%s: not readable by this user (%s): install the package's udev rule "
                                 "(60-landscape-input.rules: group input) and put the user in group input",
                                 path, strerror(e));
        }
        return hal_linux_msg(LS_EIO, msg, msglen, "%s: cannot open: %s", path, strerror(e));
    }
    char name[96] = "";
    int version = 0;
    if (ioctl(fd, EVIOCGVERSION, &version) < 0) {
        (void)close(fd);
        return hal_linux_msg(LS_EINVAL, msg, msglen,
                             "%s: not an input event device (EVIOCGVERSION failed): give its event node "
                             "or /dev/input/by-id/...-event-* link",
                             path);
    }
    if (ioctl(fd, EVIOCGNAME(sizeof name - 1), name) < 0) {
        snprintf(name, sizeof name, "?");
    }
    char lack[256];
    const size_t n = missing(fd, map, lack, sizeof lack);
    (void)close(fd);
    char axes[192], buttons[192];
    hal_evdev_format_axes(map, axes, sizeof axes);
    hal_evdev_format_buttons(map, buttons, sizeof buttons);
    if (n > 0) {
        return hal_linux_msg(LS_EINVAL, msg, msglen,
                             "%s: \"%s\" lacks %s of the map (axes %s; buttons %s): fix the map", path, name, lack,
                             axes, buttons);
    }
    return hal_linux_msg(LS_OK, msg, msglen, "%s: \"%s\" readable; has every mapped axis (%s) and button (%s)", path,
                         name, axes, buttons);
}
