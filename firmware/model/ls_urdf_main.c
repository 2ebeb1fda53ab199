/* ls_urdf: print the URDF of a robot model (what landscaped sends with
 * describeRobot).
 *
 *   ls_urdf                      the compiled-in arm (ls-sim6) on stdout
 *   ls_urdf --model FILE         the arm of a model file
 *   ls_urdf [...] -o OUT         written to OUT
 *
 * The build runs it into build/share/landscape/ls-sim6.urdf;
 * host_tools/update_generated.sh copies it into the host package. Exit 0,
 * 1 when writing failed, 2 for bad arguments or a refused model file. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "ls_robot_model_file.h"
#include "ls_robot_urdf.h"

int main(int argc, char **argv)
{
    const char *model_path = NULL, *out_path = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--model") == 0 && i + 1 < argc && model_path == NULL) {
            model_path = argv[++i];
        } else if (strcmp(argv[i], "-o") == 0 && i + 1 < argc && out_path == NULL) {
            out_path = argv[++i];
        } else {
            fprintf(stderr, "usage: ls_urdf [--model FILE] [-o OUT]  (prints the URDF of a robot model)\n");
            return 2;
        }
    }
    static ls_robot_model_t model;
    model = ls_robot_model_default;
    char msg[512];
    if (model_path != NULL && ls_robot_model_load(model_path, &model, msg, sizeof msg) != 0) {
        fprintf(stderr, "ls_urdf: %s\n", msg);
        return 2;
    }
    FILE *out = stdout;
    if (out_path != NULL) {
        out = fopen(out_path, "w");
        if (out == NULL) {
            fprintf(stderr, "ls_urdf: cannot write %s: %s\n", out_path, strerror(errno));
            return 1;
        }
    }
    static char chunk[4096];
    size_t offset = 0, total = 0;
    int rc = 0;
    do {
        int n = ls_robot_urdf_window(&model, offset, chunk, sizeof chunk, &total);
        if (n < 0 || fwrite(chunk, 1, (size_t)n, out) != (size_t)n) {
            rc = 1;
            break;
        }
        offset += (size_t)n;
    } while (offset < total);
    if (out != stdout ? fclose(out) != 0 : fflush(out) != 0) {
        rc = 1;
    }
    if (rc != 0) {
        fprintf(stderr, "ls_urdf: writing %s failed: %s\n", out_path != NULL ? out_path : "stdout", strerror(errno));
    }
    return rc;
}
