/* ls_urdf: print the URDF of the simulated arm (ls_robot_model_default).
 *
 *   ls_urdf            the URDF on stdout
 *   ls_urdf -o FILE    written to FILE
 *
 * The build runs it into build/share/landscape/ls-sim6.urdf;
 * host_tools/update_generated.sh copies it into the host package. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "ls_robot_urdf.h"

int main(int argc, char **argv)
{
    FILE *out = stdout;
    const char *path = "stdout";
    if (argc == 3 && strcmp(argv[1], "-o") == 0) {
        path = argv[2];
        out = fopen(path, "w");
        if (out == NULL) {
            fprintf(stderr, "ls_urdf: cannot write %s: %s\n", path, strerror(errno));
            return 1;
        }
    } else if (argc != 1) {
        fprintf(stderr, "usage: ls_urdf [-o FILE]  (prints the URDF of the simulated arm)\n");
        return 2;
    }
    int rc = ls_robot_urdf_write(&ls_robot_model_default, out);
    if (out != stdout && fclose(out) != 0) {
        rc = -1;
    }
    if (rc != 0) {
        fprintf(stderr, "ls_urdf: writing %s failed: %s\n", path, strerror(errno));
        return 1;
    }
    return 0;
}
