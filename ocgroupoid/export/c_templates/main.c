/* main.c: `solve [PARAMS]` solves the exported instance (or the one PARAMS describes) and
 * prints the solution JSON on stdout.
 *
 * PARAMS holds one `KEY v1 v2 ...` line per key of README.md's table; `#` starts a comment;
 * keys left out keep the exported values. It is read as strictly as the problem files are in
 * Python, with the same ranges and messages (ocg_params.c): at most 1 MB of text, decimal
 * numbers a double holds, each in its key's range (T in [1e-6, 1e6], inertias, masses and
 * radii > 0, every number within the scale double precision resolves). A solve that runs
 * past solver.max_seconds is stopped. Exit codes: 0 solved and verified (as in Python: the
 * plan replayed through the continuous problem lands and keeps its bounds), 1 the solver failed,
 * ran out of time or the solution did not verify (the JSON is still printed, with success false,
 * the solver's status and diagnostics.verdict), 2 bad input (a message on stderr).
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ocg_model.h"
#include "ocg_params.h"
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
  fprintf(out, "Exit codes: 0 solved and verified, 1 not (the solver failed or the solution "
               "did not verify; JSON still printed), 2 bad input.\n");
  return out == stdout ? 0 : 2;
}

/* SIGALRM past OCG_MAX_SECONDS: a solver that does not stop by itself (fatrop has no time
 * limit) is stopped here, with a message (write(2) and _exit(2) are safe in a handler). */
static void out_of_time(int signum) {
  static const char message[] =
      "error: the solve took longer than solver.max_seconds (OCG_MAX_SECONDS in ocg_model.h) "
      "and was stopped; raise it with make CFLAGS=-DOCG_MAX_SECONDS=..., lower N, or use "
      "IPOPT\n";
  ssize_t ignored = write(2, message, sizeof message - 1);
  (void)signum;
  (void)ignored;
  _exit(1);
}

int main(int argc, char **argv) {
  double values[OCG_NV + 1], p[OCG_NP];
  ocg_result *r;
  int code, bad = -1;
  if (argc > 2) return usage(stderr);
  if (argc == 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0))
    return usage(stdout);
  memcpy(values, ocg_default_values, sizeof(double) * OCG_NV);
  if (argc == 2 && ocg_read_params(argv[1], values) != 0) return 2;
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
  /* IPOPT stops itself at max_wall_time (OCG_MAX_SECONDS), printing the JSON; the alarm,
   * a little later, is for what does not stop by itself */
  signal(SIGALRM, out_of_time);
  alarm((unsigned)ceil(1.1 * OCG_MAX_SECONDS) + 1);
  code = ocg_solve(p, OCG_NP, NULL, 0, r);
  alarm(0);
  if (code < 0) {
    fprintf(stderr, "error: %s\n", ocg_strerror(code));
    ocg_result_free(r);
    return 2;
  }
  if (ocg_write_json(r, stdout) != 0) {
    fprintf(stderr, "error: writing the JSON failed\n");
    code = 2;
  } else if (code == OCG_NOT_SOLVED && ocg_status(r) == 0 /* Solve_Succeeded */) {
    fprintf(stderr, "not verified: the solution does not pass the checks against the "
                    "continuous problem (diagnostics.verdict in the JSON says which)\n");
    code = 1;
  } else if (code == OCG_NOT_SOLVED) {
    fprintf(stderr, "solver failed: %s\n", ocg_status_name(r));
    code = 1;
  }
  ocg_result_free(r);
  return code;
}
