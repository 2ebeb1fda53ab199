/* The robot model file reader (firmware/model/ls_robot_model_file.c, inih
 * underneath): any bytes either load into a model whose IK class fits its
 * geometry, or fail with a "FILE[:LINE]: ..." line; never a crash, a hang or
 * an unterminated string. A loaded model then goes through what landscaped
 * does with it: FK, every IK branch of that pose, and its URDF in pieces.
 * The input reaches the reader as a file (a memfd seen through
 * /proc/self/fd), exactly as [robot] model = FILE does. */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_file.h"
#include "ls_kin.h"
#include "ls_robot_model_file.h"
#include "ls_robot_urdf.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_input_file(data, size);
    ls_robot_model_t m;
    char msg[512] = "";
    if (ls_robot_model_load(path, &m, msg, sizeof msg) != LS_OK) {
        if (msg[0] == '\0' || memchr(msg, '\0', sizeof msg) == NULL || strncmp(msg, path, strlen(path)) != 0) {
            __builtin_trap(); /* a refusal names the file and says what is wrong */
        }
        return 0;
    }
    ls_ik_class_t cls;
    if (memchr(m.name, '\0', sizeof m.name) == NULL || ls_kin_classify(&m, &cls, NULL, 0) != LS_OK ||
        cls != m.ik_class) {
        __builtin_trap();
    }
    const double q[LS_N_JOINTS] = { 0.1, -0.2, 0.3, -0.4, 0.5, -0.6 };
    double T[16], qs[LS_KIN_MAX_BRANCHES][LS_N_JOINTS];
    int n = 0;
    if (ls_kin_fk(&m, q, T) != LS_OK) {
        __builtin_trap();
    }
    const int rc = ls_kin_ik_all(&m, T, qs, &n);
    if (rc == LS_EINVAL || n < 0 || n > LS_KIN_MAX_BRANCHES) {
        __builtin_trap(); /* the class fits: IK answers for the pose */
    }
    static char piece[1024];
    size_t total = 0, offset = 0;
    do {
        int got = ls_robot_urdf_window(&m, offset, piece, sizeof piece, &total);
        if (got <= 0 || strlen(piece) != (size_t)got) {
            __builtin_trap();
        }
        offset += (size_t)got;
    } while (offset < total);
    return 0;
}
