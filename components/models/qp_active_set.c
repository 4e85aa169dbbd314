/* Primal active-set method (Nocedal & Wright, Numerical Optimization, algorithm 16.3) started
 * from x = 0 with an empty working set. Each iteration solves the equality-constrained KKT system
 *     [H  W'] [p ]   [-(Hx + g)]
 *     [W  0 ] [mu] = [    0    ]
 * by Gaussian elimination with partial pivoting. p = 0: the signed multipliers decide optimality
 * (or which constraint leaves); p != 0: step to the first blocking constraint, which joins W.
 * Rows of A parallel to the working set never block (a'p = 0), so W stays independent. */
#include <math.h>
#include "qp_active_set.h"

#define KKT_MAX (QP_MAX_N + QP_MAX_N)

static int solve_dense(int n, double *K, double *rhs) {
    /* K (n x n, row-major, stride KKT_MAX) x = rhs, in place; returns 0 or -1 if singular */
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(K[r * KKT_MAX + c]) > fabs(K[piv * KKT_MAX + c])) piv = r;
        if (fabs(K[piv * KKT_MAX + c]) < 1e-300) return -1;
        if (piv != c) {
            for (int k = 0; k < n; k++) {
                double t = K[c * KKT_MAX + k]; K[c * KKT_MAX + k] = K[piv * KKT_MAX + k]; K[piv * KKT_MAX + k] = t;
            }
            double t = rhs[c]; rhs[c] = rhs[piv]; rhs[piv] = t;
        }
        for (int r = c + 1; r < n; r++) {
            double f = K[r * KKT_MAX + c] / K[c * KKT_MAX + c];
            if (f == 0.0) continue;
            for (int k = c; k < n; k++) K[r * KKT_MAX + k] -= f * K[c * KKT_MAX + k];
            rhs[r] -= f * rhs[c];
        }
    }
    for (int r = n - 1; r >= 0; r--) {
        double s = rhs[r];
        for (int k = r + 1; k < n; k++) s -= K[r * KKT_MAX + k] * rhs[k];
        rhs[r] = s / K[r * KKT_MAX + r];
    }
    return 0;
}

QP_API int agrobot_qp_solve(int n, int m, const double *H, const double *g, const double *A,
                     const double *lo, const double *up, double *x) {
    int work_row[QP_MAX_N], work_side[QP_MAX_N];   /* side +1: a'x = lo, -1: a'x = up */
    int in_work[QP_MAX_M];
    int nw = 0;
    double K[KKT_MAX * KKT_MAX], rhs[KKT_MAX];
    const double feas_tol = 1e-12;

    if (n > QP_MAX_N || m > QP_MAX_M || n < 1) return -3;
    for (int i = 0; i < n; i++) x[i] = 0.0;
    for (int j = 0; j < m; j++) {
        in_work[j] = 0;
        if (lo[j] > feas_tol || up[j] < -feas_tol) return -1;
    }
    for (int it = 1; it <= 10 * (n + m) + 10; it++) {
        int size = n + nw;
        double xnorm = 0.0;
        for (int r = 0; r < size; r++)
            for (int c = 0; c < size; c++) K[r * KKT_MAX + c] = 0.0;
        for (int r = 0; r < n; r++) {
            double hx = g[r];
            for (int c = 0; c < n; c++) {
                K[r * KKT_MAX + c] = H[r * n + c];
                hx += H[r * n + c] * x[c];
            }
            rhs[r] = -hx;
            if (fabs(x[r]) > xnorm) xnorm = fabs(x[r]);
        }
        for (int k = 0; k < nw; k++) {
            const double *a = A + work_row[k] * n;
            for (int c = 0; c < n; c++) {
                K[(n + k) * KKT_MAX + c] = a[c];
                K[c * KKT_MAX + n + k] = a[c];
            }
            rhs[n + k] = 0.0;
        }
        if (solve_dense(size, K, rhs) != 0) return -3;
        double pnorm = 0.0;
        for (int i = 0; i < n; i++) if (fabs(rhs[i]) > pnorm) pnorm = fabs(rhs[i]);
        if (pnorm <= 1e-13 * (1.0 + xnorm)) {
            /* KKT: Hx + g + W'mu = 0; lower-active needs mu <= 0, upper-active mu >= 0 */
            int leave = -1;
            double worst = -1e-12;
            for (int k = 0; k < nw; k++) {
                double lambda = -work_side[k] * rhs[n + k];
                if (lambda < worst) { worst = lambda; leave = k; }
            }
            if (leave < 0) return it;
            in_work[work_row[leave]] = 0;
            for (int k = leave; k < nw - 1; k++) {
                work_row[k] = work_row[k + 1];
                work_side[k] = work_side[k + 1];
            }
            nw--;
            continue;
        }
        double alpha = 1.0;
        int block = -1, block_side = 0;
        for (int j = 0; j < m; j++) {
            if (in_work[j]) continue;
            const double *a = A + j * n;
            double ap = 0.0, ax = 0.0;
            for (int c = 0; c < n; c++) { ap += a[c] * rhs[c]; ax += a[c] * x[c]; }
            if (ap < -1e-14) {
                double t = (lo[j] - ax) / ap;
                if (t < alpha) { alpha = t > 0.0 ? t : 0.0; block = j; block_side = 1; }
            } else if (ap > 1e-14) {
                double t = (up[j] - ax) / ap;
                if (t < alpha) { alpha = t > 0.0 ? t : 0.0; block = j; block_side = -1; }
            }
        }
        for (int i = 0; i < n; i++) x[i] += alpha * rhs[i];
        if (block >= 0) {
            if (nw >= n) return -3;
            in_work[block] = 1;
            work_row[nw] = block;
            work_side[nw] = block_side;
            nw++;
        }
    }
    return -2;
}
