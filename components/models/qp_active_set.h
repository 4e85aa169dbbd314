/* Exact primal active-set solver for small dense strictly convex QPs:
 *
 *     minimise 0.5 x'Hx + g'x   subject to  lo_j <= a_j'x <= up_j,  j = 0..m-1
 *
 * H (n x n, symmetric positive definite) and A (m x n) row-major. x = 0 must be feasible (true
 * for the MPC's moves: no move keeps the last command, which is within its limits).
 * Returns the number of iterations (>= 1) on success, -1 when x = 0 is infeasible, -2 when the
 * iteration limit is reached, -3 on a singular KKT system. Sizes: n <= QP_MAX_N, m <= QP_MAX_M.
 */
#ifndef QP_ACTIVE_SET_H
#define QP_ACTIVE_SET_H

#define QP_MAX_N 10
#define QP_MAX_M 40

/* QP_API: empty when compiled on its own (the equivalence tests); an FMU's model core defines it
 * as `static` and includes qp_active_set.c, so that nothing but the FMI API leaves the binary. */
#ifndef QP_API
#define QP_API
#endif

QP_API int agrobot_qp_solve(int n, int m, const double *H, const double *g, const double *A,
                     const double *lo, const double *up, double *x);

#endif
