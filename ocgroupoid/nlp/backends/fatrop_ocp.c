/* fatrop's own C interface (fatrop/ocp/OCPCInterface.h, shipped with CasADi) driven by the
 * stage form's Functions: ocgroupoid/nlp/backends/fatrop_ocp.py builds the maps. The
 * Functions are compiled code (their entry points in eval and work), or, where eval[i] is
 * NULL, CasADi's own evaluation of them: a FunctionBuffer each (casadi/core/function.hpp),
 * its inputs and outputs bound to arrays of its own, evaluated by buffer_eval
 * (casadi::_function_buffer_eval); the driver copies the arguments in and the results out.
 *
 * The callbacks are those of CasADi's fatrop interface (casadi/interfaces/fatrop/
 * fatrop_runtime.hpp): the five NLP Functions are evaluated whole, their Jacobian and
 * Hessian scattered into dense stage blocks, and fatrop reads the blocks stage by stage.
 * What differs is where the scatter maps come from: CasADi's interface derives its block
 * patterns by assigning the stages' blocks one at a time into a sparse matrix (time N^2 as
 * it is built); here they are one index per nonzero, computed in Python in time linear in N.
 *
 * Rows and variables are split per solve, as CasADi does: a row or variable with equal
 * bounds is an equality of its stage, one with a finite bound an inequality, a free one
 * neither. Gap rows read x_{k+1} - F_k(x_k, u_k) with coefficient +1 on x_{k+1}.
 *
 * A solve also reports where its time went: the seconds and calls of each Function's
 * evaluations during fatrop's call, and the seconds of the call itself.
 */
#define _GNU_SOURCE /* clock_gettime; and sigsetjmp, timers (fatrop_guard.h) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <blasfeo.h>
#include "fatrop/ocp/OCPCInterface.h"
#include "fatrop_guard.h"
#include "fatrop_ocp.h"

/* fatrop's callbacks take arguments the driver has no use for (parameters it keeps itself) */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif

enum { OCG_AB = 0, OCG_CD = 1, OCG_EYE = 2 };

struct ocg_data {
  const struct ocg_problem *p;
  struct ocg_solve *s;
  double *x, *lam, *a, *h, *g, *AB, *CD, *RSQ;
  int *a_eq, *a_ineq, *x_eq, *x_ineq, *a_eq_idx, *a_ineq_idx, *x_eq_idx, *x_ineq_idx;
  const double **arg;
  double **res;
  double seconds[OCG_NFUN];      /* this solve's evaluations so far */
  int calls[OCG_NFUN];
  ocg_cint *iw;
  double *w;
  struct ocg_guard *guard;       /* this solve's guard, or NULL: unguarded */
  struct FatropOcpCSolver *solver; /* this solve's (for a stop asked by s->iteration) */
  /* for s->iteration: the infeasibility at xg, the point of the last Jacobian (fatrop's
   * at each iterate; has_g: one since the solve began), reused at the iterate */
  double *xg, infeasibility_at;
  int has_g;
  struct FatropOcpCInterface ocp;
};

static const char *OCG_NAMES[OCG_NFUN] = {"nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g",
                                          "nlp_hess_l"};

double ocg_now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Evaluate Function i, counting the call and its seconds; a non-finite output is counted by
 * the guard (a guarded solve), else reported on stderr as CasADi's oracle reports it ("NaN
 * detected"), which the helper process counts; the values are used as they are (as CasADi's
 * interface does: fatrop's line search backs off). A guarded solve may be left here, before
 * the evaluation (ocg_guard_poll) or after it (ocg_guard_nan). */
static void ocg_call(struct ocg_data *d, int i, const double **in, int n_in, double **out,
                     const int *n_out, int n_res) {
  int j, k;
  double t0;
  ocg_guard_poll(d->guard);
  for (j = 0; j < n_in; ++j) d->arg[j] = in[j];
  for (j = 0; j < n_res; ++j) d->res[j] = out[j];
  t0 = ocg_now();
  if (d->p->eval[i]) {
    d->p->eval[i](d->arg, d->res, d->iw, d->w, 0);
  } else {
    for (j = 0; j < n_in; ++j)
      memcpy(d->p->buffer_in[i][j], in[j], sizeof(double) * (size_t)d->p->buffer_n_in[i][j]);
    d->p->buffer_eval(d->p->buffer[i]);
    for (j = 0; j < n_res; ++j)
      memcpy(out[j], d->p->buffer_out[i][j], sizeof(double) * (size_t)n_out[j]);
  }
  d->seconds[i] += ocg_now() - t0;
  ++d->calls[i];
  for (j = 0; j < n_res; ++j) {
    for (k = 0; k < n_out[j]; ++k) {
      if (!isfinite(out[j][k])) {
        if (d->guard) ocg_guard_nan(d->guard);
        else fprintf(stderr, "NaN detected for output %d of %s, at nonzero %d.\n", j,
                     OCG_NAMES[i], k);
        break;
      }
    }
  }
}

/* Function i (f, g, the gradient of f or the Jacobian of g) at the point x with this
 * solve's parameters: its first n_res outputs into out (of n_out nonzeros each). */
static void ocg_at(struct ocg_data *d, int i, const double *x, double **out, const int *n_out,
                   int n_res) {
  const double *in[2];
  in[0] = x;
  in[1] = d->s->q;
  ocg_call(d, i, in, 2, out, n_out, n_res);
}

/* primal_data holds per stage [u_k, x_k]; z holds [x_k, u_k] */
static void ocg_read_primal(const struct ocg_problem *p, const double *primal, double *z,
                            const struct FatropOcpCDims *s) {
  int k;
  for (k = 0; k < s->K; ++k) {
    memcpy(z + p->col[k] + p->nx[k], primal + s->ux_offs[k], sizeof(double) * p->nu[k]);
    memcpy(z + p->col[k], primal + s->ux_offs[k] + p->nu[k], sizeof(double) * p->nx[k]);
  }
}

static void ocg_write_primal(const struct ocg_problem *p, const double *z, double *primal,
                             const struct FatropOcpCDims *s) {
  int k;
  for (k = 0; k < s->K; ++k) {
    memcpy(primal + s->ux_offs[k], z + p->col[k] + p->nx[k], sizeof(double) * p->nu[k]);
    memcpy(primal + s->ux_offs[k] + p->nu[k], z + p->col[k], sizeof(double) * p->nx[k]);
  }
}

/* the largest violation of a row's or a variable's bounds at d->x, its rows in d->g (the
 * scaled rows fatrop solves) */
static double ocg_infeasibility(const struct ocg_data *d) {
  const struct ocg_problem *p = d->p;
  const struct ocg_solve *s = d->s;
  double worst = 0.0, v;
  int i;
  for (i = 0; i < p->n_rows; ++i) {
    v = fmax(s->lbg[i] - d->g[i], d->g[i] - s->ubg[i]);
    if (v > worst) worst = v;
  }
  for (i = 0; i < p->nz; ++i) {
    v = fmax(s->lbz[i] - d->x[i], d->x[i] - s->ubz[i]);
    if (v > worst) worst = v;
  }
  return worst;
}

/* for the iteration callback: the infeasibility at d->x, its rows just evaluated into d->g
 * (at each Jacobian: once an iterate; a copy of each trial point would cost more, measured) */
static void ocg_remember_g(struct ocg_data *d) {
  if (!d->s->iteration) return;
  memcpy(d->xg, d->x, sizeof(double) * (size_t)d->p->nz);
  d->infeasibility_at = ocg_infeasibility(d);
  d->has_g = 1;
}

static fatrop_int ocg_full_constr_jac(const double *primal, const double *sp, const double *gp,
                                      struct blasfeo_dmat *BAbt, struct blasfeo_dmat *Ggt,
                                      struct blasfeo_dmat *Ggt_ineq,
                                      const struct FatropOcpCDims *s, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  double *out[2];
  int n_out[2], i;
  ocg_read_primal(p, primal, d->x, s);
  out[0] = d->g; out[1] = d->a;
  n_out[0] = p->n_rows; n_out[1] = p->nnz_a;
  ocg_at(d, OCG_JAC_G, d->x, out, n_out, 2);
  ocg_remember_g(d);
  for (i = 0; i < p->nnz_a; ++i) {
    switch (p->a_kind[i]) {
      case OCG_AB: d->AB[p->a_index[i]] = -d->a[i]; break;
      case OCG_CD: d->CD[p->a_index[i]] = d->a[i]; break;
      default: if (d->a[i] != 1.0) d->s->bad_structure = 1;
    }
  }
  return 0;
}

static fatrop_int ocg_full_contr_viol(const double *primal, const double *sp, const double *gp,
                                      double *res, const struct FatropOcpCDims *s, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  int i, k, column;
  ocg_read_primal(p, primal, d->x, s);
  ocg_at(d, OCG_G, d->x, &d->g, &p->n_rows, 1);
  for (k = 0; k < s->K; ++k) {
    column = 0;
    for (i = d->a_ineq_idx[k]; i < d->a_ineq_idx[k + 1]; ++i)
      res[s->g_ineq_offs[k] + column++] = d->g[d->a_ineq[i]];
    for (i = d->x_ineq_idx[k]; i < d->x_ineq_idx[k + 1]; ++i)
      res[s->g_ineq_offs[k] + column++] = d->x[d->x_ineq[i]];
    column = 0;
    for (i = d->a_eq_idx[k]; i < d->a_eq_idx[k + 1]; ++i)
      res[s->g_offs[k] + column++] = d->g[d->a_eq[i]] - d->s->lbg[d->a_eq[i]];
    for (i = d->x_eq_idx[k]; i < d->x_eq_idx[k + 1]; ++i)
      res[s->g_offs[k] + column++] = d->x[d->x_eq[i]] - d->s->lbz[d->x_eq[i]];
  }
  for (k = 0; k < s->K - 1; ++k)
    for (i = 0; i < p->nx[k + 1]; ++i)
      res[s->dyn_eq_offs[k] + i] = d->s->lbg[p->row_ab[k] + i] - d->g[p->row_ab[k] + i];
  return 1; /* done: fatrop evaluates no stage */
}

static fatrop_int ocg_full_obj_grad(double scale, const double *primal, const double *sp,
                                    const double *gp, double *res,
                                    const struct FatropOcpCDims *s, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  int i;
  ocg_read_primal(p, primal, d->x, s);
  ocg_at(d, OCG_GRAD_F, d->x, &d->g, &p->nz, 1);
  ocg_write_primal(p, d->g, res, s);
  for (i = 0; i < p->nz; ++i) res[i] *= scale;
  return 1;
}

static fatrop_int ocg_full_obj(double scale, const double *primal, const double *sp,
                               const double *gp, double *res, const struct FatropOcpCDims *s,
                               void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const int one = 1;
  ocg_read_primal(d->p, primal, d->x, s);
  ocg_at(d, OCG_F, d->x, &res, &one, 1);
  *res *= scale;
  return 1;
}

static fatrop_int ocg_full_lag_hess(double scale, const double *primal, const double *lam,
                                    const double *sp, const double *gp,
                                    struct blasfeo_dmat *res, const struct FatropOcpCDims *s,
                                    void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  const double *in[4];
  double *out[2];
  int n_out[2], i, k, column;
  const int one = 1;
  double objective;
  ocg_read_primal(p, primal, d->x, s);
  /* the Hessian is evaluated once an iteration, at its iterate: the iteration callback's turn
   * (the objective evaluated there for it, and the rows: the last Jacobian's, else evaluated) */
  k = d->calls[OCG_HESS_L];
  if (d->s->iteration && d->s->stopped_at < 0) {
    double *f = &objective;
    ocg_at(d, OCG_F, d->x, &f, &one, 1);
    if (!(d->has_g && memcmp(d->xg, d->x, sizeof(double) * (size_t)p->nz) == 0)) {
      ocg_at(d, OCG_G, d->x, &d->g, &p->n_rows, 1);
      ocg_remember_g(d);
    }
    if (d->s->iteration(k, objective, d->infeasibility_at)) {
      fatrop_ocp_c_set_option_int(d->solver, "max_iter", k);
      d->s->stopped_at = k;
    }
  }
  for (k = 0; k < s->K; ++k) {
    column = 0;
    for (i = d->a_ineq_idx[k]; i < d->a_ineq_idx[k + 1]; ++i)
      d->lam[d->a_ineq[i]] = lam[s->g_ineq_offs[k] + column++];
    column = 0;
    for (i = d->a_eq_idx[k]; i < d->a_eq_idx[k + 1]; ++i)
      d->lam[d->a_eq[i]] = lam[s->g_offs[k] + column++];
  }
  for (k = 0; k < s->K - 1; ++k)
    for (i = 0; i < p->nx[k + 1]; ++i) d->lam[p->row_ab[k] + i] = -lam[s->dyn_eq_offs[k] + i];
  in[0] = d->x; in[1] = d->s->q; in[2] = &scale; in[3] = d->lam;
  out[0] = d->g; out[1] = d->h;
  n_out[0] = p->nz; n_out[1] = p->nnz_h;
  ocg_call(d, OCG_HESS_L, in, 4, out, n_out, 2);
  for (i = 0; i < p->nnz_h; ++i)
    if (p->h_index[i] >= 0) d->RSQ[p->h_index[i]] = d->h[i];
  /* fatrop's Lagrangian reads lam_dyn (F(x_k, u_k)) without x_{k+1}; and the bounds */
  for (k = 0; k < s->K - 1; ++k)
    for (i = 0; i < p->nx[k + 1]; ++i) d->g[p->col[k + 1] + i] += lam[s->dyn_eq_offs[k] + i];
  for (k = 0; k < s->K; ++k) {
    column = d->a_ineq_idx[k + 1] - d->a_ineq_idx[k];
    for (i = d->x_ineq_idx[k]; i < d->x_ineq_idx[k + 1]; ++i)
      d->g[d->x_ineq[i]] += lam[s->g_ineq_offs[k] + column++];
    column = d->a_eq_idx[k + 1] - d->a_eq_idx[k];
    for (i = d->x_eq_idx[k]; i < d->x_eq_idx[k + 1]; ++i)
      d->g[d->x_eq[i]] += lam[s->g_offs[k] + column++];
  }
  return 0;
}

static fatrop_int ocg_BAbt(const double *xn, const double *u, const double *x, const double *sp,
                           const double *gp, struct blasfeo_dmat *res, const fatrop_int k,
                           void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  int i, nxn = p->nx[k + 1];
  const double *ab = d->AB + p->ab_off[k];
  blasfeo_pack_tran_dmat(nxn, p->nx[k], (double *)ab, nxn, res, p->nu[k], 0);
  blasfeo_pack_tran_dmat(nxn, p->nu[k], (double *)ab + p->nx[k] * nxn, nxn, res, 0, 0);
  for (i = 0; i < nxn; ++i)
    BLASFEO_DMATEL(res, p->nx[k] + p->nu[k], i) =
        d->s->lbg[p->row_ab[k] + i] - d->g[p->row_ab[k] + i];
  return 0;
}

static fatrop_int ocg_RSQrqt(const double *scale, const double *u, const double *x,
                             const double *lam_dyn, const double *lam_eq,
                             const double *lam_ineq, const double *sp, const double *gp,
                             struct blasfeo_dmat *res, const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  const struct ocg_problem *p = d->p;
  int nx = p->nx[k], nu = p->nu[k], n = nx + nu;
  double *rsq = d->RSQ + p->rsq_off[k];
  blasfeo_pack_dmat(nx, nx, rsq, n, res, nu, nu);
  blasfeo_pack_dmat(nu, nu, rsq + nx * n + nx, n, res, 0, 0);
  blasfeo_pack_dmat(nu, nx, rsq + nx, n, res, 0, nu);
  blasfeo_pack_dmat(nx, nu, rsq + nx * n, n, res, nu, 0);
  blasfeo_pack_dmat(1, nx, d->g + p->col[k], 1, res, n, nu);
  blasfeo_pack_dmat(1, nu, d->g + p->col[k] + nx, 1, res, n, 0);
  return 0;
}

/* the rows of one stage's constraints (eq: g - lb, ineq: g) and its bounded variables */
static void ocg_pack_rows(struct ocg_data *d, const int *rows, int start, int stop,
                          const int *vars, int vstart, int vstop, int equality,
                          struct blasfeo_dmat *res, int k) {
  const struct ocg_problem *p = d->p;
  int nx = p->nx[k], nu = p->nu[k], rows_k = p->ng[k], i, j, column = 0;
  const double *cd = d->CD + p->cd_off[k];
  blasfeo_dgese(nx + nu + 1, (stop - start) + (vstop - vstart), 0.0, res, 0, 0);
  for (i = start; i < stop; ++i) {
    int r = rows[i] - p->row_cd[k];
    blasfeo_pack_tran_dmat(1, nx, (double *)cd + r, rows_k, res, nu, column);
    blasfeo_pack_tran_dmat(1, nu, (double *)cd + r + nx * rows_k, rows_k, res, 0, column);
    BLASFEO_DMATEL(res, nx + nu, column) =
        d->g[rows[i]] - (equality ? d->s->lbg[rows[i]] : 0.0);
    column++;
  }
  for (i = vstart; i < vstop; ++i) {
    j = vars[i] - p->col[k];
    j = j >= nx ? j - nx : j + nu;
    BLASFEO_DMATEL(res, j, column) = 1.0;
    BLASFEO_DMATEL(res, nx + nu, column) =
        d->x[vars[i]] - (equality ? d->s->lbz[vars[i]] : 0.0);
    column++;
  }
}

static fatrop_int ocg_Ggt(const double *u, const double *x, const double *sp, const double *gp,
                          struct blasfeo_dmat *res, const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  ocg_pack_rows(d, d->a_eq, d->a_eq_idx[k], d->a_eq_idx[k + 1], d->x_eq, d->x_eq_idx[k],
                d->x_eq_idx[k + 1], 1, res, k);
  return 0;
}

static fatrop_int ocg_Ggt_ineq(const double *u, const double *x, const double *sp,
                               const double *gp, struct blasfeo_dmat *res, const fatrop_int k,
                               void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  ocg_pack_rows(d, d->a_ineq, d->a_ineq_idx[k], d->a_ineq_idx[k + 1], d->x_ineq,
                d->x_ineq_idx[k], d->x_ineq_idx[k + 1], 0, res, k);
  return 0;
}

static fatrop_int ocg_get_nx(const fatrop_int k, void *user) {
  const struct ocg_problem *p = ((struct ocg_data *)user)->p;
  return k == p->K + 1 ? p->nx[k - 1] : p->nx[k];
}

static fatrop_int ocg_get_nu(const fatrop_int k, void *user) {
  return ((struct ocg_data *)user)->p->nu[k];
}

static fatrop_int ocg_get_ng(const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  return d->a_eq_idx[k + 1] - d->a_eq_idx[k] + d->x_eq_idx[k + 1] - d->x_eq_idx[k];
}

static fatrop_int ocg_get_ng_ineq(const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  return d->a_ineq_idx[k + 1] - d->a_ineq_idx[k] + d->x_ineq_idx[k + 1] - d->x_ineq_idx[k];
}

static fatrop_int ocg_horizon(void *user) { return ((struct ocg_data *)user)->p->K + 1; }

static fatrop_int ocg_bounds(double *lower, double *upper, const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  int i, column = 0;
  for (i = d->a_ineq_idx[k]; i < d->a_ineq_idx[k + 1]; ++i, ++column) {
    lower[column] = d->s->lbg[d->a_ineq[i]];
    upper[column] = d->s->ubg[d->a_ineq[i]];
  }
  for (i = d->x_ineq_idx[k]; i < d->x_ineq_idx[k + 1]; ++i, ++column) {
    lower[column] = d->s->lbz[d->x_ineq[i]];
    upper[column] = d->s->ubz[d->x_ineq[i]];
  }
  return 0;
}

static fatrop_int ocg_initial_x(double *xk, const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  memcpy(xk, d->s->z0 + d->p->col[k], sizeof(double) * d->p->nx[k]);
  return 0;
}

static fatrop_int ocg_initial_u(double *uk, const fatrop_int k, void *user) {
  struct ocg_data *d = (struct ocg_data *)user;
  memcpy(uk, d->s->z0 + d->p->col[k] + d->p->nx[k], sizeof(double) * d->p->nu[k]);
  return 0;
}

/* split rows and variables into equalities and inequalities, stage by stage */
static void ocg_split(struct ocg_data *d) {
  const struct ocg_problem *p = d->p;
  const struct ocg_solve *s = d->s;
  int k, i;
  d->a_eq_idx[0] = d->a_ineq_idx[0] = d->x_eq_idx[0] = d->x_ineq_idx[0] = 0;
  for (k = 0; k <= p->K; ++k) {
    d->a_eq_idx[k + 1] = d->a_eq_idx[k];
    d->a_ineq_idx[k + 1] = d->a_ineq_idx[k];
    for (i = p->row_cd[k]; i < p->row_cd[k] + p->ng[k]; ++i) {
      if (s->lbg[i] == s->ubg[i]) d->a_eq[d->a_eq_idx[k + 1]++] = i;
      else if (s->lbg[i] > -INFINITY || s->ubg[i] < INFINITY)
        d->a_ineq[d->a_ineq_idx[k + 1]++] = i;
    }
    d->x_eq_idx[k + 1] = d->x_eq_idx[k];
    d->x_ineq_idx[k + 1] = d->x_ineq_idx[k];
    for (i = p->col[k]; i < p->col[k] + p->nx[k] + p->nu[k]; ++i) {
      if (s->lbz[i] == s->ubz[i]) d->x_eq[d->x_eq_idx[k + 1]++] = i;
      else if (s->lbz[i] > -INFINITY || s->ubz[i] < INFINITY)
        d->x_ineq[d->x_ineq_idx[k + 1]++] = i;
    }
  }
}

static void ocg_options(const struct ocg_problem *p, struct FatropOcpCSolver *solver) {
  int i;
  for (i = 0; i < p->n_options; ++i) {
    const char *name = p->option_names[i];
    switch (p->option_kinds[i]) {
      case 0: fatrop_ocp_c_set_option_double(solver, name, p->option_values[i]); break;
      case 1: fatrop_ocp_c_set_option_int(solver, name, (int)p->option_values[i]); break;
      case 2: fatrop_ocp_c_set_option_bool(solver, name, (int)p->option_values[i]); break;
      default: fatrop_ocp_c_set_option_string(solver, name, p->option_strings[i]);
    }
  }
}

/* What persists between solves: the work memory and fatrop's solver, created anew only when
 * the split of rows and bounds into equalities and inequalities changes (its creation costs
 * 54 us at 5 stages of so3's size, 0.26 ms at 65, 1 ms at 257; CasADi's interface creates
 * one for every solve). */
struct ocg_context {
  struct ocg_data d;
  struct ocg_guard guard;
  struct FatropOcpCSolver *solver;
  int capped;            /* a stop set the solver's max_iter below p->max_iter */
  int *split, *previous; /* the split's index arrays, this solve's and the solver's */
  int n_split;
  void *blocks;
};

void ocg_context_free(struct ocg_context *c) {
  if (!c) return;
  if (c->solver) fatrop_ocp_c_destroy(c->solver);
  free(c->blocks); free(c->d.arg); free(c->d.res); free(c->d.iw); free(c->split);
  free(c->previous); free(c);
}

/* the context of problem p, or NULL when memory ran out */
struct ocg_context *ocg_context_new(const struct ocg_problem *p) {
  struct ocg_context *c = calloc(1, sizeof *c);
  struct ocg_data *d;
  ocg_cint sz_arg = 0, sz_res = 0, sz_iw = 0, sz_w = 0, a, r, iw, w;
  int i, n_max = p->nz > p->n_rows ? p->nz : p->n_rows;
  if (!c) return NULL;
  d = &c->d;
  for (i = 0; i < OCG_NFUN; ++i) {
    a = r = iw = w = 0; /* a FunctionBuffer holds its own work */
    if (p->work[i]) p->work[i](&a, &r, &iw, &w);
    if (a > sz_arg) sz_arg = a;
    if (r > sz_res) sz_res = r;
    if (iw > sz_iw) sz_iw = iw;
    if (w > sz_w) sz_w = w;
  }
  d->p = p;
  c->n_split = 2 * p->n_rows + 2 * p->nz + 4 * (p->K + 2);
  c->blocks = calloc((size_t)(2 * p->nz + p->n_rows + p->nnz_a + p->nnz_h + n_max + p->n_ab +
                              p->n_cd + p->n_rsq + sz_w + 1), sizeof(double));
  d->arg = calloc((size_t)sz_arg + 4, sizeof(double *));
  d->res = calloc((size_t)sz_res + 2, sizeof(double *));
  d->iw = calloc((size_t)sz_iw + 1, sizeof(ocg_cint));
  c->split = calloc((size_t)c->n_split, sizeof(int));
  c->previous = calloc((size_t)c->n_split, sizeof(int));
  if (!c->blocks || !d->arg || !d->res || !d->iw || !c->split || !c->previous) {
    ocg_context_free(c);
    return NULL;
  }
  d->x = (double *)c->blocks;
  d->lam = d->x + p->nz;
  d->a = d->lam + p->n_rows;
  d->h = d->a + p->nnz_a;
  d->g = d->h + p->nnz_h;
  d->AB = d->g + n_max;
  d->CD = d->AB + p->n_ab;
  d->RSQ = d->CD + p->n_cd;
  d->xg = d->RSQ + p->n_rsq;
  d->w = d->xg + p->nz;
  d->a_eq = c->split;
  d->a_ineq = d->a_eq + p->n_rows;
  d->x_eq = d->a_ineq + p->n_rows;
  d->x_ineq = d->x_eq + p->nz;
  d->a_eq_idx = d->x_ineq + p->nz;
  d->a_ineq_idx = d->a_eq_idx + p->K + 2;
  d->x_eq_idx = d->a_ineq_idx + p->K + 2;
  d->x_ineq_idx = d->x_eq_idx + p->K + 2;

  d->ocp.get_nx = ocg_get_nx;
  d->ocp.get_nu = ocg_get_nu;
  d->ocp.get_ng = ocg_get_ng;
  d->ocp.get_ng_ineq = ocg_get_ng_ineq;
  d->ocp.get_horizon_length = ocg_horizon;
  d->ocp.get_bounds = ocg_bounds;
  d->ocp.get_initial_xk = ocg_initial_x;
  d->ocp.get_initial_uk = ocg_initial_u;
  d->ocp.full_eval_constr_jac = ocg_full_constr_jac;
  d->ocp.full_eval_obj_grad = ocg_full_obj_grad;
  d->ocp.full_eval_obj = ocg_full_obj;
  d->ocp.full_eval_contr_viol = ocg_full_contr_viol;
  d->ocp.full_eval_lag_hess = ocg_full_lag_hess;
  d->ocp.eval_BAbt = ocg_BAbt;
  d->ocp.eval_RSQrqt = ocg_RSQrqt;
  d->ocp.eval_Ggt = ocg_Ggt;
  d->ocp.eval_Ggt_ineq = ocg_Ggt_ineq;
  d->ocp.user_data = d;
  return c;
}

/* One solve from s->z0 (s->status: fatrop's return value, 0 when it converged), guarded if
 * s->guarded (s->left: why it was left; -1 when the guard could not be armed, and nothing
 * was solved). */
void ocg_fatrop_solve(struct ocg_context *c, struct ocg_solve *s) {
  struct ocg_data *d = &c->d;
  const struct ocg_problem *p = d->p;
  int i, k, column;
  const struct blasfeo_dvec *primal, *dual;
  const struct FatropOcpCDims *dims;
  const struct FatropOcpCStats *stats;
  const int one = 1;
  double t0;
  d->s = s;
  memset(d->lam, 0, sizeof(double) * p->n_rows); /* rows without bounds keep multiplier 0 */
  ocg_split(d);
  if (!c->solver || memcmp(c->split, c->previous, sizeof(int) * (size_t)c->n_split) != 0) {
    if (c->solver) fatrop_ocp_c_destroy(c->solver);
    c->solver = fatrop_ocp_c_create(&d->ocp, 0, 0);
    if (!c->solver) { /* fatrop refused the problem: a failed solve from z0 */
      memcpy(s->z, s->z0, sizeof(double) * p->nz);
      s->status = s->return_flag = -1;
      s->iterations = 0;
      return;
    }
    ocg_options(p, c->solver);
    c->capped = 0;
    memcpy(c->previous, c->split, sizeof(int) * (size_t)c->n_split);
  } else if (c->capped) {
    fatrop_ocp_c_set_option_int(c->solver, "max_iter", p->max_iter);
    c->capped = 0;
  }
  d->solver = c->solver;
  d->has_g = 0;
  s->stopped_at = -1;
  memset(d->seconds, 0, sizeof d->seconds);
  memset(d->calls, 0, sizeof d->calls);
  s->left = OCG_LEFT_NONE;
  d->guard = NULL;
  if (s->guarded) {
    c->guard.every = s->every;
    c->guard.check = s->check;
    c->guard.nan_limit = s->nan_limit;
    if (sigsetjmp(c->guard.env, 1)) { /* left: fatrop's solver is abandoned, never freed */
      ocg_guard_disarm(&c->guard);
      c->d.guard = NULL;
      c->solver = NULL;
      s->left = c->guard.reason;
      s->nans = c->guard.nans;
      s->status = s->return_flag = -1;
      s->iterations = 0;
      memcpy(s->z, s->z0, sizeof(double) * c->d.p->nz);
      return;
    }
    if (!ocg_guard_arm(&c->guard, s->limit, s->watch_sigint)) {
      s->left = -1; /* no timer: the caller solves unguarded */
      return;
    }
    d->guard = &c->guard;
  }
  t0 = ocg_now();
  s->status = fatrop_ocp_c_solve(c->solver);
  s->solve_seconds = ocg_now() - t0;
  c->capped = s->stopped_at >= 0;
  if (d->guard) {
    ocg_guard_disarm(d->guard);
    s->nans = d->guard->nans;
    d->guard = NULL;
  }
  memcpy(s->seconds, d->seconds, sizeof d->seconds);
  memcpy(s->calls, d->calls, sizeof d->calls);
  primal = fatrop_ocp_c_get_primal(c->solver);
  dual = fatrop_ocp_c_get_dual(c->solver);
  dims = fatrop_ocp_c_get_dims(c->solver);
  stats = fatrop_ocp_c_get_stats(c->solver);
  s->iterations = stats->iterations_count;
  s->return_flag = stats->return_flag;

  ocg_read_primal(p, primal->pa, s->z, dims);
  memset(s->lam_g, 0, sizeof(double) * p->n_rows);
  memset(s->lam_x, 0, sizeof(double) * p->nz);
  for (k = 0; k < dims->K; ++k) {
    column = 0;
    for (i = d->a_ineq_idx[k]; i < d->a_ineq_idx[k + 1]; ++i)
      s->lam_g[d->a_ineq[i]] = dual->pa[dims->g_ineq_offs[k] + column++];
    for (i = d->x_ineq_idx[k]; i < d->x_ineq_idx[k + 1]; ++i)
      s->lam_x[d->x_ineq[i]] = dual->pa[dims->g_ineq_offs[k] + column++];
    column = 0;
    for (i = d->a_eq_idx[k]; i < d->a_eq_idx[k + 1]; ++i)
      s->lam_g[d->a_eq[i]] = dual->pa[dims->g_offs[k] + column++];
    for (i = d->x_eq_idx[k]; i < d->x_eq_idx[k + 1]; ++i)
      s->lam_x[d->x_eq[i]] = dual->pa[dims->g_offs[k] + column++];
  }
  for (k = 0; k < dims->K - 1; ++k)
    for (i = 0; i < p->nx[k + 1]; ++i)
      s->lam_g[p->row_ab[k] + i] = -dual->pa[dims->dyn_eq_offs[k] + i];

  /* the cost and the rows at the solution */
  ocg_at(d, OCG_F, s->z, &s->f, &one, 1);
  ocg_at(d, OCG_G, s->z, &s->g, &p->n_rows, 1);
}
