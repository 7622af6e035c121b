/* ocg_fatrop_hooks.h: a thin wrapper around fatrop's C interface (defined in ocg_solver.c),
 * used by exports with solver.backend fatrop (OCG_BACKEND_FATROP in ocg_model.h).
 *
 * CasADi's generated solver keeps fatrop's return flag and iteration count to itself.
 * ocg_generated.c then defines OCG_ROUTE_FATROP and includes this header first, so that its
 * call to fatrop_ocp_c_solve goes through the wrapper, which records both.
 */
#ifndef OCG_FATROP_HOOKS_H
#define OCG_FATROP_HOOKS_H

#include <fatrop/ocp/OCPCInterface.h>

fatrop_int ocg_fatrop_solve(struct FatropOcpCSolver *solver);

#ifdef OCG_ROUTE_FATROP
#define fatrop_ocp_c_solve ocg_fatrop_solve
#endif

#endif /* OCG_FATROP_HOOKS_H */
