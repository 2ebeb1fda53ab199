/* The set-point trace of the simulated arm (hal_sim_world.h "Set-point
 * trace"): a buffer filled by the control loop, written to a CSV file at
 * shutdown. Only open and write do I/O or allocate; record is the loop's. */
#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sim_world_internal.h"

static void set_msg(char *msg, size_t msglen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void set_msg(char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg != NULL && msglen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
}

/* The configuration alone: sizes, and a PATH that is not a directory. */
static int check_config(const hal_sim_trace_config_t *cfg, char *msg, size_t msglen)
{
    size_t len = strlen(cfg->path);
    if (len > HAL_SIM_TRACE_PATH_MAX) {
        set_msg(msg, msglen, "set-point trace: the path is longer than %d characters; use a shorter one",
                HAL_SIM_TRACE_PATH_MAX);
        return LS_EINVAL;
    }
    if (cfg->rate_hz == 0 || cfg->capacity == 0 || cfg->capacity > SIZE_MAX / sizeof(sim_trace_sample_t)) {
        set_msg(msg, msglen, "set-point trace %s: needs a rate_hz > 0 and a capacity of 1..%zu samples", cfg->path,
                SIZE_MAX / sizeof(sim_trace_sample_t));
        return LS_EINVAL;
    }
    struct stat st;
    if (cfg->path[len - 1] == '/' || (stat(cfg->path, &st) == 0 && S_ISDIR(st.st_mode))) {
        set_msg(msg, msglen, "set-point trace %s: is a directory; give the path of a file to write", cfg->path);
        return LS_EINVAL;
    }
    return LS_OK;
}

int sim_trace_open(sim_trace_t *tr, const hal_sim_trace_config_t *cfg, char *msg, size_t msglen)
{
    memset(tr, 0, sizeof *tr);
    if (cfg->path == NULL || cfg->path[0] == '\0') {
        return LS_OK;
    }
    int rc = check_config(cfg, msg, msglen);
    if (rc < 0) {
        return rc;
    }
    size_t bytes = cfg->capacity * sizeof(sim_trace_sample_t);
    tr->buf = malloc(bytes);
    if (tr->buf == NULL) {
        set_msg(msg, msglen, "set-point trace %s: cannot allocate %zu MiB for %zu samples; lower the rate", cfg->path,
                bytes >> 20, cfg->capacity);
        return LS_EIO;
    }
    /* Touch every page now: the loop's first write to a page takes no fault. */
    memset(tr->buf, 0, bytes);
    snprintf(tr->path, sizeof tr->path, "%s", cfg->path);
    snprintf(tr->tmp, sizeof tr->tmp, "%s.tmp", cfg->path);
    tr->tmp_file = fopen(tr->tmp, "w");
    if (tr->tmp_file == NULL) {
        set_msg(msg, msglen, "set-point trace: cannot create %s: %s; give a path in an existing, writable directory",
                tr->tmp, strerror(errno));
        free(tr->buf);
        memset(tr, 0, sizeof *tr);
        return LS_EIO;
    }
    tr->rate_hz = cfg->rate_hz;
    tr->capacity = cfg->capacity;
    return LS_OK;
}

void sim_trace_record(sim_trace_t *tr, double t_s, const double *q_rad)
{
    if (tr->buf == NULL) {
        return;
    }
    if (tr->n == tr->capacity) {
        tr->dropped++; /* keep the start of the run: a test reads it */
        return;
    }
    sim_trace_sample_t *s = &tr->buf[tr->n++];
    s->t_s = t_s;
    memcpy(s->q_rad, q_rad, sizeof s->q_rad);
}

/* The header lines and one row per sample; 0 or the errno of the first
 * failed write. */
static int write_rows(const sim_trace_t *tr, FILE *f)
{
    if (fprintf(f, "# landscaped setpoint trace: rate_hz=%u samples=%zu dropped=%llu\nt_s,q1,q2,q3,q4,q5,q6\n",
                (unsigned)tr->rate_hz, tr->n, (unsigned long long)tr->dropped) < 0) {
        return errno != 0 ? errno : EIO;
    }
    for (size_t i = 0; i < tr->n; i++) {
        const sim_trace_sample_t *s = &tr->buf[i];
        if (fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s->t_s, s->q_rad[0], s->q_rad[1], s->q_rad[2],
                    s->q_rad[3], s->q_rad[4], s->q_rad[5]) < 0) {
            return errno != 0 ? errno : EIO;
        }
    }
    return 0;
}

int sim_trace_write(sim_trace_t *tr, char *msg, size_t msglen)
{
    if (tr->tmp_file == NULL) {
        return 0; /* no trace, or written already */
    }
    FILE *f = tr->tmp_file;
    tr->tmp_file = NULL;
    errno = 0;
    int err = write_rows(tr, f);
    if (fclose(f) != 0 && err == 0) {
        err = errno != 0 ? errno : EIO; /* the buffered tail did not reach the file (ENOSPC...) */
    }
    if (err != 0) {
        (void)unlink(tr->tmp);
        set_msg(msg, msglen, "set-point trace: cannot write %s: %s; the trace is lost (check the disk space)", tr->tmp,
                strerror(err));
        return LS_EIO;
    }
    if (rename(tr->tmp, tr->path) != 0) {
        err = errno;
        (void)unlink(tr->tmp);
        set_msg(msg, msglen, "set-point trace: cannot rename %s to %s: %s; the trace is lost", tr->tmp, tr->path,
                strerror(err));
        return LS_EIO;
    }
    set_msg(msg, msglen, "%zu samples (%llu dropped) written to %s", tr->n, (unsigned long long)tr->dropped, tr->path);
    return 1;
}

void sim_trace_close(sim_trace_t *tr)
{
    if (tr->tmp_file != NULL) {
        (void)fclose(tr->tmp_file);
        (void)unlink(tr->tmp); /* never written: no empty file left behind */
    }
    free(tr->buf);
    memset(tr, 0, sizeof *tr);
}
