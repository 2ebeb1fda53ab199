/* ls_robot_model: robot model files on the command line, with landscaped's own
 * loader and kinematics.
 *
 *   ls_robot_model check FILE   load FILE as landscaped does: its name, IK class
 *                         and reach (exit 0), or the refusal (exit 2)
 *   ls_robot_model keys         the key table as JSON (the host package's copy,
 *                         host_tools/update_generated.sh)
 *   ls_robot_model fk FILE      for each line of six joint angles (rad) on stdin,
 *                         the flange pose: 16 numbers, column-major, %.17g
 *                         (the tests' handle on the firmware's FK)
 *
 * Exit 2 for bad arguments, a refused model or a bad input line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_kin.h"
#include "ls_robot_model_file.h"

static int usage(void)
{
    fprintf(stderr, "usage: ls_robot_model check FILE | ls_robot_model keys | ls_robot_model fk FILE < joints\n");
    return 2;
}

/* JSON string of ASCII text (the table holds no quote or backslash). */
static void json_str(const char *s)
{
    putchar('"');
    for (; *s != '\0'; s++) {
        if (*s == '"' || *s == '\\') {
            putchar('\\');
        }
        putchar(*s);
    }
    putchar('"');
}

static int keys(void)
{
    printf("{\n  \"generated_by\": \"ls_robot_model keys (firmware/model/ls_robot_model_file.c)\",\n");
    printf("  \"joints\": %d,\n  \"name_max\": %d,\n  \"quantities\": {", LS_N_JOINTS, LS_ROBOT_MODEL_NAME_MAX - 1);
    for (int q = 0; q < LS_MQ_COUNT; q++) {
        printf("%s\n    ", q > 0 ? "," : "");
        json_str(ls_robot_model_quantity_text((ls_model_quantity_t)q));
        printf(": [");
        const ls_model_unit_t *u = ls_robot_model_units((ls_model_quantity_t)q);
        for (size_t i = 0; u[i].name != NULL; i++) {
            printf("%s{\"name\": ", i > 0 ? ", " : "");
            json_str(u[i].name);
            printf(", \"multiply\": %.17g, \"divide\": %.17g}", u[i].multiply, u[i].divide);
        }
        printf("]");
    }
    printf("\n  },\n  \"keys\": [");
    for (size_t i = 0; i < ls_robot_model_key_count(); i++) {
        const ls_model_key_t *k = ls_robot_model_key(i);
        printf("%s\n    {\"section\": ", i > 0 ? "," : "");
        json_str(k->section);
        printf(", \"key\": ");
        json_str(k->key);
        printf(", \"quantity\": ");
        json_str(ls_robot_model_quantity_text(k->quantity));
        char expected[256];
        ls_robot_model_expected_text(k, expected, sizeof expected);
        printf(", \"min\": %.17g, \"max\": %.17g, \"min_open\": %s, \"range\": ", k->min_si, k->max_si,
               k->min_open ? "true" : "false");
        json_str(k->expected);
        printf(", \"expected\": ");
        json_str(expected);
        printf(", \"what\": ");
        json_str(k->what);
        printf("}");
    }
    printf("\n  ]\n}\n");
    return fflush(stdout) == 0 ? 0 : 1;
}

static int load(const char *path, ls_robot_model_t *m)
{
    char msg[512];
    if (ls_robot_model_load(path, m, msg, sizeof msg) != 0) {
        fprintf(stderr, "%s\n", msg);
        return 2;
    }
    return 0;
}

static int fk(const char *path)
{
    static ls_robot_model_t m;
    int rc = load(path, &m);
    if (rc != 0) {
        return rc;
    }
    char line[512];
    while (fgets(line, sizeof line, stdin) != NULL) {
        double q[LS_N_JOINTS], T[16];
        char *p = line;
        for (int j = 0; j < LS_N_JOINTS; j++) {
            char *end;
            q[j] = strtod(p, &end);
            if (end == p) {
                fprintf(stderr, "ls_robot_model fk: expected six joint angles per line, got: %s", line);
                return 2;
            }
            p = end;
        }
        if (ls_kin_fk(&m, q, T) != 0) {
            fprintf(stderr, "ls_robot_model fk: joint angles not finite: %s", line);
            return 2;
        }
        for (int i = 0; i < 16; i++) {
            printf("%.17g%c", T[i], i == 15 ? '\n' : ' ');
        }
    }
    return fflush(stdout) == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "keys") == 0) {
        return keys();
    }
    if (argc == 3 && strcmp(argv[1], "fk") == 0) {
        return fk(argv[2]);
    }
    if (argc == 3 && strcmp(argv[1], "check") == 0) {
        static ls_robot_model_t m;
        int rc = load(argv[2], &m);
        if (rc == 0) {
            printf("%s: %s, %s IK, reach %.3f m\n", argv[2], m.name, ls_ik_class_name(m.ik_class),
                   ls_robot_model_reach_m(&m));
        }
        return rc;
    }
    return usage();
}
