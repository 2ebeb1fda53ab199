/* SLCAN serial adapter link (hal_linux_slcan_tty.h). */
#include "hal_linux_slcan_tty.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "slcan_codec.h"

typedef struct {
    bool used;
    int fd;
    char path[200];
    ls_slcan_lexer_t lx;
    char rbuf[512]; /* bytes read, not yet fed to the lexer */
    size_t rlen, rpos;
    char tbuf[4096]; /* whole lines waiting for room in the device */
    size_t tlen;
    hal_can_status_t st;
    uint32_t acks; /* the adapter's CR, BEL, z and Z answers, dropped */
} slcan_tty_t;

static slcan_tty_t g_links[HAL_LINUX_SLCAN_TTY_MAX_LINKS];

char hal_linux_slcan_bitrate_index(uint32_t bitrate)
{
    static const uint32_t rates[] = { 10000u, 20000u, 50000u, 100000u, 125000u, 250000u, 500000u, 800000u, 1000000u };
    for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++) {
        if (rates[i] == bitrate) {
            return (char)('0' + i);
        }
    }
    return 0;
}

/* Write as much of the waiting lines as the device takes; keep the rest. */
static int flush_tx(slcan_tty_t *t)
{
    while (t->tlen > 0) {
        const ssize_t w = write(t->fd, t->tbuf, t->tlen);
        if (w < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
                return LS_EAGAIN;
            }
            return LS_EIO;
        }
        memmove(t->tbuf, t->tbuf + w, t->tlen - (size_t)w);
        t->tlen -= (size_t)w;
    }
    return LS_OK;
}

static int queue_line(slcan_tty_t *t, const char *line, size_t n)
{
    if (t->tlen + n > sizeof t->tbuf) {
        return LS_EAGAIN; /* whole lines only: the caller keeps the frame */
    }
    memcpy(t->tbuf + t->tlen, line, n);
    t->tlen += n;
    return LS_OK;
}

static int tty_send(void *self, const hal_can_frame_t *frame)
{
    slcan_tty_t *t = self;
    char line[LS_SLCAN_MAX_LINE];
    const size_t n = ls_slcan_format(frame, line, sizeof line);
    if (n == 0) {
        return LS_EINVAL;
    }
    if (flush_tx(t) == LS_EIO) {
        t->st.tx_dropped++;
        return LS_EIO;
    }
    if (queue_line(t, line, n) != LS_OK) {
        return LS_EAGAIN;
    }
    t->st.tx_frames++;
    return flush_tx(t) == LS_EIO ? LS_EIO : LS_OK;
}

static int tty_recv(void *self, hal_can_frame_t *frame)
{
    slcan_tty_t *t = self;
    if (t->tlen > 0 && flush_tx(t) == LS_EIO) {
        return LS_EIO;
    }
    for (;;) {
        while (t->rpos < t->rlen) {
            const char c = t->rbuf[t->rpos++];
            if (c == '\a') {
                t->acks++; /* an adapter's "error" answer to a command */
                continue;
            }
            size_t len = 0;
            if (!ls_slcan_lexer_feed(&t->lx, c, &len)) {
                continue;
            }
            ls_slcan_msg_t m;
            if (ls_slcan_parse(t->lx.buf, len, &m) == 0 && m.kind == LS_SLCAN_FRAME) {
                *frame = m.frame;
                t->st.rx_frames++;
                return 1;
            }
            if (len == 0 || t->lx.buf[0] == 'z' || t->lx.buf[0] == 'Z') {
                t->acks++; /* CR, or a transmit acknowledgement */
            } else {
                t->st.rx_dropped++;
            }
        }
        const ssize_t r = read(t->fd, t->rbuf, sizeof t->rbuf);
        if (r > 0) {
            t->rlen = (size_t)r;
            t->rpos = 0;
            continue;
        }
        if (r == 0 || errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
            return LS_EAGAIN;
        }
        return LS_EIO; /* the device went away (an adapter unplugged: EIO) */
    }
}

static int tty_poll_fd(void *self)
{
    return ((slcan_tty_t *)self)->fd;
}

static int tty_status(void *self, hal_can_status_t *out)
{
    *out = ((slcan_tty_t *)self)->st;
    return LS_OK;
}

static bool tty_tx_pending(void *self)
{
    return ((slcan_tty_t *)self)->tlen > 0;
}

static uint64_t tty_next_due_us(void *self)
{
    const slcan_tty_t *t = self;
    return t->rpos < t->rlen ? 0u : UINT64_MAX;
}

static void tty_close(void *self)
{
    slcan_tty_t *t = self;
    if (!t->used) {
        return;
    }
    (void)!write(t->fd, "C\r", 2); /* close the channel: best effort */
    (void)close(t->fd);
    memset(t, 0, sizeof *t);
}

static const hal_can_ops_t k_ops = {
    .send = tty_send,
    .recv = tty_recv,
    .poll_fd = tty_poll_fd,
    .status = tty_status,
    .close = tty_close,
    .tx_pending = tty_tx_pending,
    .next_due_us = tty_next_due_us,
};

static void say(char *msg, size_t msglen, const char *fmt, const char *a, const char *b)
{
    if (msg != NULL && msglen > 0) {
        (void)snprintf(msg, msglen, fmt, a, b);
    }
}

int hal_linux_slcan_tty_open(hal_can_link_t *out, const char *path, uint32_t bitrate, char *msg, size_t msglen)
{
    if (out == NULL || path == NULL || path[0] == '\0') {
        say(msg, msglen, "%s%sno serial device given", "", "");
        return LS_EINVAL;
    }
    memset(out, 0, sizeof *out);
    const char idx = hal_linux_slcan_bitrate_index(bitrate);
    if (idx == 0) {
        say(msg, msglen, "%s: %s", path,
            "the bitrate has no SLCAN index: use 10000, 20000, 50000, 100000, 125000, 250000, 500000, 800000 or "
            "1000000");
        return LS_EINVAL;
    }
    if (strlen(path) >= sizeof g_links[0].path) {
        say(msg, msglen, "%s: %s", path, "path too long");
        return LS_EINVAL;
    }
    slcan_tty_t *t = NULL;
    for (size_t i = 0; i < HAL_LINUX_SLCAN_TTY_MAX_LINKS; i++) {
        if (!g_links[i].used) {
            t = &g_links[i];
            break;
        }
    }
    if (t == NULL) {
        say(msg, msglen, "%s: %s", path, "too many SLCAN serial links");
        return LS_EINVAL;
    }
    const int fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        say(msg, msglen, "%s: %s", path,
            e == ENOENT   ? "no such device: is the adapter plugged in (or ls-simdrives started)?"
            : e == EACCES ? "permission denied: add the service user to the dialout group"
                          : strerror(e));
        return e == ENOENT ? LS_ENODEV : e == EACCES ? LS_EPERM : LS_EIO;
    }
    struct termios tio;
    if (tcgetattr(fd, &tio) == 0) {
        cfmakeraw(&tio);
        tio.c_cc[VMIN] = 0;
        tio.c_cc[VTIME] = 0;
        (void)cfsetspeed(&tio, B115200); /* USB CDC adapters ignore it; FTDI-based ones need one */
        if (tcsetattr(fd, TCSANOW, &tio) != 0) {
            const int e = errno;
            (void)close(fd);
            say(msg, msglen, "%s: raw mode: %s", path, strerror(e));
            return LS_EIO;
        }
    }
    memset(t, 0, sizeof *t);
    t->used = true;
    t->fd = fd;
    memcpy(t->path, path, strlen(path) + 1u);
    ls_slcan_lexer_init(&t->lx);
    t->st.bitrate = bitrate;
    t->st.state = HAL_CAN_STATE_ACTIVE;
    /* Close whatever channel a previous owner left open, set the bitrate, open. */
    const char setup[] = { 'C', '\r', 'S', idx, '\r', 'O', '\r' };
    (void)queue_line(t, setup, sizeof setup);
    if (flush_tx(t) == LS_EIO) {
        const int e = errno;
        memset(t, 0, sizeof *t);
        (void)close(fd);
        say(msg, msglen, "%s: %s", path, strerror(e));
        return LS_EIO;
    }
    out->ops = &k_ops;
    out->self = t;
    (void)snprintf(out->name, sizeof out->name, "slcan:tty:%.120s", path);
    return LS_OK;
}
