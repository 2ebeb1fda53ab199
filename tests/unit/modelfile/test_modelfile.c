/* Robot model files (firmware/model/ls_robot_model_file.h): the shipped
 * files load with their IK class, ls-sim6.ini is the compiled-in default to
 * the bit, and each kind of bad file is refused with one line naming the
 * file, the line, the key, what was given and what is allowed. The bad
 * files are ls-sim6.ini with one line changed, written to a temporary file. */
#define _GNU_SOURCE
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "ls_err.h"
#include "ls_kin.h"
#include "ls_math.h"
#include "ls_robot_model_file.h"
#include "ls_robot_urdf.h"

static const char *robot_path(const char *name)
{
    static char path[512];
    snprintf(path, sizeof path, "%s/%s", LS_ROBOTS_DIR, name);
    return path;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    static char text[16384];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    fclose(f);
    return text;
}

/* ls-sim6.ini with the first line starting with `from` replaced by `to`
 * ("" deletes it; from NULL appends `to`), in a temporary file whose path
 * is returned. */
static const char *variant(const char *from, const char *to)
{
    static char path[64];
    static char out[20000];
    const char *text = slurp(robot_path("ls-sim6.ini"));
    if (from == NULL) {
        snprintf(out, sizeof out, "%s%s\n", text, to);
    } else {
        const char *at = strstr(text, from);
        assert_non_null(at);
        assert_true(at == text || at[-1] == '\n');
        const char *eol = strchr(at, '\n');
        assert_non_null(eol);
        snprintf(out, sizeof out, "%.*s%s%s%s", (int)(at - text), text, to, to[0] != '\0' ? "\n" : "", eol + 1);
    }
    snprintf(path, sizeof path, "/tmp/ls-model-XXXXXX");
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, out, strlen(out)), (ssize_t)strlen(out));
    close(fd);
    return path;
}

/* The one line a variant is refused with, after "PATH:". */
static const char *refusal(const char *from, const char *to)
{
    static char msg[512];
    ls_robot_model_t m;
    memset(&m, 0xA5, sizeof m);
    ls_robot_model_t before = m;
    const char *path = variant(from, to);
    assert_int_equal(ls_robot_model_load(path, &m, msg, sizeof msg), LS_EINVAL);
    assert_memory_equal(&m, &before, sizeof m); /* untouched on error */
    unlink(path);
    assert_non_null(strchr(msg, ':'));
    assert_null(strchr(msg, '\n'));
    const size_t n = strlen(path);
    assert_int_equal(strncmp(msg, path, n), 0);
    return msg + n + 1;
}

static void the_shipped_ls_sim6_file_is_the_compiled_in_default(void **state)
{
    (void)state;
    ls_robot_model_t m;
    char msg[512] = "";
    assert_int_equal(ls_robot_model_load(robot_path("ls-sim6.ini"), &m, msg, sizeof msg), LS_OK);
    const ls_robot_model_t *d = &ls_robot_model_default;
    assert_string_equal(m.name, d->name);
    assert_int_equal(m.ik_class, d->ik_class);
    /* Every double to the bit: the file is the default, not an approximation. */
    const size_t first = offsetof(ls_robot_model_t, dh);
    assert_memory_equal((const char *)&m + first, (const char *)d + first, sizeof m - first);
}

static void every_shipped_arm_loads_with_its_ik_class(void **state)
{
    (void)state;
    static const struct {
        const char *file, *name;
        ls_ik_class_t cls;
    } arms[] = {
        { "ls-sim6.ini", "ls-sim6", LS_IK_CLASS_SPHERICAL_WRIST },
        { "kr6-r900.ini", "kr6-r900", LS_IK_CLASS_SPHERICAL_WRIST },
        { "puma560.ini", "puma560", LS_IK_CLASS_SPHERICAL_WRIST },
        { "ur5e.ini", "ur5e", LS_IK_CLASS_OFFSET_WRIST },
        { "ur10e.ini", "ur10e", LS_IK_CLASS_OFFSET_WRIST },
    };
    for (size_t i = 0; i < sizeof arms / sizeof arms[0]; i++) {
        ls_robot_model_t m;
        char msg[512] = "";
        if (ls_robot_model_load(robot_path(arms[i].file), &m, msg, sizeof msg) != LS_OK) {
            fail_msg("%s: %s", arms[i].file, msg);
        }
        assert_string_equal(m.name, arms[i].name);
        assert_int_equal(m.ik_class, arms[i].cls);
    }
}

static void units_convert_to_si_exactly(void **state)
{
    (void)state;
    ls_robot_model_t m;
    char msg[512] = "";
    const char *path = variant("d = 0.400 m", "d = 400 mm");
    assert_int_equal(ls_robot_model_load(path, &m, msg, sizeof msg), LS_OK);
    unlink(path);
    assert_true(m.dh[0].d_m == 0.4);
    path = variant("max_velocity = 2.5 rad/s", "max_velocity = 180 deg/s");
    assert_int_equal(ls_robot_model_load(path, &m, msg, sizeof msg), LS_OK);
    unlink(path);
    assert_true(m.qd_max_rad_s[0] == 180 * (LS_PI / 180.0));
    path = variant("workspace_min = -0.95 -0.95 0.02 m", "workspace_min = -950 -950 20 mm");
    assert_int_equal(ls_robot_model_load(path, &m, msg, sizeof msg), LS_OK);
    unlink(path);
    assert_true(m.workspace_min_m[0] == -0.95 && m.workspace_min_m[2] == 0.02);
}

static void a_missing_key_is_named(void **state)
{
    (void)state;
    assert_string_equal(refusal("max_jerk = 80 rad/s^3", ""),
                        " [joint.3] max_jerk: missing; every key is required (docs/deploy.md \"Describe your arm\")");
    assert_string_equal(refusal("name = ls-sim6", ""),
                        " [robot] name: missing; every key is required (docs/deploy.md \"Describe your arm\")");
}

static void an_inverted_joint_limit_names_both_lines(void **state)
{
    (void)state;
    /* [joint.2] min is on line 32 of ls-sim6.ini, max on line 33. */
    assert_string_equal(refusal("max = 110 deg", "max = -120 deg"),
                        "36: [joint.2] max: got '-120 deg', expected above min = -110 deg (line 35)");
    const char *ws = refusal("workspace_max = 0.95 0.95 1.40 m", "workspace_max = 0.95 0.95 0.01 m");
    assert_non_null(strstr(ws, "[cartesian] workspace_max: got '0.95 0.95 0.01 m', expected above workspace_min = "
                               "-0.95 -0.95 0.02 m"));
    assert_non_null(strstr(ws, "z is not"));
}

static void a_value_that_is_not_a_finite_number_with_its_unit_is_refused(void **state)
{
    (void)state;
    static const char *bad[] = { "nan deg", "inf deg",      "1e999 deg", "0x10 deg", "90",       "90 m",
                                 "90deg",   "90 deg extra", "",          "- 90 deg", "9.0.1 deg" };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char line[64];
        snprintf(line, sizeof line, "alpha = %s", bad[i]);
        const char *msg = refusal("alpha = -90 deg", line);
        char want[256];
        snprintf(want, sizeof want,
                 "19: [joint.1] alpha: got '%s', expected an angle: a number and its unit (deg or rad), -360..360 deg",
                 bad[i]);
        assert_string_equal(msg, want);
    }
    assert_string_equal(
        refusal("mass = 5 kg", "mass = 0 kg"),
        "28: [joint.1] mass: got '0 kg', expected a mass: a number and its unit (kg), above 0 up to 1e+04 kg");
    assert_string_equal(refusal("workspace_min = -0.95 -0.95 0.02 m", "workspace_min = -0.95 0.02 m"),
                        "103: [cartesian] workspace_min: got '-0.95 0.02 m', expected a point: three numbers (x y z) "
                        "and one unit (m or mm), each -10..10 m");
}

static void a_geometry_no_ik_class_fits_is_refused_with_the_reason(void **state)
{
    (void)state;
    /* An offset between joints 4 and 5 and a twisted forearm: neither class. */
    const char *msg = refusal("a = 0 m", "a = 0.02 m");
    assert_string_equal(msg, " no closed-form inverse kinematics fits this arm: not a spherical wrist (a4 = 0.02 m; "
                             "a4, a5, a6 and d5 must be 0 so that joints 4-6 meet) and not an offset wrist (a4 = "
                             "0.02 m; a4, a5 and a6 must be 0) (docs/architecture.md \"Inverse kinematics\")");
}

static void syntax_sections_and_keys_are_checked(void **state)
{
    (void)state;
    assert_string_equal(refusal("[joint.3]", "[joint.7]"),
                        "43: unknown section [joint.7]; expected [robot], [joint.1] .. [joint.6] or [cartesian]");
    assert_string_equal(refusal("mass = 3 kg", "weight = 3 kg"),
                        "54: [joint.3] weight: unknown key; expected one of a, alpha, d, theta_offset, min, max, "
                        "max_velocity, max_acceleration, max_jerk, max_torque, mass");
    assert_string_equal(refusal("mass = 3 kg", "mass = 3 kg\nmass = 4 kg"),
                        "55: [joint.3] mass: given twice (first on line 54); keep one");
    assert_string_equal(refusal("[robot]", "link_radius = 0.04 m\n[robot]"),
                        "9: key 'link_radius' outside any section: put it under [robot], [joint.1] .. [joint.6] or "
                        "[cartesian]");
    assert_string_equal(refusal("mass = 3 kg", "mass 3 kg"),
                        "54: syntax error: expected '[section]', 'key = value' or a ; or # comment");
    assert_string_equal(refusal("name = ls-sim6", "name = an arm whose name is far too long to be kept"),
                        "10: [robot] name: got 'an arm whose name is far too long to be kept', expected 1..31 "
                        "printable ASCII characters");
}

static void an_unreadable_file_is_named(void **state)
{
    (void)state;
    char msg[512];
    ls_robot_model_t m;
    assert_int_equal(ls_robot_model_load("/nonexistent/arm.ini", &m, msg, sizeof msg), LS_EINVAL);
    assert_string_equal(msg, "/nonexistent/arm.ini: cannot read the robot model file: No such file or directory "
                             "(name an existing file in [robot] model or --model)");
    assert_int_equal(ls_robot_model_load(NULL, &m, msg, sizeof msg), LS_EINVAL);
    assert_int_equal(ls_robot_model_load(robot_path("ls-sim6.ini"), NULL, NULL, 0), LS_EINVAL);
}

static void the_key_table_names_every_key_once_per_section_kind(void **state)
{
    (void)state;
    size_t n = ls_robot_model_key_count();
    assert_int_equal(n, 21);
    for (size_t i = 0; i < n; i++) {
        const ls_model_key_t *a = ls_robot_model_key(i);
        assert_non_null(a->expected);
        for (size_t j = i + 1; j < n; j++) {
            const ls_model_key_t *b = ls_robot_model_key(j);
            assert_false(strcmp(a->section, b->section) == 0 && strcmp(a->key, b->key) == 0);
        }
    }
    assert_null(ls_robot_model_key(n));
    assert_null(ls_robot_model_units(LS_MQ_NAME)[0].name);
}

/* The URDF in windows of any size joins into the same text. */
static void the_urdf_joins_from_windows_of_any_size(void **state)
{
    (void)state;
    static char whole[16384], joined[16384], piece[1024];
    size_t total = 0, t2 = 0;
    int n = ls_robot_urdf_window(&ls_robot_model_default, 0, whole, sizeof whole, &total);
    assert_true(n > 1000 && (size_t)n == total && total < sizeof whole);
    assert_null(memchr(whole, '\0', total));
    for (size_t cap = 2; cap <= sizeof piece; cap = cap * 3 + 1) {
        size_t off = 0;
        while (off < total) {
            n = ls_robot_urdf_window(&ls_robot_model_default, off, piece, cap, &t2);
            assert_true(n > 0 && (size_t)n < cap && t2 == total);
            memcpy(joined + off, piece, (size_t)n);
            off += (size_t)n;
        }
        assert_int_equal(ls_robot_urdf_window(&ls_robot_model_default, total, piece, cap, &t2), 0);
        assert_string_equal(piece, "");
        assert_memory_equal(joined, whole, total);
    }
    assert_int_equal(ls_robot_urdf_window(NULL, 0, piece, sizeof piece, &t2), LS_EINVAL);
    assert_int_equal(ls_robot_urdf_window(&ls_robot_model_default, 0, piece, 0, &t2), LS_EINVAL);
    assert_non_null(strstr(whole, "<robot name=\"ls-sim6\">"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(the_shipped_ls_sim6_file_is_the_compiled_in_default),
        cmocka_unit_test(every_shipped_arm_loads_with_its_ik_class),
        cmocka_unit_test(units_convert_to_si_exactly),
        cmocka_unit_test(a_missing_key_is_named),
        cmocka_unit_test(an_inverted_joint_limit_names_both_lines),
        cmocka_unit_test(a_value_that_is_not_a_finite_number_with_its_unit_is_refused),
        cmocka_unit_test(a_geometry_no_ik_class_fits_is_refused_with_the_reason),
        cmocka_unit_test(syntax_sections_and_keys_are_checked),
        cmocka_unit_test(an_unreadable_file_is_named),
        cmocka_unit_test(the_key_table_names_every_key_once_per_section_kind),
        cmocka_unit_test(the_urdf_joins_from_windows_of_any_size),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
