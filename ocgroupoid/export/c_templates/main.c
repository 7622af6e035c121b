/* main.c: `solve [PARAMS]` solves the exported instance (or the one PARAMS describes) and
 * prints the solution JSON on stdout.
 *
 * PARAMS holds one `KEY v1 v2 ...` line per key of README.md's table; `#` starts a comment;
 * keys left out keep the exported values. The numbers are checked as the problem files
 * check them in Python, with the same messages: finite, representable (no overflow or
 * underflow), and > 0 for the physical parameters a model requires positive (inertias,
 * masses, radii). Exit codes: 0 solved, 1 IPOPT failed (the JSON is still printed, with
 * success false and IPOPT's status), 2 bad input (a message on stderr).
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ocg_model.h"
#include "ocg_solver.h"

static int usage(FILE *out) {
  int i;
  fprintf(out,
          "usage: solve [PARAMS]\n"
          "Solve %s (N=%d) and print the solution JSON on stdout.\n"
          "PARAMS: lines `KEY v1 v2 ...` ('#' comments; keys left out keep the exported\n"
          "values, see params.txt). Keys:\n",
          OCG_PROBLEM, OCG_N);
  for (i = 0; i < OCG_N_BLOCKS; ++i)
    fprintf(out, "  %-16s %d number%s  %s\n", ocg_blocks[i].key, ocg_blocks[i].size,
            ocg_blocks[i].size == 1 ? " " : "s", ocg_blocks[i].meaning);
  fprintf(out, "Exit codes: 0 solved, 1 IPOPT failed (JSON still printed), 2 bad input.\n");
  return out == stdout ? 0 : 2;
}

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

/* Read PARAMS into values (which hold the defaults); 0, or 2 with a message. */
static int read_params(const char *path, double *values) {
  FILE *in = fopen(path, "r");
  char *line = NULL, *save = NULL;
  size_t cap = 0;
  int seen[OCG_N_BLOCKS + 1] = {0};
  int number = 0, status = 0;
  struct stat info;
  if (!in) {
    fprintf(stderr, "error: cannot open %s: %s\n", path, strerror(errno));
    return 2;
  }
  if (fstat(fileno(in), &info) == 0 && S_ISDIR(info.st_mode)) {
    fprintf(stderr, "error: %s is a folder; give a parameter file (e.g. params.txt)\n", path);
    fclose(in);
    return 2;
  }
  while (status == 0 && getline(&line, &cap, in) != -1) {
    char *hash = strchr(line, '#'), *key, *tok;
    int b, count = 0;
    ++number;
    if (hash) *hash = '\0';
    key = strtok_r(line, " \t\r\n", &save);
    if (!key) continue;
    b = find_block(key);
    if (b < 0) {
      fprintf(stderr, "error: %s:%d: unknown key '%s'; run `solve --help` for the keys\n",
              path, number, key);
      status = 2;
      break;
    }
    if (seen[b]++) {
      fprintf(stderr, "error: %s:%d: key '%s' given twice; keep one line\n", path, number,
              key);
      status = 2;
      break;
    }
    while ((tok = strtok_r(NULL, " \t\r\n", &save)) != NULL) {
      char *end, shown[40];
      double v;
      errno = 0;
      v = strtod(tok, &end);
      if (end == tok || *end != '\0') {
        fprintf(stderr, "error: %s:%d: '%s' is not a number (key %s)\n", path, number, tok,
                key);
        status = 2;
        break;
      }
      if (!isfinite(v)) {
        fprintf(stderr, "error: %s:%d: %s has a non-finite value '%s'%s; give finite numbers\n",
                path, number, key, tok, errno == ERANGE ? " (it overflows a double)" : "");
        status = 2;
        break;
      }
      if (errno == ERANGE) {
        fprintf(stderr, "error: %s:%d: %s: '%s' underflows (a double holds magnitudes down "
                "to 2.2e-308); write 0 or a larger number\n", path, number, key, tok);
        status = 2;
        break;
      }
      if (ocg_blocks[b].positive && !(v > 0)) {
        python_repr(v, shown, sizeof shown);
        if (ocg_blocks[b].size == 1)
          fprintf(stderr, "error: %s:%d: %s: value must be > 0, got %s\n", path, number, key,
                  shown);
        else
          fprintf(stderr, "error: %s:%d: %s: component %d must be > 0, got %s\n", path, number,
                  key, count, shown);
        status = 2;
        break;
      }
      if (count < ocg_blocks[b].size) values[ocg_blocks[b].offset + count] = v;
      ++count;
    }
    if (status == 0 && count != ocg_blocks[b].size) {
      fprintf(stderr, "error: %s:%d: %s takes %d number%s (%s), got %d\n", path, number, key,
              ocg_blocks[b].size, ocg_blocks[b].size == 1 ? "" : "s", ocg_blocks[b].meaning,
              count);
      status = 2;
    }
  }
  if (status == 0 && ferror(in)) {
    fprintf(stderr, "error: reading %s failed: %s\n", path, strerror(errno));
    status = 2;
  }
  free(line);
  fclose(in);
  return status;
}

int main(int argc, char **argv) {
  double values[OCG_NV + 1], p[OCG_NP];
  ocg_result *r;
  int code, bad = -1;
  if (argc > 2) return usage(stderr);
  if (argc == 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0))
    return usage(stdout);
  memcpy(values, ocg_default_values, sizeof(double) * OCG_NV);
  if (argc == 2 && read_params(argv[1], values) != 0) return 2;
  code = ocg_pack(values, OCG_NV, p, OCG_NP, &bad);
  if (code != OCG_OK) {
    if (bad >= 0)
      fprintf(stderr, "error: %s: outside its domain: %s\n", ocg_blocks[bad].key,
              ocg_blocks[bad].meaning);
    else
      fprintf(stderr, "error: %s\n", ocg_strerror(code));
    return 2;
  }
  r = ocg_result_new();
  if (!r) {
    fprintf(stderr, "error: %s\n", ocg_strerror(OCG_ERR_MEMORY));
    return 2;
  }
  code = ocg_solve(p, OCG_NP, NULL, 0, r);
  if (code < 0) {
    fprintf(stderr, "error: %s\n", ocg_strerror(code));
    ocg_result_free(r);
    return 2;
  }
  if (ocg_write_json(r, stdout) != 0) {
    fprintf(stderr, "error: writing the JSON failed\n");
    code = 2;
  } else if (code == OCG_NOT_SOLVED) {
    fprintf(stderr, "IPOPT failed: %s\n", ocg_status_name(r));
    code = 1;
  }
  ocg_result_free(r);
  return code;
}
