/* ocg_ipopt_hooks.h: two thin wrappers around IPOPT's C interface (defined in ocg_solver.c).
 *
 * CasADi's generated solver keeps IPOPT's return status and iteration count to itself.
 * ocg_generated.c defines OCG_ROUTE_IPOPT and includes this header first, so that its calls
 * to CreateIpoptProblem and IpoptSolve go through the wrappers, which install an
 * intermediate callback (the iteration count) and record the status.
 */
#ifndef OCG_IPOPT_HOOKS_H
#define OCG_IPOPT_HOOKS_H

#include <coin-or/IpStdCInterface.h>

IpoptProblem ocg_create_ipopt_problem(ipindex n, ipnumber *x_L, ipnumber *x_U, ipindex m,
                                      ipnumber *g_L, ipnumber *g_U, ipindex nele_jac,
                                      ipindex nele_hess, ipindex index_style,
                                      Eval_F_CB eval_f, Eval_G_CB eval_g,
                                      Eval_Grad_F_CB eval_grad_f, Eval_Jac_G_CB eval_jac_g,
                                      Eval_H_CB eval_h);

enum ApplicationReturnStatus ocg_ipopt_solve(IpoptProblem problem, ipnumber *x, ipnumber *g,
                                             ipnumber *obj_val, ipnumber *mult_g,
                                             ipnumber *mult_x_L, ipnumber *mult_x_U,
                                             UserDataPtr user_data);

#ifdef OCG_ROUTE_IPOPT
#define CreateIpoptProblem ocg_create_ipopt_problem
#define IpoptSolve ocg_ipopt_solve
#endif

#endif /* OCG_IPOPT_HOOKS_H */
