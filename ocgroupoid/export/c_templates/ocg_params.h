/* ocg_params.h: reading a parameter file as strictly as the problem files are read in Python.
 *
 * A parameter file is text of at most OCG_PARAMS_MAX_BYTES bytes (UTF-8, no NUL or other
 * control character but tab and line breaks) with one `KEY v1 v2 ...` line per key of
 * ocg_blocks; `#` starts a comment; keys left out keep their values. A number is written in
 * decimal (`5`, `-0.25`, `1.5e-3`: no hex, inf or nan), holds in a double (neither overflows
 * nor falls below 2.2e-308) and lies in its key's range (ocg_ranges, generated from
 * ocgroupoid.model.ranges), and the messages are Python's.
 */
#ifndef OCG_PARAMS_H
#define OCG_PARAMS_H

/* Read PATH into values (which hold the defaults); 0, or 2 with a message on stderr. */
int ocg_read_params(const char *path, double *values);

#endif
