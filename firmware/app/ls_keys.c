/* The supervisors' key file. See ls_keys.h. */
#include "ls_keys.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <sodium/utils.h>

#include "ls_ini_line.h"

static int fail(char *msg, size_t msglen, int code, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static int fail(char *msg, size_t msglen, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return code;
}

const char *ls_keys_path(const ls_config_t *cfg, char *buf, size_t buflen)
{
    if (cfg->key_file[0] != '\0') {
        const int n = snprintf(buf, buflen, "%s", cfg->key_file);
        return n > 0 && (size_t)n < buflen ? buf : NULL;
    }
    const char *dir = getenv("CREDENTIALS_DIRECTORY");
    if (dir == NULL || dir[0] == '\0') {
        return NULL;
    }
    const int n = snprintf(buf, buflen, "%s/%s", dir, LS_KEYS_CREDENTIAL);
    struct stat st;
    return n > 0 && (size_t)n < buflen && stat(buf, &st) == 0 ? buf : NULL;
}

int ls_keys_check_mode(const char *path, char *msg, size_t msglen)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        return fail(msg, msglen, errno == ENOENT ? LS_ENODEV : LS_EPERM, "%s: %s: the supervisors' key file", path,
                    strerror(errno));
    }
    if (!S_ISREG(st.st_mode)) {
        return fail(msg, msglen, LS_EINVAL, "%s: not a regular file: name the supervisors' key file", path);
    }
    if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0u) {
        return fail(msg, msglen, LS_EPERM,
                    "%s: mode %04o lets %s use the supervisors' keys: chmod 600 %s (only its owner may read it)", path,
                    (unsigned)(st.st_mode & 07777u), (st.st_mode & S_IRWXO) != 0u ? "everyone" : "its group", path);
    }
    if (st.st_uid != 0 && st.st_uid != geteuid()) {
        return fail(msg, msglen, LS_EPERM,
                    "%s: owned by uid %u, not by root or landscaped's user (uid %u): chown it, so that no other "
                    "user can change the keys",
                    path, (unsigned)st.st_uid, (unsigned)geteuid());
    }
    return LS_OK;
}

/* 2 * LS_AUTH_KEY_BYTES hex digits into key: LS_OK or LS_EINVAL. libsodium's
 * decoder runs in constant time, so a key's digits leak nothing by timing. */
static int parse_key(const char *v, uint8_t *key)
{
    size_t got = 0;
    if (strlen(v) != 2u * LS_AUTH_KEY_BYTES ||
        sodium_hex2bin(key, LS_AUTH_KEY_BYTES, v, 2u * LS_AUTH_KEY_BYTES, NULL, &got, NULL) != 0 ||
        got != LS_AUTH_KEY_BYTES) {
        return LS_EINVAL;
    }
    return LS_OK;
}

/* One line of the key file (comments and blank lines already skipped). */
static int take_line(char *s, ls_auth_t *auth, const char *path, int line, char *msg, size_t msglen)
{
    char *eq = strchr(s, '=');
    if (eq == NULL) {
        return fail(msg, msglen, LS_EINVAL, "%s:%d: expected NAME = 64 hex digits (one key per line)", path, line);
    }
    *eq = '\0';
    const char *name = ls_ini_trim(s);
    const char *value = ls_ini_trim(eq + 1);
    uint8_t key[LS_AUTH_KEY_BYTES];
    if (parse_key(value, key) != LS_OK) {
        /* never the value itself: it may be most of a key */
        return fail(msg, msglen, LS_EINVAL,
                    "%s:%d: key \"%.*s\": expected %u hex digits (%u random bytes), got %zu characters", path, line,
                    (int)(LS_AUTH_KEY_ID_SIZE - 1u), name, (unsigned)(2u * LS_AUTH_KEY_BYTES),
                    (unsigned)LS_AUTH_KEY_BYTES, strlen(value));
    }
    const int r = ls_auth_add_key(auth, name, key);
    ls_auth_wipe(key, sizeof key);
    if (r == LS_EINVAL) {
        return fail(msg, msglen, LS_EINVAL,
                    "%s:%d: key name \"%.*s\": expected 1..%u printable characters without blanks, '=', '#' or ';'",
                    path, line, (int)(LS_AUTH_KEY_ID_SIZE - 1u), name, (unsigned)(LS_AUTH_KEY_ID_SIZE - 1u));
    }
    if (r == LS_ESTATE) {
        return fail(msg, msglen, LS_EINVAL, "%s:%d: key \"%s\" is given twice: keep one", path, line, name);
    }
    if (r == LS_ENOSPC) {
        return fail(msg, msglen, LS_EINVAL, "%s:%d: more than %d keys: the device holds %d", path, line,
                    LS_AUTH_MAX_KEYS, LS_AUTH_MAX_KEYS);
    }
    return LS_OK;
}

int ls_keys_load(const char *path, ls_auth_t *auth, char *msg, size_t msglen)
{
    int r = ls_keys_check_mode(path, msg, msglen);
    if (r != LS_OK) {
        return r;
    }
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return fail(msg, msglen, errno == EACCES ? LS_EPERM : LS_EIO, "%s: %s: the supervisors' key file", path,
                    strerror(errno));
    }
    /* stdio's buffer holds the file's bytes too: ours, wiped after */
    static char iobuf[BUFSIZ];
    (void)setvbuf(f, iobuf, _IOFBF, sizeof iobuf);
    char buf[256];
    char why[64] = "";
    int line = 0;
    r = LS_OK;
    while (r == LS_OK && ls_ini_next_line(buf, (int)sizeof buf, f, &line, why, sizeof why) != NULL) {
        char *s = ls_ini_trim(buf);
        if (s[0] != '\0' && s[0] != '#' && s[0] != ';') {
            r = take_line(s, auth, path, line, msg, msglen);
        }
        ls_auth_wipe(buf, sizeof buf);
    }
    if (r == LS_OK && why[0] != '\0') {
        r = fail(msg, msglen, LS_EINVAL, "%s:%d: %s", path, line, why);
    }
    ls_auth_wipe(buf, sizeof buf);
    fclose(f);
    ls_auth_wipe(iobuf, sizeof iobuf);
    if (r == LS_OK && auth->n_keys == 0) {
        r = fail(msg, msglen, LS_EINVAL, "%s: holds no key: add a line NAME = 64 hex digits", path);
    }
    return r;
}
