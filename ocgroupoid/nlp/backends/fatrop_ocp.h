/* fatrop's own C interface driven by the stage form's Functions (fatrop_ocp.c): the problem
 * (constant over solves), one solve's inputs and outputs, and the context between solves.
 * Python fills the structs through ctypes (fatrop_ocp.py mirrors them); the exported C solver
 * includes this header (ocgroupoid/export/fatrop.py). */
#ifndef OCG_FATROP_OCP_H
#define OCG_FATROP_OCP_H

typedef long long ocg_cint; /* CasADi's casadi_int in generated code */
typedef int (*ocg_eval)(const double **arg, double **res, ocg_cint *iw, double *w,
                        int mem);
typedef int (*ocg_work)(ocg_cint *sz_arg, ocg_cint *sz_res, ocg_cint *sz_iw,
                        ocg_cint *sz_w);
typedef void (*ocg_buffer_eval)(void *buffer);

enum { OCG_F, OCG_G, OCG_GRAD_F, OCG_JAC_G, OCG_HESS_L, OCG_NFUN };
enum { OCG_MAX_IN = 4, OCG_MAX_OUT = 2 }; /* nlp_hess_l's inputs, nlp_jac_g's outputs */

/* The problem, constant over solves (filled by Python through ctypes; the exported C
 * solver's is a table of its own). */
struct ocg_problem {
  int K;                         /* stages 0..K */
  const int *nx, *nu, *ng;       /* K + 1 each */
  const int *col;                /* first column of stage k (x_k, then u_k) */
  const int *row_ab, *row_cd;    /* first gap row into x_{k+1}; first row of stage k */
  const int *ab_off, *cd_off, *rsq_off; /* offsets of the dense stage blocks */
  int nz, n_rows, nnz_a, nnz_h, n_ab, n_cd, n_rsq;
  const int *a_kind, *a_index;   /* per Jacobian nonzero: block kind and index in it */
  const int *h_index;            /* per Hessian nonzero: index in RSQ, or -1 */
  ocg_eval eval[OCG_NFUN];       /* compiled code, or NULL: */
  ocg_work work[OCG_NFUN];
  ocg_buffer_eval buffer_eval;   /* casadi::_function_buffer_eval */
  void *buffer[OCG_NFUN];        /* each Function's FunctionBuffer, bound to: */
  double *buffer_in[OCG_NFUN][OCG_MAX_IN], *buffer_out[OCG_NFUN][OCG_MAX_OUT];
  int buffer_n_in[OCG_NFUN][OCG_MAX_IN]; /* the inputs' nonzeros */
  int n_options;
  const char **option_names;
  const int *option_kinds;       /* 0 double, 1 int, 2 bool, 3 string */
  const double *option_values;
  const char **option_strings;
  int max_iter;                  /* the max_iter among the options (restored after a stop) */
};

/* One solve's inputs and outputs. */
struct ocg_solve {
  const double *z0, *q, *lbz, *ubz, *lbg, *ubg;
  double *z, *g, *lam_g, *lam_x, *f;
  int iterations, return_flag, status, bad_structure;
  double seconds[OCG_NFUN];      /* each Function's evaluations during fatrop's call */
  int calls[OCG_NFUN];
  double solve_seconds;          /* fatrop's call, evaluations included */
  /* a guarded solve (fatrop_guard.c): left after `limit` seconds, at the `nan_limit`-th
   * non-finite evaluation, on Ctrl-C (watch_sigint) or when check() says stop (asked every
   * `every` seconds); `left` says why (OCG_LEFT_*), `nans` counts the evaluations */
  int guarded, nan_limit, watch_sigint, left, nans;
  double limit, every;
  int (*check)(void);
  /* fatrop's iteration callback, or NULL: asked at the start of iteration k (k done) with
   * the objective and the infeasibility at the iterate; a nonzero answer stops fatrop at
   * the end of that iteration (max_iter set to k; `stopped_at` = k, else -1) */
  int (*iteration)(int k, double objective, double infeasibility);
  int stopped_at;
};

/* What persists between solves (fatrop_ocp.c). */
struct ocg_context;

/* the context of problem p (which must outlive it), or NULL when memory ran out */
struct ocg_context *ocg_context_new(const struct ocg_problem *p);
void ocg_context_free(struct ocg_context *c);
/* One solve from s->z0 (fatrop_ocp.c). */
void ocg_fatrop_solve(struct ocg_context *c, struct ocg_solve *s);

#endif
