/* Robot model files (ls_robot_model_file.h): one key table for the reader,
 * the refusals and the host's copy (ls_robot_model keys). */
#include "ls_robot_model_file.h"

#include <ctype.h>
#include <errno.h>
#include <ini.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ls_err.h"
#include "ls_ini_line.h"
#include "ls_kin.h"
#include "ls_math.h"

#define DEG (LS_PI / 180.0)

/* ---- units and keys ----------------------------------------------------- */

static const ls_model_unit_t U_NONE[] = { { NULL, 0, 0 } };
static const ls_model_unit_t U_LENGTH[] = { { "m", 1, 1 }, { "mm", 1, 1000 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_ANGLE[] = { { "deg", DEG, 1 }, { "rad", 1, 1 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_ANG_VEL[] = { { "rad/s", 1, 1 }, { "deg/s", DEG, 1 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_ANG_ACC[] = { { "rad/s^2", 1, 1 }, { "deg/s^2", DEG, 1 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_ANG_JERK[] = { { "rad/s^3", 1, 1 }, { "deg/s^3", DEG, 1 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_LIN_VEL[] = { { "m/s", 1, 1 }, { "mm/s", 1, 1000 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_LIN_ACC[] = { { "m/s^2", 1, 1 }, { "mm/s^2", 1, 1000 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_LIN_JERK[] = { { "m/s^3", 1, 1 }, { "mm/s^3", 1, 1000 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_TORQUE[] = { { "Nm", 1, 1 }, { NULL, 0, 0 } };
static const ls_model_unit_t U_MASS[] = { { "kg", 1, 1 }, { NULL, 0, 0 } };

static const struct {
    const ls_model_unit_t *units;
    const char *text;
} QUANTITIES[LS_MQ_COUNT] = {
    [LS_MQ_NAME] = { U_NONE, "a name" },
    [LS_MQ_LENGTH] = { U_LENGTH, "a length" },
    [LS_MQ_ANGLE] = { U_ANGLE, "an angle" },
    [LS_MQ_ANG_VEL] = { U_ANG_VEL, "an angular velocity" },
    [LS_MQ_ANG_ACC] = { U_ANG_ACC, "an angular acceleration" },
    [LS_MQ_ANG_JERK] = { U_ANG_JERK, "an angular jerk" },
    [LS_MQ_LIN_VEL] = { U_LIN_VEL, "a speed" },
    [LS_MQ_LIN_ACC] = { U_LIN_ACC, "an acceleration" },
    [LS_MQ_LIN_JERK] = { U_LIN_JERK, "a jerk" },
    [LS_MQ_TORQUE] = { U_TORQUE, "a torque" },
    [LS_MQ_MASS] = { U_MASS, "a mass" },
    [LS_MQ_POINT] = { U_LENGTH, "a point" },
};

/* Where a key's value goes: offset into the model, and the stride from one
 * joint's value to the next (0 for the keys of [robot] and [cartesian]). */
typedef struct {
    ls_model_key_t k;
    size_t offset, stride;
} key_place_t;

#define DH(field) offsetof(ls_robot_model_t, dh) + offsetof(ls_dh_t, field), sizeof(ls_dh_t)
#define JOINT(field) offsetof(ls_robot_model_t, field), sizeof(double)
#define ONE(field) offsetof(ls_robot_model_t, field), 0

/* Ranges: wide enough for any arm of this kind, narrow enough to catch a
 * value in the wrong unit. Lengths and the workspace within 10 m; joint
 * limits within three turns (the IK wraps angles that far, ls_kin.cpp). */
static const key_place_t KEYS[] = {
    { { "robot", "name", LS_MQ_NAME, 0, 0, false, "1..31 printable ASCII characters",
        "the arm's name (describe, URDF)" },
      ONE(name) },
    { { "robot", "link_radius", LS_MQ_LENGTH, 0.001, 0.5, false, "0.001..0.5 m",
        "capsule radius of the simulated links and of the URDF's visuals" },
      ONE(link_radius_m) },
    { { "joint", "a", LS_MQ_LENGTH, -10, 10, false, "-10..10 m", "DH a: along x_i" }, DH(a_m) },
    { { "joint", "alpha", LS_MQ_ANGLE, -360 * DEG, 360 * DEG, false, "-360..360 deg", "DH alpha: about x_i" },
      DH(alpha_rad) },
    { { "joint", "d", LS_MQ_LENGTH, -10, 10, false, "-10..10 m", "DH d: along z_(i-1)" }, DH(d_m) },
    { { "joint", "theta_offset", LS_MQ_ANGLE, -360 * DEG, 360 * DEG, false, "-360..360 deg",
        "DH theta at joint angle 0" },
      DH(theta_offset_rad) },
    { { "joint", "min", LS_MQ_ANGLE, -540 * DEG, 540 * DEG, false, "-540..540 deg", "lower joint limit" },
      JOINT(q_min_rad) },
    { { "joint", "max", LS_MQ_ANGLE, -540 * DEG, 540 * DEG, false, "-540..540 deg", "upper joint limit" },
      JOINT(q_max_rad) },
    { { "joint", "max_velocity", LS_MQ_ANG_VEL, 0, 100, true, "above 0 up to 100 rad/s", "joint velocity limit" },
      JOINT(qd_max_rad_s) },
    { { "joint", "max_acceleration", LS_MQ_ANG_ACC, 0, 10000, true, "above 0 up to 10000 rad/s^2",
        "joint acceleration limit" },
      JOINT(qdd_max_rad_s2) },
    { { "joint", "max_jerk", LS_MQ_ANG_JERK, 0, 1e6, true, "above 0 up to 1e+06 rad/s^3", "joint jerk limit" },
      JOINT(qddd_max_rad_s3) },
    { { "joint", "max_torque", LS_MQ_TORQUE, 0, 1e5, true, "above 0 up to 1e+05 Nm", "drive torque limit" },
      JOINT(torque_max_Nm) },
    { { "joint", "mass", LS_MQ_MASS, 0, 1e4, true, "above 0 up to 1e+04 kg", "mass of the link the joint moves" },
      JOINT(link_mass_kg) },
    { { "cartesian", "max_linear_speed", LS_MQ_LIN_VEL, 0, 10, true, "above 0 up to 10 m/s", "tool tip speed" },
      ONE(max_linear_speed_m_s) },
    { { "cartesian", "max_angular_speed", LS_MQ_ANG_VEL, 0, 100, true, "above 0 up to 100 rad/s",
        "tool angular speed" },
      ONE(max_angular_speed_rad_s) },
    { { "cartesian", "max_linear_acceleration", LS_MQ_LIN_ACC, 0, 1000, true, "above 0 up to 1000 m/s^2",
        "tool tip acceleration" },
      ONE(max_linear_accel_m_s2) },
    { { "cartesian", "max_angular_acceleration", LS_MQ_ANG_ACC, 0, 10000, true, "above 0 up to 10000 rad/s^2",
        "tool angular acceleration" },
      ONE(max_angular_accel_rad_s2) },
    { { "cartesian", "max_linear_jerk", LS_MQ_LIN_JERK, 0, 1e5, true, "above 0 up to 1e+05 m/s^3", "tool tip jerk" },
      ONE(max_linear_jerk_m_s3) },
    { { "cartesian", "max_angular_jerk", LS_MQ_ANG_JERK, 0, 1e6, true, "above 0 up to 1e+06 rad/s^3",
        "tool angular jerk" },
      ONE(max_angular_jerk_rad_s3) },
    { { "cartesian", "workspace_min", LS_MQ_POINT, -10, 10, false, "each -10..10 m",
        "lowest x y z of the tool tip's box, base frame" },
      ONE(workspace_min_m) },
    { { "cartesian", "workspace_max", LS_MQ_POINT, -10, 10, false, "each -10..10 m",
        "highest x y z of the tool tip's box, base frame" },
      ONE(workspace_max_m) },
};
#define N_KEYS (sizeof KEYS / sizeof KEYS[0])

enum { KEY_NAME = 0, KEY_MIN = 6, KEY_MAX = 7, KEY_WS_MIN = 19, KEY_WS_MAX = 20 };
_Static_assert(N_KEYS == 21, "KEY_* indexes follow the table");

/* Sections in file order: [robot], [joint.1] .. [joint.6], [cartesian]
 * (landscaped.conf names its drive joints so too). */
#define N_SECTIONS (2 + LS_N_JOINTS)
static const char SECTIONS_TEXT[] = "[robot], [joint.1] .. [joint.6] or [cartesian]";

size_t ls_robot_model_key_count(void)
{
    return N_KEYS;
}

const ls_model_key_t *ls_robot_model_key(size_t i)
{
    return i < N_KEYS ? &KEYS[i].k : NULL;
}

const ls_model_unit_t *ls_robot_model_units(ls_model_quantity_t q)
{
    return (unsigned)q < LS_MQ_COUNT ? QUANTITIES[q].units : U_NONE;
}

const char *ls_robot_model_quantity_text(ls_model_quantity_t q)
{
    return (unsigned)q < LS_MQ_COUNT ? QUANTITIES[q].text : "";
}

void ls_robot_model_expected_text(const ls_model_key_t *k, char *out, size_t outlen)
{
    if (k->quantity == LS_MQ_NAME) {
        snprintf(out, outlen, "%s", k->expected);
        return;
    }
    char units[64] = "";
    size_t used = 0;
    const ls_model_unit_t *u = ls_robot_model_units(k->quantity);
    for (size_t i = 0; u[i].name != NULL && used < sizeof units; i++) {
        int w = snprintf(units + used, sizeof units - used, "%s%s", i > 0 ? " or " : "", u[i].name);
        used += w > 0 ? (size_t)w : 0u;
    }
    snprintf(out, outlen, "%s: %s and %s unit (%s), %s", ls_robot_model_quantity_text(k->quantity),
             k->quantity == LS_MQ_POINT ? "three numbers (x y z)" : "a number",
             k->quantity == LS_MQ_POINT ? "one" : "its", units, k->expected);
}

/* ---- values -------------------------------------------------------------- */

/* Decimal text only: [+-] digits [. digits] [e [+-] digits] (no hex, inf or
 * nan); the whole token. */
static bool parse_number(const char *tok, double *out)
{
    const char *p = tok;
    if (*p == '+' || *p == '-') {
        p++;
    }
    size_t digits = 0;
    while (isdigit((unsigned char)*p)) {
        p++;
        digits++;
    }
    if (*p == '.') {
        p++;
        while (isdigit((unsigned char)*p)) {
            p++;
            digits++;
        }
    }
    if (digits == 0) {
        return false;
    }
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-') {
            p++;
        }
        if (!isdigit((unsigned char)*p)) {
            return false;
        }
        while (isdigit((unsigned char)*p)) {
            p++;
        }
    }
    if (*p != '\0') {
        return false;
    }
    double v = strtod(tok, NULL);
    if (!isfinite(v)) {
        return false;
    }
    *out = v;
    return true;
}

/* "v1 [v2 v3] unit" -> SI values, each within the key's range. */
static bool parse_quantity(const ls_model_key_t *k, const char *text, double out[3])
{
    char buf[128];
    if (strlen(text) >= sizeof buf) {
        return false;
    }
    strcpy(buf, text);
    char *tok[5];
    size_t n = 0;
    for (char *save = NULL, *t = strtok_r(buf, " \t", &save); t != NULL; t = strtok_r(NULL, " \t", &save)) {
        if (n == 5) {
            return false;
        }
        tok[n++] = t;
    }
    const size_t n_numbers = k->quantity == LS_MQ_POINT ? 3 : 1;
    if (n != n_numbers + 1) {
        return false;
    }
    const ls_model_unit_t *u = ls_robot_model_units(k->quantity);
    while (u->name != NULL && strcmp(u->name, tok[n_numbers]) != 0) {
        u++;
    }
    if (u->name == NULL) {
        return false;
    }
    for (size_t i = 0; i < n_numbers; i++) {
        double v;
        if (!parse_number(tok[i], &v)) {
            return false;
        }
        v = v * u->multiply / u->divide;
        if (!(k->min_open ? v > k->min_si : v >= k->min_si) || !(v <= k->max_si)) {
            return false;
        }
        out[i] = v;
    }
    return true;
}

static bool valid_name(const char *v)
{
    size_t n = strlen(v);
    if (n == 0 || n >= LS_ROBOT_MODEL_NAME_MAX) {
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        if (v[i] < 0x20 || v[i] > 0x7E) {
            return false;
        }
    }
    return true;
}

/* ---- the file ------------------------------------------------------------ */

typedef struct {
    const char *path;
    FILE *f;
    ls_robot_model_t m;
    int line;       /* the line inih is parsing */
    int error_line; /* 0: no error yet */
    char *msg;
    size_t msglen;
    int seen[N_SECTIONS][N_KEYS];                              /* the line of each key, 0: not given */
    char min_text[LS_N_JOINTS][64], max_text[LS_N_JOINTS][64]; /* as written, for the refusals */
    char ws_min_text[64], ws_max_text[64];
} load_t;

#define ERROR_WITHOUT_LINE (-1) /* load_t.error_line: an error that no line of the file holds */

static void fail(load_t *c, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void fail(load_t *c, int line, const char *fmt, ...)
{
    if (c->error_line != 0) {
        return;
    }
    c->error_line = line > 0 ? line : ERROR_WITHOUT_LINE;
    int w =
        line > 0 ? snprintf(c->msg, c->msglen, "%s:%d: ", c->path, line) : snprintf(c->msg, c->msglen, "%s: ", c->path);
    if (w >= 0 && (size_t)w < c->msglen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->msg + w, c->msglen - (size_t)w, fmt, ap);
        va_end(ap);
    }
}

#define NO_SECTION (-1) /* section_index: not a section of a robot model file */

/* 0 = [robot], 1..6 = [joint.N], 7 = [cartesian]; NO_SECTION for anything else. */
static int section_index(const char *s)
{
    if (strcmp(s, "robot") == 0) {
        return 0;
    }
    if (strcmp(s, "cartesian") == 0) {
        return N_SECTIONS - 1;
    }
    if (strncmp(s, "joint.", 6) == 0 && s[6] >= '1' && s[6] < '1' + LS_N_JOINTS && s[7] == '\0') {
        return s[6] - '0';
    }
    return NO_SECTION;
}

static const char *section_kind(int s)
{
    return s == 0 ? "robot" : (s == N_SECTIONS - 1 ? "cartesian" : "joint");
}

static void section_name(int s, char *out, size_t outlen)
{
    if (s > 0 && s < N_SECTIONS - 1) {
        snprintf(out, outlen, "joint.%d", s);
    } else {
        snprintf(out, outlen, "%s", section_kind(s));
    }
}

/* inih's line source (ls_ini_next_line: counted lines, over-long lines and
 * NUL bytes refused, leading blanks dropped), which also stops at the first
 * error. */
static char *reader(char *str, int num, void *stream)
{
    load_t *c = stream;
    char why[64];
    if (c->error_line != 0 || ls_ini_next_line(str, num, c->f, &c->line, why, sizeof why) == NULL) {
        if (c->error_line == 0 && why[0] != '\0') {
            fail(c, c->line, "%s", why);
        }
        return NULL;
    }
    /* A section header is checked on its own line (inih names it only with
     * its first key, and not at all when it has none). */
    const char *end = str[0] == '[' ? strchr(str, ']') : NULL;
    if (end != NULL) {
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)(end - str - 1), str + 1);
        if (section_index(name) < 0) {
            fail(c, c->line, "unknown section [%s]; expected %s", name, SECTIONS_TEXT);
            return NULL;
        }
    }
    return str;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    load_t *c = user;
    if (c->error_line != 0) {
        return 0;
    }
    if (section[0] == '\0') {
        fail(c, c->line, "key '%s' outside any section: put it under %s", name, SECTIONS_TEXT);
        return 0;
    }
    const int s = section_index(section);
    if (s < 0) { /* the reader has refused its header already */
        fail(c, c->line, "unknown section [%s]; expected %s", section, SECTIONS_TEXT);
        return 0;
    }
    size_t k = 0;
    while (k < N_KEYS && !(strcmp(KEYS[k].k.section, section_kind(s)) == 0 && strcmp(KEYS[k].k.key, name) == 0)) {
        k++;
    }
    if (k == N_KEYS) {
        char keys[400] = "";
        size_t used = 0;
        for (size_t i = 0; i < N_KEYS && used < sizeof keys; i++) {
            if (strcmp(KEYS[i].k.section, section_kind(s)) == 0) {
                int w = snprintf(keys + used, sizeof keys - used, "%s%s", used > 0 ? ", " : "", KEYS[i].k.key);
                used += w > 0 ? (size_t)w : 0u;
            }
        }
        fail(c, c->line, "[%s] %s: unknown key; expected one of %s", section, name, keys);
        return 0;
    }
    if (c->seen[s][k] != 0) {
        fail(c, c->line, "[%s] %s: given twice (first on line %d); keep one", section, name, c->seen[s][k]);
        return 0;
    }
    c->seen[s][k] = c->line;
    const ls_model_key_t *key = &KEYS[k].k;
    char expected[256];
    if (key->quantity == LS_MQ_NAME) {
        if (!valid_name(value)) {
            ls_robot_model_expected_text(key, expected, sizeof expected);
            fail(c, c->line, "[%s] %s: got '%s', expected %s", section, name, value, expected);
            return 0;
        }
        snprintf(c->m.name, sizeof c->m.name, "%s", value);
        return 1;
    }
    double v[3];
    if (!parse_quantity(key, value, v)) {
        ls_robot_model_expected_text(key, expected, sizeof expected);
        fail(c, c->line, "[%s] %s: got '%s', expected %s", section, name, value, expected);
        return 0;
    }
    unsigned char *base = (unsigned char *)&c->m + KEYS[k].offset;
    if (key->quantity == LS_MQ_POINT) {
        memcpy(base, v, 3 * sizeof(double));
    } else {
        const size_t joint = s > 0 && s < N_SECTIONS - 1 ? (size_t)(s - 1) : 0u;
        memcpy(base + joint * KEYS[k].stride, &v[0], sizeof(double));
    }
    if (k == KEY_MIN || k == KEY_MAX) {
        snprintf(k == KEY_MIN ? c->min_text[s - 1] : c->max_text[s - 1], sizeof c->min_text[0], "%s", value);
    } else if (k == KEY_WS_MIN || k == KEY_WS_MAX) {
        snprintf(k == KEY_WS_MIN ? c->ws_min_text : c->ws_max_text, sizeof c->ws_min_text, "%s", value);
    }
    return 1;
}

/* What the keys one at a time cannot check: all given, limits ordered, a
 * geometry the IK solves. */
static void check_whole(load_t *c)
{
    for (int s = 0; s < N_SECTIONS && c->error_line == 0; s++) {
        for (size_t k = 0; k < N_KEYS; k++) {
            if (strcmp(KEYS[k].k.section, section_kind(s)) == 0 && c->seen[s][k] == 0) {
                char sec[16];
                section_name(s, sec, sizeof sec);
                fail(c, 0, "[%s] %s: missing; every key is required (docs/deploy.md \"Describe your arm\")", sec,
                     KEYS[k].k.key);
                return;
            }
        }
    }
    for (int j = 0; j < LS_N_JOINTS && c->error_line == 0; j++) {
        if (!(c->m.q_max_rad[j] > c->m.q_min_rad[j])) {
            fail(c, c->seen[j + 1][KEY_MAX], "[joint.%d] max: got '%s', expected above min = %s (line %d)", j + 1,
                 c->max_text[j], c->min_text[j], c->seen[j + 1][KEY_MIN]);
        }
    }
    for (int i = 0; i < 3 && c->error_line == 0; i++) {
        if (!(c->m.workspace_max_m[i] > c->m.workspace_min_m[i])) {
            fail(c, c->seen[N_SECTIONS - 1][KEY_WS_MAX],
                 "[cartesian] workspace_max: got '%s', expected above workspace_min = %s (line %d) on every axis; "
                 "%c is not",
                 c->ws_max_text, c->ws_min_text, c->seen[N_SECTIONS - 1][KEY_WS_MIN], "xyz"[i]);
        }
    }
    if (c->error_line != 0) {
        return;
    }
    char why[400];
    if (ls_kin_classify(&c->m, &c->m.ik_class, why, sizeof why) != LS_OK) {
        fail(c, 0, "no closed-form inverse kinematics fits this arm: %s (docs/architecture.md \"Inverse kinematics\")",
             why);
    }
}

int ls_robot_model_load(const char *path, ls_robot_model_t *model, char *msg, size_t msglen)
{
    static char dummy[1];
    if (msg == NULL || msglen == 0) {
        msg = dummy;
        msglen = sizeof dummy;
    }
    msg[0] = '\0';
    if (path == NULL || model == NULL) {
        snprintf(msg, msglen, "no robot model file given");
        return LS_EINVAL;
    }
    load_t ctx;
    load_t *c = &ctx;
    memset(c, 0, sizeof *c);
    c->path = path;
    c->msg = msg;
    c->msglen = msglen;
    c->f = fopen(path, "r");
    struct stat st;
    if (c->f != NULL && fstat(fileno(c->f), &st) == 0 && S_ISDIR(st.st_mode)) {
        fclose(c->f); /* fopen takes a directory; reading it would fail with less to say */
        c->f = NULL;
        errno = EISDIR;
    }
    if (c->f == NULL) {
        snprintf(msg, msglen,
                 "%s: cannot read the robot model file: %s (name an existing file in [robot] model or --model)", path,
                 strerror(errno));
        return LS_EINVAL;
    }
    int r = ini_parse_stream(reader, c, handler, c);
    const bool read_error = ferror(c->f) != 0;
    fclose(c->f);
    if (r > 0 && (c->error_line == 0 || r < c->error_line)) {
        c->error_line = 0; /* inih reports the earlier syntax error: keep whichever came first */
        fail(c, r, "syntax error: expected '[section]', 'key = value' or a ; or # comment");
    }
    if (c->error_line == 0 && read_error) {
        fail(c, 0, "read error after line %d", c->line);
    }
    if (c->error_line == 0 && r < 0) {
        fail(c, 0, "the INI parser failed (%d)", r);
    }
    if (c->error_line == 0) {
        check_whole(c);
    }
    const int rc = c->error_line == 0 ? LS_OK : LS_EINVAL;
    if (rc == LS_OK) {
        *model = c->m;
    }
    return rc;
}
