/* ocg_solver.h: the C API of a problem exported by ocgroupoid (API version 3).
 *
 * One export solves every instance of its model: the instance is the parameter vector p
 * = [physical parameters | initial pack | V0 | final pack | VN | T] of the compiled NLP.
 * Build p from the numbers of a parameter file with ocg_pack() (quaternions normalised,
 * tangent bases completed), or copy it from Python (Transcription.pack).
 *
 *     ocg_result *r = ocg_result_new();
 *     double p[OCG_NP];                       // sizes also from ocg_n_p(), ... at run time
 *     ocg_pack(ocg_default_values, OCG_NV, p, OCG_NP, NULL);
 *     int code = ocg_solve(p, OCG_NP, NULL, 0, r);       // NULL: start from the geodesic guess
 *     if (code >= 0) printf("%s %g\n", ocg_status_name(r), ocg_cost(r));
 *     size_t rows, cols;
 *     const double *u = ocg_output(r, OCG_CONTROLS, &rows, &cols);  // rows = times
 *     ocg_result_free(r);
 *
 * Arrays are row-major with one row per time. Functions never abort: bad input returns a
 * negative code. Not reentrant: CasADi's generated solver keeps static memory, so solve one
 * instance at a time per process (several ocg_result objects are fine).
 */
#ifndef OCG_SOLVER_H
#define OCG_SOLVER_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define OCG_API_VERSION 3 /* 2: the control polynomial (OCG_CONTROL_BREAKS, ...);
                             3: primal-dual warm starts (ocg_solve_warm, OCG_LAM_X) */

/* Return codes. */
enum ocg_code {
  OCG_OK = 0,              /* IPOPT succeeded (Solve_Succeeded, Solved_To_Acceptable_Level,
                              Feasible_Point_Found) */
  OCG_NOT_SOLVED = 1,      /* IPOPT ran and stopped otherwise; the result holds its status and
                              last iterate */
  OCG_ERR_NULL = -1,       /* a required pointer is NULL */
  OCG_ERR_LENGTH = -2,     /* an array has the wrong number of values */
  OCG_ERR_NOT_FINITE = -3, /* NaN or Inf in the input */
  OCG_ERR_DOMAIN = -4,     /* T <= 0, a zero quaternion, a direction that is not unit length */
  OCG_ERR_MEMORY = -5,     /* out of memory */
  OCG_ERR_EVALUATION = -6, /* a generated function failed (e.g. its memory is in use) */
  OCG_ERR_UNSOLVED = -7    /* a warm start from a result that holds no solve */
};

/* What ocg_output() reads from a result: rows x cols, row-major, one row per time. */
enum ocg_output {
  OCG_X = 0,              /* 1 x n_x: NLP point with states recomputed from s_0 (warm start) */
  OCG_T = 1,              /* (N+1) x 1: node times */
  OCG_STATES = 2,         /* (N+1) x n: states as shown (rotations as row-major 3x3 matrices) */
  OCG_NODE_STATES = 3,    /* (N+1) x n: states as stored (rotations as quaternions w x y z) */
  OCG_VELOCITY_T = 4,     /* times of the velocities (nodes; interval midpoints for order 1) */
  OCG_VELOCITIES = 5,
  OCG_CONTROL_T = 6,      /* times of the control samples */
  OCG_CONTROLS = 7,       /* one row of controls per sample time */
  OCG_MULTIPLIER_T = 8,   /* times of the multipliers lambda^k of Phi_d */
  OCG_MULTIPLIERS = 9,    /* one row of lambda^k per time (0 columns without constraints) */
  OCG_FINAL_MULTIPLIERS = 10, /* 1 x m: multipliers of the final conditions */
  OCG_P = 11,             /* 1 x n_p: the parameters solved for */
  OCG_LAM_G = 12,         /* 1 x n_g: all constraint multipliers as IPOPT returned them */
  OCG_CONTROL_BREAKS = 13, /* pieces+1 x 1: breakpoints of the control polynomial */
  OCG_CONTROL_COEFFICIENTS = 14, /* pieces x (k n_u): per piece, coefficient i of control j
                                    at column i n_u + j, powers of t - breakpoint from k-1
                                    down to 0 (scipy.interpolate.PPoly's order) */
  OCG_LAM_X = 15          /* 1 x n_x: the multipliers of the variable bounds */
};

typedef struct ocg_result ocg_result;

/* The exported model and its sizes. */
const char *ocg_problem(void);
int ocg_intervals(void);     /* N */
size_t ocg_n_p(void);        /* length of p */
size_t ocg_n_x(void);        /* NLP variables (length of a warm start) */
size_t ocg_n_g(void);        /* NLP constraints */
size_t ocg_n_values(void);   /* numbers of a parameter file, see ocg_pack */
const char *ocg_strerror(int code);

/* p from the numbers of a parameter file (values in the order of README.md's table).
 * On OCG_ERR_DOMAIN, *bad_block (if not NULL) is the index of the first offending key. */
int ocg_pack(const double *values, size_t n_values, double *p, size_t n_p, int *bad_block);

/* Results. */
ocg_result *ocg_result_new(void); /* NULL when out of memory */
void ocg_result_free(ocg_result *r);

/* Solve the instance p. x0 = NULL starts from the geodesic guess of the Python API; else
 * x0 (length ocg_n_x(), e.g. OCG_X of an earlier result) is the starting point. Returns
 * OCG_OK, OCG_NOT_SOLVED, or a negative code (the result is then left unchanged). */
int ocg_solve(const double *p, size_t n_p, const double *x0, size_t n_x0, ocg_result *r);

/* Solve the instance p from the primal-dual point of an earlier result `from` (its solver's
 * point and multipliers; from may be r): IPOPT's warm start (warm_start_init_point, small
 * bound pushes, mu_init 1e-6), a few iterations when p is near from's. An export with
 * solver.backend fatrop, which has no dual warm start, starts from the primal point only.
 * Returns as ocg_solve, and OCG_ERR_UNSOLVED when from holds no solve. */
int ocg_solve_warm(const double *p, size_t n_p, const ocg_result *from, ocg_result *r);

int ocg_status(const ocg_result *r);              /* IPOPT ApplicationReturnStatus */
const char *ocg_status_name(const ocg_result *r); /* e.g. "Solve_Succeeded"; "" if unsolved */
int ocg_success(const ocg_result *r);
double ocg_cost(const ocg_result *r);
int ocg_iterations(const ocg_result *r);
double ocg_solve_seconds(const ocg_result *r);
const double *ocg_output(const ocg_result *r, enum ocg_output which, size_t *rows,
                         size_t *cols); /* NULL if unsolved or unknown */

/* The result as the solution JSON of the Python API (Solution.to_json): problem, success,
 * status, N, T, cost, stats, discretization, parameters, controls, states, velocities,
 * multipliers, diagnostics, nlp {x, p}. Returns 0, or -1 if writing failed. */
int ocg_write_json(const ocg_result *r, FILE *out);

#ifdef __cplusplus
}
#endif

#endif /* OCG_SOLVER_H */
