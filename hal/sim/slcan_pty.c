/* SLCAN over a pseudo-terminal. Frames are only sent while the channel is
 * open (the host sent 'O'), so nothing stale piles up in the pty while no
 * supervisor is attached; while sessions live on the link (hal_can_hold_open)
 * a 'C' is deferred until the last one ends; commands are acknowledged with CR like a Lawicel
 * adapter (BEL on error). Transmitted frames are not acknowledged with 'z'
 * (python-can ignores it and the device->host direction is the slower one). */
#include "slcan_pty.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include "slcan_codec.h"

typedef struct {
    bool used;
    int master;
    int slave_keep; /* our own slave fd: keeps the master from seeing EIO while no host is attached */
    bool open;      /* the host sent 'O' */
    bool held;      /* sessions live on this link (hal_can_hold_open) */
    bool close_due; /* a 'C' came while held: carried out when the hold ends */
    char path[256];
    char lock_path[262]; /* path + ".lock" */
    int lock_fd;         /* holds flock(LOCK_EX) on lock_path while the link lives */
    ls_slcan_lexer_t lx;
    char rbuf[512];
    size_t rlen, rpos;
    char tbuf[4096]; /* whole lines waiting for room in the pty */
    size_t tlen;
    hal_can_status_t st;
} slcan_pty_t;

static slcan_pty_t g_links[HAL_SLCAN_PTY_MAX_LINKS];

static void reply(slcan_pty_t *p, char c)
{
    /* Queued behind pending frames so a line is never split; a full queue
     * loses the ack, which python-can ignores anyway. */
    if (p->tlen < sizeof p->tbuf) {
        p->tbuf[p->tlen++] = c;
    }
}

/* Write as much of the pending lines as the pty takes; keeps the rest. */
static int flush_tx(slcan_pty_t *p)
{
    while (p->tlen > 0) {
        ssize_t w = write(p->master, p->tbuf, p->tlen);
        if (w < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
                return LS_EAGAIN;
            }
            return LS_EIO;
        }
        memmove(p->tbuf, p->tbuf + w, p->tlen - (size_t)w);
        p->tlen -= (size_t)w;
    }
    return LS_OK;
}

static int pty_send(void *self, const hal_can_frame_t *frame)
{
    slcan_pty_t *p = self;
    if (!p->open) {
        p->st.tx_dropped++;
        return LS_OK; /* no supervisor attached: the frame is lost on an unlistened bus */
    }
    char line[LS_SLCAN_MAX_LINE];
    size_t n = ls_slcan_format(frame, line, sizeof line);
    if (n == 0) {
        return LS_EINVAL;
    }
    (void)flush_tx(p);
    if (p->tlen + n > sizeof p->tbuf) {
        return LS_EAGAIN; /* the host is not reading: the caller keeps the frame */
    }
    memcpy(p->tbuf + p->tlen, line, n);
    p->tlen += n;
    p->st.tx_frames++;
    int r = flush_tx(p);
    return r == LS_EIO ? LS_EIO : LS_OK;
}

static void handle_line(slcan_pty_t *p, const char *line, size_t len, hal_can_frame_t *frame, bool *got)
{
    ls_slcan_msg_t m;
    if (ls_slcan_parse(line, len, &m) != 0) {
        p->st.rx_dropped++;
        reply(p, '\a');
        return;
    }
    switch (m.kind) {
    case LS_SLCAN_FRAME:
        *frame = m.frame;
        *got = true;
        p->st.rx_frames++;
        return;
    case LS_SLCAN_OPEN:
        p->close_due = false;
        if (!(p->open && p->held)) {
            /* Drop whatever was written while nobody listened; while
             * sessions live on the link their frames in flight stay. */
            tcflush(p->master, TCOFLUSH);
            p->tlen = 0;
        }
        p->open = true;
        break;
    case LS_SLCAN_CLOSE:
        if (p->held && p->open) {
            /* One client's close (python-can's shutdown) must not mute
             * the others' sessions: acknowledged, carried out later. */
            p->close_due = true;
            p->st.close_held++;
        } else {
            p->open = false;
        }
        break;
    case LS_SLCAN_BITRATE: p->st.bitrate = m.bitrate; break;
    case LS_SLCAN_EMPTY: return; /* python-can sends a bare CR to clear the adapter's buffer */
    case LS_SLCAN_VERSION:
    case LS_SLCAN_SERIAL:
    case LS_SLCAN_FLAGS:
    case LS_SLCAN_TIMESTAMP: break;
    }
    reply(p, '\r');
}

static int pty_recv(void *self, hal_can_frame_t *frame)
{
    slcan_pty_t *p = self;
    (void)flush_tx(p);
    for (;;) {
        while (p->rpos < p->rlen) {
            char c = p->rbuf[p->rpos++];
            size_t len = 0;
            if (ls_slcan_lexer_feed(&p->lx, c, &len)) {
                bool got = false;
                handle_line(p, p->lx.buf, len, frame, &got);
                if (got) {
                    return 1;
                }
            }
        }
        ssize_t r = read(p->master, p->rbuf, sizeof p->rbuf);
        if (r <= 0) {
            if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR || errno == EIO)) {
                return LS_EAGAIN;
            }
            return r == 0 ? LS_EAGAIN : LS_EIO;
        }
        p->rlen = (size_t)r;
        p->rpos = 0;
    }
}

static int pty_hold_open(void *self, bool hold)
{
    slcan_pty_t *p = self;
    p->held = hold;
    if (!hold && p->close_due) {
        p->close_due = false;
        p->open = false;
    }
    return LS_OK;
}

/* Lines wait in tbuf only while the pty has no room: it polls writable
 * when it has, and recv or send writes them. */
static bool pty_tx_pending(void *self)
{
    const slcan_pty_t *p = self;
    return p->tlen > 0;
}

/* Bytes read from the pty but not parsed yet (the caller stopped taking
 * frames mid-buffer) are due at once: the fd may not poll readable again. */
static uint64_t pty_next_due_us(void *self)
{
    const slcan_pty_t *p = self;
    return p->rpos < p->rlen ? 0u : UINT64_MAX;
}

static int pty_poll_fd(void *self)
{
    return ((slcan_pty_t *)self)->master;
}

static int pty_status(void *self, hal_can_status_t *out)
{
    slcan_pty_t *p = self;
    *out = p->st;
    out->rx_dropped += p->lx.overlong;
    return LS_OK;
}

static void pty_close(void *self)
{
    slcan_pty_t *p = self;
    if (!p->used) {
        return;
    }
    if (p->path[0] != '\0') {
        unlink(p->path);
    }
    /* Unlinked while still held: a process that opened the old file finds it
     * replaced (take_lock) and retries on the new one. */
    unlink(p->lock_path);
    close(p->lock_fd);
    close(p->slave_keep);
    close(p->master);
    p->used = false;
}

static const hal_can_ops_t g_ops = {
    .send = pty_send,
    .recv = pty_recv,
    .poll_fd = pty_poll_fd,
    .status = pty_status,
    .close = pty_close,
    .hold_open = pty_hold_open,
    .tx_pending = pty_tx_pending,
    .next_due_us = pty_next_due_us,
};

/* flock `lock_path` for this process: the fd, or LS_EIO with msg set. */
static int take_lock(const char *lock_path, const char *path, char *msg, size_t msglen)
{
    for (int attempt = 0; attempt < 3; attempt++) {
        int fd = open(lock_path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0) {
            snprintf(msg, msglen, "cannot open the lock file %s: %s", lock_path, strerror(errno));
            return LS_EIO;
        }
        if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
            const int e = errno;
            char pid[24] = "";
            ssize_t n = pread(fd, pid, sizeof pid - 1, 0);
            close(fd);
            if (e != EWOULDBLOCK) {
                snprintf(msg, msglen, "cannot lock %s: %s", lock_path, strerror(e));
                return LS_EIO;
            }
            pid[n > 0 ? n : 0] = '\0';
            pid[strcspn(pid, "\r\n")] = '\0';
            snprintf(msg, msglen,
                     "%s is in use by landscaped PID %s (lock %s): stop that controller or choose another path", path,
                     pid[0] != '\0' ? pid : "(unknown)", lock_path);
            return LS_EIO;
        }
        /* The holder we waited for may have removed the file as it exited:
         * a lock on a file no longer at lock_path guards nothing. */
        struct stat a, b;
        if (fstat(fd, &a) == 0 && stat(lock_path, &b) == 0 && a.st_ino == b.st_ino && a.st_dev == b.st_dev) {
            char pid[24];
            int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
            if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != (ssize_t)len) {
                snprintf(msg, msglen, "cannot write the lock file %s: %s", lock_path, strerror(errno));
                close(fd);
                return LS_EIO;
            }
            return fd;
        }
        close(fd);
    }
    snprintf(msg, msglen, "the lock file %s keeps being replaced: is another landscaped starting on %s?", lock_path,
             path);
    return LS_EIO;
}

int hal_sim_slcan_pty_open(hal_can_link_t *out, const char *path, char *msg, size_t msglen)
{
    slcan_pty_t *p = NULL;
    for (size_t i = 0; i < HAL_SLCAN_PTY_MAX_LINKS; i++) {
        if (!g_links[i].used) {
            p = &g_links[i];
            break;
        }
    }
    if (p == NULL) {
        snprintf(msg, msglen, "at most %d slcan pty links", HAL_SLCAN_PTY_MAX_LINKS);
        return LS_EINVAL;
    }
    if (path == NULL || path[0] == '\0' || strlen(path) >= sizeof p->path) {
        snprintf(msg, msglen, "slcan:pty needs a path for the symlink, e.g. --link slcan:pty:/tmp/landscape0");
        return LS_EINVAL;
    }
    char lock_path[sizeof p->lock_path];
    snprintf(lock_path, sizeof lock_path, "%s.lock", path);
    struct stat sb;
    if (lstat(path, &sb) == 0 && !S_ISLNK(sb.st_mode)) {
        snprintf(msg, msglen, "%s exists and is not a symlink: choose another path for the pty link", path);
        return LS_EINVAL;
    }
    int lock_fd = take_lock(lock_path, path, msg, msglen);
    if (lock_fd < 0) {
        return lock_fd;
    }
    if (lstat(path, &sb) == 0) {
        unlink(path); /* a stale link from a controller that did not exit cleanly (its lock is free) */
    }
    int master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) {
        snprintf(msg, msglen, "cannot create a pseudo-terminal: %s", strerror(errno));
        if (master >= 0) {
            close(master);
        }
        unlink(lock_path);
        close(lock_fd);
        return LS_EIO;
    }
    const char *slave_name = ptsname(master);
    int slave = slave_name != NULL ? open(slave_name, O_RDWR | O_NOCTTY | O_NONBLOCK) : LS_ENODEV;
    if (slave < 0) {
        snprintf(msg, msglen, "cannot open the pty slave: %s", strerror(errno));
        close(master);
        unlink(lock_path);
        close(lock_fd);
        return LS_EIO;
    }
    struct termios tio;
    if (tcgetattr(slave, &tio) == 0) {
        cfmakeraw(&tio);
        tcsetattr(slave, TCSANOW, &tio);
    }
    if (symlink(slave_name, path) != 0) {
        snprintf(msg, msglen, "cannot create the symlink %s -> %s: %s", path, slave_name, strerror(errno));
        close(slave);
        close(master);
        unlink(lock_path);
        close(lock_fd);
        return LS_EIO;
    }
    memset(p, 0, sizeof *p);
    p->used = true;
    p->lock_fd = lock_fd;
    snprintf(p->lock_path, sizeof p->lock_path, "%s", lock_path);
    p->master = master;
    p->slave_keep = slave;
    snprintf(p->path, sizeof p->path, "%s", path);
    ls_slcan_lexer_init(&p->lx);
    out->ops = &g_ops;
    out->self = p;
    snprintf(out->name, sizeof out->name, "slcan:pty:%s", path);
    return LS_OK;
}
