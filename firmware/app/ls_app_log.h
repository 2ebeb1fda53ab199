/* The programs' log lines (landscaped, ls-simdrives): one line on stderr
 * with the sd-daemon level prefix journald stores as its priority
 * (docs/architecture.md "Logging"), then the program's name and the level's:
 *     <3>landscaped: error: --link can0: unknown link kind; ...
 * Any thread (stdio locks the stream per call; a line is three calls, so
 * lines of two threads may interleave only at their edges). Header only. */
#ifndef LS_APP_LOG_H
#define LS_APP_LOG_H

#include <stdarg.h>
#include <stdio.h>

#define LS_APP_LOG_ERR 3
#define LS_APP_LOG_WARNING 4
#define LS_APP_LOG_INFO 6
#define LS_APP_LOG_DEBUG 7

static inline void ls_app_log(const char *prog, int level, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static inline void ls_app_log(const char *prog, int level, const char *fmt, ...)
{
    static const char *const names[] = { "", "", "", "error", "warning", "", "info", "debug" };
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "<%d>%s: %s: ", level, prog, names[level & 7]);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

#endif
