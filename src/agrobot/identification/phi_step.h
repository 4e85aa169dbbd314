/* The exact first-order-hold step of a linear system, the one C home of identification.driving.phi_steps
 * (included by identification/single_track_kernel.c and diagnosis/replay_kernels.c).
 *
 * For dx/dt = A x + B u with u linear over a step of length t (u0 -> u1),
 *
 *     x(t) = P x0 + g1 u0 + g2 (u1 - u0),  P = e^{tA},
 *     g1 = int_0^t e^{As} ds B = t phi1(tA) B,  g2 = (1/t) int_0^t e^{As} (t - s) ds B = t phi2(tA) B,
 *     phi1(X) = sum_k X^k / (k + 1)!,  phi2(X) = sum_k X^k / (k + 2)!
 *
 * (the top block row of expm([[tA, tB, 0], [0, 0, I], [0, 0, 0]]) = [P, g1, g2]; a zero-order hold
 * is g1 alone; the form x+ = P x0 + G0 u0 + G1 u1 has G1 = g2, G0 = g1 - g2). By scaling and
 * squaring: X = tA / 2^s with ||X||_1 <= 1/2, expm(X) by its [6/6] Pade approximant, phi2(X) beta
 * (beta = tB / 2^s) by Horner to degree 12 and phi1(X) beta = beta + X phi2(X) beta (relative errors
 * below 1e-16), then s squarings of the block matrix [[P, g1, g2], [0, I, cI], [0, 0, I]]:
 *
 *     (P, g1, g2, c) -> (P P, P g1 + g1, P g2 + c g1 + g2, 2 c),  c = 2^-s at the start.
 *
 * Each column of B is stepped with its own arithmetic (a column's result does not depend on the
 * others). */
#ifndef AGROBOT_PHI_STEP_H
#define AGROBOT_PHI_STEP_H
#include <math.h>

enum { NX = 5, NU = 4 };  /* the most states (rlfr's four and a held input's lag state) and input columns */


/* The inverse of the n x n matrix A (n <= NX) by Gauss-Jordan elimination with partial pivoting;
 * 0 when A is singular */
static inline int invert(int n, double A[NX][NX], double M[NX][NX]) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            M[i][j] = i == j ? 1.0 : 0.0;
    for (int col = 0; col < n; col++) {
        int piv = col;
        for (int i = col + 1; i < n; i++)
            if (fabs(A[i][col]) > fabs(A[piv][col]))
                piv = i;
        if (A[piv][col] == 0.0)
            return 0;
        for (int j = 0; j < n; j++) {
            double t = A[col][j]; A[col][j] = A[piv][j]; A[piv][j] = t;
            t = M[col][j]; M[col][j] = M[piv][j]; M[piv][j] = t;
        }
        double inv = 1.0 / A[col][col];
        for (int j = 0; j < n; j++) {
            A[col][j] *= inv;
            M[col][j] *= inv;
        }
        for (int i = 0; i < n; i++) {
            double e = A[i][col];
            if (i == col || e == 0.0)
                continue;
            for (int j = 0; j < n; j++) {
                A[i][j] -= e * A[col][j];
                M[i][j] -= e * M[col][j];
            }
        }
    }
    return 1;
}


/* C = A B for n x n matrices, n <= NX (C distinct from A and B) */
static inline void matmul(int n, double A[NX][NX], double B[NX][NX], double C[NX][NX]) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int k = 0; k < n; k++)
                s += A[i][k] * B[k][j];
            C[i][j] = s;
        }
}


/* Y = A X for X, Y n x p row-major (p <= NU), n <= NX (Y distinct from X); p = 1: y = A x */
static inline void matcols(int n, int p, double A[NX][NX], const double *X, double *Y) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < p; j++) {
            Y[i * p + j] = 0.0;
            for (int k = 0; k < n; k++)
                Y[i * p + j] += A[i][k] * X[k * p + j];
        }
}


/* E = expm(X) by the [6/6] Pade approximant (||X||_1 <= 1/2), n <= NX; 0 when its denominator is
 * singular */
static inline int pade(int n, double X[NX][NX], double E[NX][NX]) {
    static const double c[7] = {1.0, 0.5, 5.0 / 44.0, 1.0 / 66.0, 1.0 / 792.0, 1.0 / 15840.0, 1.0 / 665280.0};
    double X2[NX][NX], X4[NX][NX], X6[NX][NX], U[NX][NX], V[NX][NX], T[NX][NX], M[NX][NX];
    matmul(n, X, X, X2);
    matmul(n, X2, X2, X4);
    matmul(n, X4, X2, X6);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double id = i == j ? 1.0 : 0.0;
            T[i][j] = c[1] * id + c[3] * X2[i][j] + c[5] * X4[i][j];
            V[i][j] = c[0] * id + c[2] * X2[i][j] + c[4] * X4[i][j] + c[6] * X6[i][j];
        }
    matmul(n, X, T, U);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            T[i][j] = V[i][j] - U[i][j];
            V[i][j] += U[i][j];
        }
    if (!invert(n, T, M))
        return 0;
    matmul(n, M, V, E);
    return 1;
}



/* (P, g1, g2) of dx/dt = A x + B u over t (see the top): m states (m <= NX), p input columns (p <= NU);
 * B, g1 and g2 m x p, row-major; 0 when the Pade denominator is singular */
static inline int phi_step(int m, int p, double A[NX][NX], const double *B, double t, double P[NX][NX],
                           double *g1, double *g2) {
    static const int DEGREE = 12;
    double X[NX][NX], T[NX][NX], y[NX * NU], u[NX * NU], norm = 0.0;
    for (int j = 0; j < m; j++) {
        double col = 0.0;
        for (int i = 0; i < m; i++)
            col += fabs(t * A[i][j]);
        norm = col > norm ? col : norm;
    }
    int s = norm > 0.5 ? (int)ceil(log2(norm / 0.5)) : 0;
    double scale = ldexp(t, -s), c = ldexp(1.0, -s), f = 1.0;       /* f = 1 / (k + 2)! */
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            X[i][j] = scale * A[i][j];
    for (int k = 1; k <= DEGREE + 2; k++)
        f /= k;
    for (int i = 0; i < m * p; i++)
        y[i] = scale * B[i] * f;
    for (int k = DEGREE - 1; k >= 0; k--) {        /* y <- X y + beta / (k + 2)!: phi2(X) beta */
        f *= k + 3;
        matcols(m, p, X, y, u);
        for (int i = 0; i < m * p; i++)
            y[i] = u[i] + scale * B[i] * f;
    }
    matcols(m, p, X, y, u);                       /* phi1(X) beta = beta + X phi2(X) beta */
    for (int i = 0; i < m * p; i++) {
        g1[i] = scale * B[i] + u[i];
        g2[i] = c * y[i];
    }
    if (!pade(m, X, P))
        return 0;
    for (int k = 0; k < s; k++) {
        double u1[NX * NU], u2[NX * NU];
        matcols(m, p, P, g1, u1);
        matcols(m, p, P, g2, u2);
        for (int i = 0; i < m * p; i++) {
            g2[i] = u2[i] + c * g1[i] + g2[i];
            g1[i] = u1[i] + g1[i];
        }
        c *= 2.0;
        matmul(m, P, P, T);
        for (int i = 0; i < m; i++)
            for (int j = 0; j < m; j++)
                P[i][j] = T[i][j];
    }
    return 1;
}

#endif
