/* ocg_params.c: a parameter file read as strictly as Python reads problem files (see
 * ocg_params.h). The file is read whole, within a size cap, and checked for NUL bytes, other
 * control characters and UTF-8 before a line is parsed; every number is checked for its
 * syntax, for what a double holds, and against its key's range (ocg_ranges), with the
 * messages of ocgroupoid.model.ranges.Range.problem and of the YAML loader. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ocg_model.h"
#include "ocg_params.h"

/* the longest number (characters): Python refuses integers beyond 320 digits */
#define OCG_NUMBER_CHARS 320
/* how much of a token a message shows */
#define OCG_SHOWN 40

static int find_block(const char *key) {
  int i;
  for (i = 0; i < OCG_N_BLOCKS; ++i)
    if (strcmp(ocg_blocks[i].key, key) == 0) return i;
  return -1;
}

/* x as Python's repr writes it (shortest round trip, "1.0" not "1", "1e-05"), so that the
 * messages read as the Python side's. */
static void python_repr(double x, char *buf, size_t size) {
  int digits, exponent;
  if (x == 0.0 || !isfinite(x)) {
    snprintf(buf, size, "%s", x != x ? "nan" : isinf(x) ? (x > 0 ? "inf" : "-inf")
                                                      : (signbit(x) ? "-0.0" : "0.0"));
    return;
  }
  for (digits = 1; digits < 17; ++digits) {
    snprintf(buf, size, "%.*e", digits - 1, x);
    if (strtod(buf, NULL) == x) break;
  }
  exponent = (int)floor(log10(fabs(strtod(buf, NULL))));
  if (exponent >= -4 && exponent < 16) {
    size_t n;
    snprintf(buf, size, "%.*f", digits - 1 - exponent > 0 ? digits - 1 - exponent : 0, x);
    n = strlen(buf);
    if (!strchr(buf, '.') && n + 2 < size) memcpy(buf + n, ".0", 3);
  } else {
    snprintf(buf, size, "%.*e", digits - 1, x);
  }
}

/* The first OCG_SHOWN characters of a token, with "..." when it is longer. */
static const char *shown(const char *token, char *buf) {
  size_t n = strlen(token);
  if (n <= OCG_SHOWN) return token;
  memcpy(buf, token, OCG_SHOWN);
  memcpy(buf + OCG_SHOWN, "...", 4);
  return buf;
}

/* 1-based line of the byte at offset `at`. */
static int line_of(const char *text, size_t at) {
  int line = 1;
  size_t i;
  for (i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

/* Offset of the first byte that does not continue valid UTF-8 (n if none). */
static size_t utf8_error(const unsigned char *s, size_t n) {
  size_t i = 0;
  while (i < n) {
    unsigned char c = s[i];
    size_t len = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    size_t k;
    if (len == 0 || i + len > n || (len == 2 && c < 0xc2) || (len == 4 && c > 0xf4)) return i;
    for (k = 1; k < len; ++k)
      if ((s[i + k] & 0xc0) != 0x80) return i;
    if ((len == 3 && c == 0xe0 && s[i + 1] < 0xa0) || (len == 3 && c == 0xed && s[i + 1] > 0x9f) ||
        (len == 4 && c == 0xf0 && s[i + 1] < 0x90) || (len == 4 && c == 0xf4 && s[i + 1] > 0x8f))
      return i;
    i += len;
  }
  return n;
}

/* The file as a NUL-terminated text, or 2 with a message: a folder, a NUL byte, more than
 * OCG_PARAMS_MAX_BYTES bytes, not UTF-8, a control character. */
static int read_text(const char *path, char **out) {
  FILE *in = fopen(path, "rb");
  struct stat info;
  char *text;
  size_t n, i;
  const char *nul;
  if (!in) {
    fprintf(stderr, "error: cannot open %s: %s\n", path, strerror(errno));
    return 2;
  }
  if (fstat(fileno(in), &info) == 0 && S_ISDIR(info.st_mode)) {
    fprintf(stderr, "error: %s is a folder; give a parameter file (e.g. params.txt)\n", path);
    fclose(in);
    return 2;
  }
  text = malloc((size_t)OCG_PARAMS_MAX_BYTES + 2);
  if (!text) {
    fprintf(stderr, "error: out of memory reading %s\n", path);
    fclose(in);
    return 2;
  }
  n = fread(text, 1, (size_t)OCG_PARAMS_MAX_BYTES + 1, in);
  if (ferror(in)) {
    fprintf(stderr, "error: reading %s failed: %s\n", path, strerror(errno));
    fclose(in);
    free(text);
    return 2;
  }
  fclose(in);
  text[n] = '\0';
  nul = memchr(text, '\0', n);
  if (nul) {
    fprintf(stderr, "error: %s:%d: a NUL byte: this is a binary file, not a parameter file; "
            "give a text file of KEY v1 v2 ... lines (e.g. params.txt)\n", path,
            line_of(text, (size_t)(nul - text)));
  } else if (n > (size_t)OCG_PARAMS_MAX_BYTES) {
    fprintf(stderr, "error: %s: more than %d bytes; a parameter file is a few lines of text\n",
            path, OCG_PARAMS_MAX_BYTES);
  } else if ((i = utf8_error((const unsigned char *)text, n)) < n) {
    fprintf(stderr, "error: %s:%d: not UTF-8 text; give a text parameter file\n", path,
            line_of(text, i));
  } else {
    for (i = 0; i < n; ++i) {
      unsigned char c = (unsigned char)text[i];
      if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f) break;
    }
    if (i == n) {
      *out = text;
      return 0;
    }
    fprintf(stderr, "error: %s:%d: a control character (byte 0x%02x) is not text; give a text "
            "parameter file\n", path, line_of(text, i), (unsigned)(unsigned char)text[i]);
  }
  free(text);
  return 2;
}

/* Whether a token is a number in decimal: [+-] digits [. digits] [e [+-] digits]. */
static int decimal(const char *t, int *nonzero) {
  int digits = 0;
  *nonzero = 0;
  if (*t == '+' || *t == '-') ++t;
  for (; *t >= '0' && *t <= '9'; ++t, ++digits) *nonzero |= *t != '0';
  if (*t == '.')
    for (++t; *t >= '0' && *t <= '9'; ++t, ++digits) *nonzero |= *t != '0';
  if (digits == 0) return 0;
  if (*t == 'e' || *t == 'E') {
    ++t;
    if (*t == '+' || *t == '-') ++t;
    if (!(*t >= '0' && *t <= '9')) return 0;
    while (*t >= '0' && *t <= '9') ++t;
  }
  return *t == '\0';
}

/* One number of KEY, or 2 with a message. */
static int number(const char *path, int line, const char *key, const char *tok, double *v) {
  char buf[OCG_SHOWN + 4];
  int nonzero;
  size_t n = strlen(tok);
  if (n > OCG_NUMBER_CHARS) {
    fprintf(stderr, "error: %s:%d: %s: '%s' (%zu characters) is too long for a number; write "
            "it with fewer digits\n", path, line, key, shown(tok, buf), n);
    return 2;
  }
  if (!decimal(tok, &nonzero)) {
    fprintf(stderr, "error: %s:%d: '%s' is not a number (key %s); write decimal digits, e.g. "
            "5, -0.25 or 1.5e-3\n", path, line, shown(tok, buf), key);
    return 2;
  }
  *v = strtod(tok, NULL);
  if (isinf(*v)) {
    fprintf(stderr, "error: %s:%d: %s: %s is too large for a float (beyond 1.8e+308); write a "
            "smaller number\n", path, line, key, tok);
    return 2;
  }
  if (nonzero && fabs(*v) < DBL_MIN) {
    fprintf(stderr, "error: %s:%d: %s: %s is too small for a float (below 2.2e-308, it would "
            "be read as 0 or lose digits); write 0 or a larger number\n", path, line, key, tok);
    return 2;
  }
  return 0;
}

/* The numbers of block b against its range (ocgroupoid.model.ranges.Range.problem). */
static int in_range(const char *path, int line, int b, const double *v) {
  const ocg_range *r = &ocg_ranges[b];
  const char *key = ocg_blocks[b].key;
  int n = ocg_blocks[b].size, i;
  char what[32], repr[40];
  double small, large;
  for (i = 0; i < n; ++i) {
    if (n > 1)
      snprintf(what, sizeof what, "component %d", i);
    else
      snprintf(what, sizeof what, "value");
    if (r->kind == OCG_RANGE_TIME && !(r->lo <= v[i] && v[i] <= r->hi)) {
      fprintf(stderr, "error: %s:%d: %s = %g is outside [%g, %g], the range of times the NLP's "
              "scaling tolerates; rescale the units of time (and the parameters with them)\n",
              path, line, key, v[i], r->lo, r->hi);
      return 2;
    }
    if (r->kind == OCG_RANGE_POSITIVE && !(v[i] > 0)) {
      python_repr(v[i], repr, sizeof repr);
      fprintf(stderr, "error: %s:%d: %s: %s must be > 0, got %s\n", path, line, key, what, repr);
      return 2;
    }
    if (!(r->lo <= v[i] && v[i] <= r->hi)) {
      fprintf(stderr, "error: %s:%d: %s: %s is %g, outside [%g, %g], the scale double precision "
              "resolves next to the problem's other numbers; rescale its units\n", path, line,
              key, what, v[i], r->lo, r->hi);
      return 2;
    }
  }
  if (r->ratio > 0 && n > 1) {
    small = large = v[0];
    for (i = 1; i < n; ++i) {
      small = v[i] < small ? v[i] : small;
      large = v[i] > large ? v[i] : large;
    }
    if (large > r->ratio * small) {
      fprintf(stderr, "error: %s:%d: %s: its components span a factor %g (%g to %g), beyond the "
              "%g double precision resolves (the smaller keep fewer than 4 digits next to the "
              "larger); bring them closer\n", path, line, key, large / small, small, large,
              r->ratio);
      return 2;
    }
  }
  return 0;
}

/* One line (comment removed): KEY and its numbers into values; 0, or 2 with a message. */
static int parse_line(const char *path, int line, char *text, int *seen, double *values) {
  char *save = NULL, *tok, *key = strtok_r(text, " \t\r", &save);
  char buf[OCG_SHOWN + 4];
  double v[64], *got;
  int b, count = 0, status = 0;
  if (!key) return 0;
  b = find_block(key);
  if (b < 0) {
    fprintf(stderr, "error: %s:%d: unknown key '%s'; run `solve --help` for the keys\n", path,
            line, shown(key, buf));
    return 2;
  }
  if (seen[b]++) {
    fprintf(stderr, "error: %s:%d: key '%s' given twice; keep one line\n", path, line, key);
    return 2;
  }
  got = ocg_blocks[b].size <= 64 ? v : malloc(sizeof(double) * (size_t)ocg_blocks[b].size);
  if (!got) {
    fprintf(stderr, "error: out of memory reading %s\n", path);
    return 2;
  }
  while (status == 0 && (tok = strtok_r(NULL, " \t\r", &save)) != NULL) {
    double x = 0.0;
    status = number(path, line, key, tok, &x);
    if (status == 0 && count < ocg_blocks[b].size) got[count] = x;
    ++count;
  }
  if (status == 0 && count != ocg_blocks[b].size) {
    fprintf(stderr, "error: %s:%d: %s takes %d number%s (%s), got %d\n", path, line, key,
            ocg_blocks[b].size, ocg_blocks[b].size == 1 ? "" : "s", ocg_blocks[b].meaning,
            count);
    status = 2;
  }
  if (status == 0) status = in_range(path, line, b, got);
  if (status == 0) memcpy(values + ocg_blocks[b].offset, got, sizeof(double) * (size_t)count);
  if (got != v) free(got);
  return status;
}

int ocg_read_params(const char *path, double *values) {
  char *text = NULL, *line, *next;
  int seen[OCG_N_BLOCKS + 1] = {0};
  int number_of_line = 0, status;
  status = read_text(path, &text);
  if (status != 0) return status;
  for (line = text; status == 0 && line; line = next) {
    char *hash;
    next = strchr(line, '\n');
    if (next) *next++ = '\0';
    ++number_of_line;
    hash = strchr(line, '#');
    if (hash) *hash = '\0';
    status = parse_line(path, number_of_line, line, seen, values);
  }
  free(text);
  return status;
}
