/* The line source of the INI readers (landscaped.conf, robot model files):
 * inih's ini_parse_stream reads through a callback, and both readers give it
 * this, so a file is taken apart the same way and refused with the same
 * words wherever it comes from. Init-time only: stdio, no state of its own. */
#ifndef LS_INI_LINE_H
#define LS_INI_LINE_H

#include <stddef.h>
#include <stdio.h>

/* The next line of f into str (num bytes, inih's buffer), counted in *line.
 * Refuses what inih would take apart silently: a NUL byte in the line ("a
 * NUL byte in the line: this is not a text file") and a line longer than
 * num - 3 characters ("line longer than N characters"), with that text in
 * why. Drops a UTF-8 byte order mark at the start of line 1 and the leading
 * blanks of every line, so that inih never reads an indented line as the
 * continuation of the previous value: every key is on its own line.
 * Returns str; NULL at the end of the file (why "") or on a refusal (why
 * set; the caller reports it with the file and *line). */
char *ls_ini_next_line(char *str, int num, FILE *f, int *line, char *why, size_t whylen);

/* s without its leading and trailing blanks: the trailing ones are cut in
 * place (a NUL written), the result points into s. */
char *ls_ini_trim(char *s);

#endif
