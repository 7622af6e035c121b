/* ocg_solver.c: the C API of ocg_solver.h on top of the CasADi-generated functions
 * (ocg_generated.c, ocg_generated_warm.c) and the model tables (ocg_model.c). The same file serves every export.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ocg_generated.h"
#include "ocg_generated_warm.h"
#include "ocg_ipopt_hooks.h"
#include "ocg_model.h"
#include "ocg_solver.h"
#if OCG_BACKEND_FATROP
#include "ocg_fatrop_hooks.h"
#endif

/* A failed fatrop solve (not an IPOPT status; fatrop's return flag is 1 for every failure). */
#define OCG_FATROP_FAILED (-1000)

/* ------------------------------------------------------------------ solver hooks */

/* The return status (IPOPT's vocabulary) and iterations of the last solve, whichever backend
 * ran it. */
static struct {
  int iterations;
  enum ApplicationReturnStatus status;
} ocg_last;

#if OCG_BACKEND_FATROP
fatrop_int ocg_fatrop_solve(struct FatropOcpCSolver *solver) {
  fatrop_int flag = fatrop_ocp_c_solve(solver);
  const struct FatropOcpCStats *stats = fatrop_ocp_c_get_stats(solver);
  ocg_last.iterations = stats ? (int)stats->iterations_count : 0;
  ocg_last.status = flag == 0 ? Solve_Succeeded
                          : ocg_last.iterations >= OCG_MAX_ITER
                              ? Maximum_Iterations_Exceeded
                              : (enum ApplicationReturnStatus)OCG_FATROP_FAILED;
  return flag;
}
#endif

static bool ocg_intermediate(ipindex alg_mod, ipindex iter_count, ipnumber obj_value,
                             ipnumber inf_pr, ipnumber inf_du, ipnumber mu, ipnumber d_norm,
                             ipnumber regularization_size, ipnumber alpha_du, ipnumber alpha_pr,
                             ipindex ls_trials, UserDataPtr user_data) {
  (void)alg_mod, (void)obj_value, (void)inf_pr, (void)inf_du, (void)mu, (void)d_norm;
  (void)regularization_size, (void)alpha_du, (void)alpha_pr, (void)ls_trials, (void)user_data;
  ocg_last.iterations = (int)iter_count;
  return true;
}

IpoptProblem ocg_create_ipopt_problem(ipindex n, ipnumber *x_L, ipnumber *x_U, ipindex m,
                                      ipnumber *g_L, ipnumber *g_U, ipindex nele_jac,
                                      ipindex nele_hess, ipindex index_style,
                                      Eval_F_CB eval_f, Eval_G_CB eval_g,
                                      Eval_Grad_F_CB eval_grad_f, Eval_Jac_G_CB eval_jac_g,
                                      Eval_H_CB eval_h) {
  IpoptProblem problem = CreateIpoptProblem(n, x_L, x_U, m, g_L, g_U, nele_jac, nele_hess,
                                            index_style, eval_f, eval_g, eval_grad_f,
                                            eval_jac_g, eval_h);
  if (problem) SetIntermediateCallback(problem, ocg_intermediate);
  return problem;
}

enum ApplicationReturnStatus ocg_ipopt_solve(IpoptProblem problem, ipnumber *x, ipnumber *g,
                                             ipnumber *obj_val, ipnumber *mult_g,
                                             ipnumber *mult_x_L, ipnumber *mult_x_U,
                                             UserDataPtr user_data) {
  ocg_last.status =
      IpoptSolve(problem, x, g, obj_val, mult_g, mult_x_L, mult_x_U, user_data);
  return ocg_last.status;
}

static const char *ocg_ipopt_status_name(int status) {
  switch (status) {
    case Solve_Succeeded: return "Solve_Succeeded";
    case OCG_FATROP_FAILED: return "Fatrop_Failed";
    case Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Diverging_Iterates: return "Diverging_Iterates";
    case User_Requested_Stop: return "User_Requested_Stop";
    case Feasible_Point_Found: return "Feasible_Point_Found";
    case Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Restoration_Failed: return "Restoration_Failed";
    case Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Maximum_WallTime_Exceeded: return "Maximum_WallTime_Exceeded";
    case Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Invalid_Option: return "Invalid_Option";
    case Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Unrecoverable_Exception: return "Unrecoverable_Exception";
    case NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Insufficient_Memory: return "Insufficient_Memory";
    case Internal_Error: return "Internal_Error";
    default: return "Unknown_Status";
  }
}

/* ------------------------------------------------------------------ generated functions */

typedef struct {
  int (*eval)(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w,
              int mem);
  int (*work)(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw, casadi_int *sz_w);
  int (*checkout)(void);
  void (*release)(int mem);
  void (*incref)(void);
  void (*decref)(void);
  const casadi_int *(*sparsity_out)(casadi_int i);
  casadi_int (*n_out)(void);
} ocg_function;

#define OCG_FUNCTION(name)                                                              \
  {name, name##_work, name##_checkout, name##_release, name##_incref, name##_decref,     \
   name##_sparsity_out, name##_n_out}

static const ocg_function ocg_f_nlpsol = OCG_FUNCTION(ocg_gen_nlpsol);
static const ocg_function ocg_f_nlpsol_warm = OCG_FUNCTION(ocg_gen_nlpsol_warm);
static const ocg_function ocg_f_guess = OCG_FUNCTION(ocg_gen_guess);
static const ocg_function ocg_f_pack = OCG_FUNCTION(ocg_gen_pack);
static const ocg_function ocg_f_post = OCG_FUNCTION(ocg_gen_post);
static const ocg_function ocg_f_verify = OCG_FUNCTION(ocg_gen_verify);
static const ocg_function *const ocg_functions[] = {&ocg_f_nlpsol, &ocg_f_nlpsol_warm,
                                                    &ocg_f_guess, &ocg_f_pack, &ocg_f_post,
                                                    &ocg_f_verify};
/* The checks of ocg_gen_verify (ratios to their tolerances, each passes at <= 1) and the
 * figures behind them, as Python's verdict (ocgroupoid.solve.verify_graph) names them. */
static const char *const ocg_check_names[OCG_N_CHECKS] = OCG_CHECK_NAMES;
static const char *const ocg_check_failures[OCG_N_CHECKS] = OCG_CHECK_FAILURES;
static const char *const ocg_figure_names[OCG_N_FIGURES] = OCG_FIGURE_NAMES;
#define OCG_N_FUNCTIONS (sizeof ocg_functions / sizeof ocg_functions[0])
/* ocg_gen_post has OCG_N_POST outputs (ocg_model.h): OCG_X .. OCG_FINAL_MULTIPLIERS, then the
 * control polynomial's breakpoints and coefficients */
static int ocg_post_index(enum ocg_output which) {
  if ((int)which >= 0 && (int)which <= (int)OCG_FINAL_MULTIPLIERS) return (int)which;
  if (which == OCG_CONTROL_BREAKS) return 11;
  if (which == OCG_CONTROL_COEFFICIENTS) return 12;
  return -1;
}

typedef struct {
  const casadi_real **arg;
  casadi_real **res;
  casadi_int *iw;
  casadi_real *w;
} ocg_work;

static void ocg_work_free(ocg_work *wk) {
  free((void *)wk->arg);
  free(wk->res);
  free(wk->iw);
  free(wk->w);
}

/* Work arrays large enough for every generated function. */
static int ocg_work_new(ocg_work *wk) {
  casadi_int n_arg = 0, n_res = 0, n_iw = 0, n_w = 0;
  size_t i;
  for (i = 0; i < OCG_N_FUNCTIONS; ++i) {
    casadi_int a, r, iw, w;
    ocg_functions[i]->work(&a, &r, &iw, &w);
    if (a > n_arg) n_arg = a;
    if (r > n_res) n_res = r;
    if (iw > n_iw) n_iw = iw;
    if (w > n_w) n_w = w;
  }
  wk->arg = malloc(sizeof(*wk->arg) * (size_t)(n_arg + 1));
  wk->res = malloc(sizeof(*wk->res) * (size_t)(n_res + 1));
  wk->iw = malloc(sizeof(*wk->iw) * (size_t)(n_iw + 1));
  wk->w = malloc(sizeof(*wk->w) * (size_t)(n_w + 1));
  if (!wk->arg || !wk->res || !wk->iw || !wk->w) {
    ocg_work_free(wk);
    return OCG_ERR_MEMORY;
  }
  return OCG_OK;
}

static int ocg_call(const ocg_function *f, const double *const *in, size_t n_in,
                    double *const *out, size_t n_out, ocg_work *wk) {
  size_t i;
  int mem, flag;
  for (i = 0; i < n_in; ++i) wk->arg[i] = in[i];
  for (i = 0; i < n_out; ++i) wk->res[i] = out[i];
  f->incref();
  mem = f->checkout();
  if (mem < 0) {
    f->decref();
    return OCG_ERR_EVALUATION;
  }
  flag = f->eval(wk->arg, wk->res, wk->iw, wk->w, mem);
  f->release(mem);
  f->decref();
  return flag ? OCG_ERR_EVALUATION : OCG_OK;
}

/* ------------------------------------------------------------------ results */

struct ocg_result {
  int solved, status, success, iterations, warm;
  double checks[OCG_N_CHECKS], figures[OCG_N_FIGURES]; /* the verdict (ocg_gen_verify) */
  double cost, seconds, residual;
  double p[OCG_NP], x_ipopt[OCG_NX], x_start[OCG_NX], g[OCG_NG + 1], lam_g[OCG_NG + 1];
  double lam_x[OCG_NX], lam_g_start[OCG_NG + 1], lam_x_start[OCG_NX];
  double *post[OCG_N_POST];
  size_t post_width[OCG_N_POST], post_count[OCG_N_POST]; /* CasADi nrow, ncol */
  ocg_work work;
};

const char *ocg_problem(void) { return OCG_PROBLEM; }
int ocg_intervals(void) { return OCG_N; }
size_t ocg_n_p(void) { return OCG_NP; }
size_t ocg_n_x(void) { return OCG_NX; }
size_t ocg_n_g(void) { return OCG_NG; }
size_t ocg_n_values(void) { return OCG_NV; }

const char *ocg_strerror(int code) {
  switch (code) {
    case OCG_OK: return "solved";
    case OCG_NOT_SOLVED: return "the solver stopped without success (see the status)";
    case OCG_ERR_NULL: return "a required pointer is NULL";
    case OCG_ERR_LENGTH: return "an array has the wrong number of values";
    case OCG_ERR_NOT_FINITE: return "NaN or Inf in the input";
    case OCG_ERR_DOMAIN:
      return "a value is outside its domain (T <= 0, zero quaternion, non-unit direction)";
    case OCG_ERR_MEMORY: return "out of memory";
    case OCG_ERR_EVALUATION: return "a generated function failed";
    case OCG_ERR_UNSOLVED: return "a warm start from a result that holds no solve";
    default: return "unknown code";
  }
}

static int ocg_all_finite(const double *v, size_t n) {
  size_t i;
  for (i = 0; i < n; ++i)
    if (!isfinite(v[i])) return 0;
  return 1;
}

void ocg_result_free(ocg_result *r) {
  size_t i;
  if (!r) return;
  for (i = 0; i < OCG_N_POST; ++i) free(r->post[i]);
  ocg_work_free(&r->work);
  free(r);
}

ocg_result *ocg_result_new(void) {
  size_t i;
  ocg_result *r = calloc(1, sizeof *r);
  if (!r) return NULL;
  if (ocg_work_new(&r->work) != OCG_OK) {
    free(r);
    return NULL;
  }
  for (i = 0; i < OCG_N_POST; ++i) {
    const casadi_int *sp = ocg_f_post.sparsity_out((casadi_int)i);
    r->post_width[i] = (size_t)sp[0];
    r->post_count[i] = (size_t)sp[1];
    r->post[i] = calloc(r->post_width[i] * r->post_count[i] + 1, sizeof(double));
    if (!r->post[i]) {
      ocg_result_free(r);
      return NULL;
    }
  }
  return r;
}

int ocg_pack(const double *values, size_t n_values, double *p, size_t n_p, int *bad_block) {
  double bad[OCG_N_BLOCKS + 1];
  ocg_work wk;
  int code, i;
  if (!values || !p) return OCG_ERR_NULL;
  if (n_values != OCG_NV || n_p != OCG_NP) return OCG_ERR_LENGTH;
  if (!ocg_all_finite(values, n_values)) return OCG_ERR_NOT_FINITE;
  if (ocg_work_new(&wk) != OCG_OK) return OCG_ERR_MEMORY;
  {
    const double *in[] = {values};
    double *out[] = {p, bad};
    code = ocg_call(&ocg_f_pack, in, 1, out, 2, &wk);
  }
  ocg_work_free(&wk);
  if (code != OCG_OK) return code;
  for (i = 0; i < OCG_N_BLOCKS; ++i) {
    if (bad[i] != 0.0) {
      if (bad_block) *bad_block = i;
      return OCG_ERR_DOMAIN;
    }
  }
  return OCG_OK;
}

static double ocg_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The solve of ocg_solve and ocg_solve_warm: from x0 (NULL: the geodesic guess), with
 * multipliers when dual is set (r->lam_g_start, r->lam_x_start). */
static int ocg_run(const double *p, size_t n_p, const double *x0, size_t n_x0, int dual,
                   ocg_result *r) {
  double f = NAN, t0;
  size_t i;
  int code;
  if (!p || !r) return OCG_ERR_NULL;
  if (n_p != OCG_NP) return OCG_ERR_LENGTH;
  if (!ocg_all_finite(p, n_p)) return OCG_ERR_NOT_FINITE;
  if (!(p[OCG_P_T] > 0.0)) return OCG_ERR_DOMAIN;
  if (x0 && n_x0 != OCG_NX) return OCG_ERR_LENGTH;
  if (x0 && !ocg_all_finite(x0, n_x0)) return OCG_ERR_NOT_FINITE;
  r->solved = 0;
  memmove(r->p, p, sizeof r->p); /* p and x0 may point into r (OCG_P, OCG_X) */
  if (x0) {
    memmove(r->x_start, x0, sizeof r->x_start);
  } else {
    const double *in[] = {r->p};
    double *out[] = {r->x_start};
    code = ocg_call(&ocg_f_guess, in, 1, out, 1, &r->work);
    if (code != OCG_OK) return code;
  }
  ocg_last.iterations = 0;
  ocg_last.status = Internal_Error;
  t0 = ocg_now();
  {
    const double *in[] = {r->x_start, r->p, r->lam_g_start, r->lam_x_start};
    double *out[] = {r->x_ipopt, &f, r->g, r->lam_g, r->lam_x};
    code = dual ? ocg_call(&ocg_f_nlpsol_warm, in, 4, out, 5, &r->work)
                : ocg_call(&ocg_f_nlpsol, in, 2, out, 5, &r->work);
  }
  r->seconds = ocg_now() - t0;
  if (code != OCG_OK) return code;
  r->status = (int)ocg_last.status;
  /* as the Python API: IPOPT reports no iterations when it stops before the first */
  r->iterations = r->status == Not_Enough_Degrees_Of_Freedom ? 0 : ocg_last.iterations;
  r->cost = f;
  r->warm = x0 != NULL;
  r->residual = 0.0;
  for (i = 0; i < OCG_NG; ++i)
    if (fabs(r->g[i]) > r->residual || isnan(r->g[i])) r->residual = fabs(r->g[i]);
  {
    const double *in[] = {r->x_ipopt, r->p, r->lam_g};
    code = ocg_call(&ocg_f_post, in, 3, r->post, OCG_N_POST, &r->work);
  }
  if (code != OCG_OK) return code;
  {
    const double *in[] = {r->x_ipopt, r->p, r->lam_g};
    double *out[] = {r->checks, r->figures};
    code = ocg_call(&ocg_f_verify, in, 3, out, 2, &r->work);
  }
  if (code != OCG_OK) return code;
  /* success means verified, as in Python: the requested tolerance reached, and every check
   * of the solution and of its plan replayed through the continuous problem within its
   * tolerance (a NaN ratio, a problem nothing can replay, fails) */
  r->success = r->status == Solve_Succeeded;
  for (i = 0; i < OCG_N_CHECKS; ++i)
    if (!(r->checks[i] <= 1.0)) r->success = 0;
  r->solved = 1;
  return r->success ? OCG_OK : OCG_NOT_SOLVED;
}

int ocg_solve(const double *p, size_t n_p, const double *x0, size_t n_x0, ocg_result *r) {
  return ocg_run(p, n_p, x0, n_x0, 0, r);
}

int ocg_solve_warm(const double *p, size_t n_p, const ocg_result *from, ocg_result *r) {
  double x[OCG_NX];
  if (!p || !from || !r) return OCG_ERR_NULL;
  if (!from->solved) return OCG_ERR_UNSOLVED;
  if (n_p != OCG_NP) return OCG_ERR_LENGTH; /* checked before r changes */
  memcpy(x, from->x_ipopt, sizeof x);
  memmove(r->lam_g_start, from->lam_g, sizeof r->lam_g_start);
  memmove(r->lam_x_start, from->lam_x, sizeof r->lam_x_start);
  return ocg_run(p, n_p, x, OCG_NX, 1, r);
}

int ocg_status(const ocg_result *r) { return r && r->solved ? r->status : Internal_Error; }
const char *ocg_status_name(const ocg_result *r) {
  return r && r->solved ? ocg_ipopt_status_name(r->status) : "";
}
int ocg_success(const ocg_result *r) { return r && r->solved && r->success; }
double ocg_cost(const ocg_result *r) { return r && r->solved ? r->cost : NAN; }
int ocg_iterations(const ocg_result *r) { return r && r->solved ? r->iterations : 0; }
double ocg_solve_seconds(const ocg_result *r) { return r && r->solved ? r->seconds : NAN; }

const double *ocg_output(const ocg_result *r, enum ocg_output which, size_t *rows,
                         size_t *cols) {
  size_t n_rows = 0, n_cols = 0;
  const double *data = NULL;
  if (r && r->solved) {
    int k = ocg_post_index(which);
    if (k >= 0 && k < OCG_N_POST) {
      n_rows = r->post_count[k];
      n_cols = r->post_width[k];
      data = r->post[k];
    } else if (which == OCG_P) {
      n_rows = 1, n_cols = OCG_NP, data = r->p;
    } else if (which == OCG_LAM_G) {
      n_rows = 1, n_cols = OCG_NG, data = r->lam_g;
    } else if (which == OCG_LAM_X) {
      n_rows = 1, n_cols = OCG_NX, data = r->lam_x;
    }
  }
  if (rows) *rows = data ? n_rows : 0;
  if (cols) *cols = data ? n_cols : 0;
  return data;
}

/* ------------------------------------------------------------------ JSON */

static void ocg_json_number(FILE *out, double v) {
  if (isfinite(v))
    fprintf(out, "%.17g", v);
  else
    fputs("null", out); /* as the Python API: NaN and Inf become null */
}

static void ocg_json_string(FILE *out, const char *s) {
  fputc('"', out);
  for (; *s; ++s) {
    if (*s == '"' || *s == '\\')
      fprintf(out, "\\%c", *s);
    else if ((unsigned char)*s < 0x20)
      fprintf(out, "\\u%04x", (unsigned)(unsigned char)*s);
    else
      fputc(*s, out);
  }
  fputc('"', out);
}

static void ocg_json_vector(FILE *out, const double *v, size_t n) {
  size_t i;
  fputc('[', out);
  for (i = 0; i < n; ++i) {
    if (i) fputs(", ", out);
    ocg_json_number(out, v[i]);
  }
  fputc(']', out);
}

/* rows x cols row-major: a list of rows */
static void ocg_json_matrix(FILE *out, const double *v, size_t rows, size_t cols) {
  size_t k;
  fputc('[', out);
  for (k = 0; k < rows; ++k) {
    if (k) fputs(", ", out);
    ocg_json_vector(out, v + k * cols, cols);
  }
  fputc(']', out);
}

/* pieces x (k m) row-major as PPoly's c[k][pieces][m] */
static void ocg_json_coefficients(FILE *out, const double *v, size_t pieces, size_t width,
                                  size_t m) {
  size_t i, j, k = m ? width / m : 0;
  fputc('[', out);
  for (i = 0; i < k; ++i) {
    if (i) fputs(", ", out);
    fputc('[', out);
    for (j = 0; j < pieces; ++j) {
      if (j) fputs(", ", out);
      ocg_json_vector(out, v + j * width + i * m, m);
    }
    fputc(']', out);
  }
  fputc(']', out);
}

static void ocg_json_names(FILE *out, const char *const *names, int n) {
  int i;
  fputc('[', out);
  for (i = 0; i < n; ++i) {
    if (i) fputs(", ", out);
    ocg_json_string(out, names[i]);
  }
  fputc(']', out);
}

/* One entry per field: over the times, each field's slice of the row (a matrix if rows > 0) */
static void ocg_json_fields(FILE *out, const ocg_result *r, enum ocg_output times,
                            enum ocg_output which, const ocg_field *fields, int n_fields) {
  size_t n_t, width, k, one;
  const double *t = ocg_output(r, times, &n_t, &one);
  const double *v = ocg_output(r, which, &n_t, &width);
  int i;
  fputs("{\"t\": ", out);
  ocg_json_vector(out, t, n_t);
  for (i = 0; i < n_fields; ++i) {
    const ocg_field *f = &fields[i];
    fputs(", ", out);
    ocg_json_string(out, f->name);
    fputs(": [", out);
    for (k = 0; k < n_t; ++k) {
      const double *row = v + k * width + f->offset;
      if (k) fputs(", ", out);
      if (f->rows > 0)
        ocg_json_matrix(out, row, (size_t)f->rows, (size_t)f->cols);
      else
        ocg_json_vector(out, row, (size_t)f->cols);
    }
    fputc(']', out);
  }
  fputc('}', out);
}

int ocg_write_json(const ocg_result *r, FILE *out) {
  size_t rows, cols, one;
  const double *v;
  int i;
  if (!r || !out || !r->solved) return -1;
  fputs("{\n \"problem\": ", out);
  ocg_json_string(out, OCG_PROBLEM);
  fprintf(out, ",\n \"success\": %s,\n \"status\": ", r->success ? "true" : "false");
  ocg_json_string(out, ocg_status_name(r));
  fprintf(out, ",\n \"N\": %d,\n \"T\": ", OCG_N);
  v = ocg_output(r, OCG_T, &rows, &one); /* the last node time: the solved horizon */
  ocg_json_number(out, rows ? v[rows - 1] : r->p[OCG_P_T]);
  fputs(",\n \"cost\": ", out);
  ocg_json_number(out, r->cost);
  fprintf(out, ",\n \"stats\": {\"iterations\": %d, \"solve_seconds\": ", r->iterations);
  ocg_json_number(out, r->seconds);
  fputs(", \"backend\": ", out);
  ocg_json_string(out, OCG_BACKEND);
  fputs("},\n \"discretization\": {\"scheme\": ", out);
  ocg_json_string(out, OCG_SCHEME);
  fputs(", \"retraction\": ", out);
  ocg_json_string(out, OCG_RETRACTION);
  fputs(", \"rule\": ", out);
  ocg_json_string(out, OCG_RULE);
  fprintf(out, ", \"order\": %d, \"start\": ", OCG_ORDER);
  ocg_json_string(out, r->warm ? "warm start" : OCG_GUESS_LABEL);
  fputs("},\n \"parameters\": {", out);
  for (i = 0; i < OCG_N_PARAMETER_FIELDS; ++i) {
    if (i) fputs(", ", out);
    ocg_json_string(out, ocg_parameter_fields[i].name);
    fputs(": ", out);
    ocg_json_vector(out, r->p + ocg_parameter_fields[i].offset,
                    (size_t)ocg_parameter_fields[i].cols);
  }
  fputs("},\n \"controls\": {\"t\": ", out);
  v = ocg_output(r, OCG_CONTROL_T, &rows, &one);
  ocg_json_vector(out, v, rows);
  fputs(", \"u\": ", out);
  v = ocg_output(r, OCG_CONTROLS, &rows, &cols);
  ocg_json_matrix(out, v, rows, cols);
  fputs(", \"names\": ", out);
  ocg_json_names(out, ocg_control_names, OCG_NU);
  fputs(", \"ppoly\": {\"x\": ", out);
  v = ocg_output(r, OCG_CONTROL_BREAKS, &rows, &one);
  ocg_json_vector(out, v, rows);
  fputs(", \"c\": ", out);
  v = ocg_output(r, OCG_CONTROL_COEFFICIENTS, &rows, &cols);
  ocg_json_coefficients(out, v, rows, cols, (size_t)OCG_NU);
  fputs("}},\n \"states\": ", out);
  ocg_json_fields(out, r, OCG_T, OCG_STATES, ocg_state_fields, OCG_N_STATE_FIELDS);
  fputs(",\n \"manifolds\": " OCG_MANIFOLDS_JSON ",\n \"labels\": " OCG_LABELS_JSON
        ",\n \"velocities\": ", out);
  ocg_json_fields(out, r, OCG_VELOCITY_T, OCG_VELOCITIES, ocg_velocity_fields,
                  OCG_N_VELOCITY_FIELDS);
  fputs(",\n \"multipliers\": {\"t\": ", out);
  v = ocg_output(r, OCG_MULTIPLIER_T, &rows, &one);
  ocg_json_vector(out, v, rows);
  fputs(", \"names\": ", out);
  ocg_json_names(out, ocg_multiplier_names, OCG_N_MULTIPLIER_NAMES);
  v = ocg_output(r, OCG_MULTIPLIERS, &rows, &cols);
  if (cols > 0) {
    fputs(", \"Phi\": ", out);
    ocg_json_matrix(out, v, rows, cols);
  }
  v = ocg_output(r, OCG_FINAL_MULTIPLIERS, &rows, &cols);
  if (cols > 0) {
    fputs(", \"final\": ", out);
    ocg_json_vector(out, v, cols);
  }
  fputs("},\n \"diagnostics\": {\"nlp_constraint_residual_max\": ", out);
  ocg_json_number(out, r->residual);
  for (i = 0; i < OCG_N_FIGURES; ++i) {
    fputs(", ", out);
    ocg_json_string(out, ocg_figure_names[i]);
    fputs(": ", out);
    ocg_json_number(out, r->figures[i]);
  }
  fprintf(out, ", \"verdict\": {\"verified\": %s, \"checks\": {",
          r->success ? "true" : "false");
  for (i = 0; i < OCG_N_CHECKS; ++i) {
    if (i) fputs(", ", out);
    ocg_json_string(out, ocg_check_names[i]);
    fputs(": ", out);
    ocg_json_number(out, r->checks[i]);
  }
  fputs("}, \"failures\": [", out);
  {
    int first = 1;
    if (r->status != Solve_Succeeded) {
      fputs("\"the solver stopped at ", out);
      fputs(ocg_status_name(r), out);
      fputs(", not at the requested tolerance\"", out);
      first = 0;
    }
    for (i = 0; i < OCG_N_CHECKS; ++i) {
      if (r->checks[i] <= 1.0) continue;
      if (!first) fputs(", ", out);
      ocg_json_string(out, ocg_check_failures[i]);
      first = 0;
    }
  }
  fputs("]}},\n \"nlp\": {\"x\": ", out);
  v = ocg_output(r, OCG_X, &rows, &cols);
  ocg_json_vector(out, v, cols);
  fputs(", \"p\": ", out);
  ocg_json_vector(out, r->p, OCG_NP);
  fputs("}\n}\n", out);
  return ferror(out) ? -1 : 0;
}
