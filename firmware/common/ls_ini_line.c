#include "ls_ini_line.h"

#include <ctype.h>
#include <string.h>

char *ls_ini_next_line(char *str, int num, FILE *f, int *line, char *why, size_t whylen)
{
    if (whylen > 0) {
        why[0] = '\0';
    }
    if (fgets(str, num, f) == NULL) {
        return NULL;
    }
    ++*line;
    const size_t n = strlen(str);
    if ((n == 0 || str[n - 1] != '\n') && !feof(f)) {
        if (n + 1 < (size_t)num) {
            snprintf(why, whylen, "a NUL byte in the line: this is not a text file");
        } else {
            snprintf(why, whylen, "line longer than %d characters", num - 3);
        }
        return NULL;
    }
    const char *start = str;
    if (*line == 1 && strncmp(start, "\xEF\xBB\xBF", 3) == 0) {
        start += 3; /* UTF-8 byte order mark */
    }
    start += strspn(start, " \t");
    if (start != str) {
        memmove(str, start, strlen(start) + 1);
    }
    return str;
}

char *ls_ini_trim(char *s)
{
    while (isspace((unsigned char)*s)) {
        s++;
    }
    size_t n = strlen(s);
    while (n > 0 && isspace((unsigned char)s[n - 1])) {
        s[--n] = '\0';
    }
    return s;
}
