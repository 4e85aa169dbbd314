/* The diagnosis's stage replays (diagnosis.replay) at compiled speed; each function does the
 * arithmetic of its Python reference, sample by sample:
 *
 * - steering_first_order: components.models.steering_equivalent.simulate, the closed-loop first-order
 *   equivalent delta <- delta + clip(alpha dz(c - delta, D), -r s, r s) over one or two pieces of
 *   each sample step (the delayed held command constant on each);
 * - indexed_recursion: Z_k = A(i_k) Z_{k-1} + B(i_k)[:, col] * u_k + B1(i_k)[:, col] * u_{k+1},
 *   Z_{-1} = 0, u_N = u_{N-1} (the yaw replay's time-varying recursion under a first-order hold, the
 *   system matrices of the step's speed bin i_k; B1 NULL: a zero-order hold), giving the chosen rows
 *   of Z_{k-1} (the state before each sample's update), for R sets side by side;
 * - first_order_hold: the exact first-order hold (Phi, G0, G1) of a stack of systems, the yaw replay's
 *   at the log's speeds (diagnosis.replay.first_order_hold; phi_step.h gives the equations). */
#include <string.h>

#include "phi_step.h"        /* identification/: NX, NU, phi_step */

long replay_kernels_version(void) { return 3; }

/* phi_step.h's largest system and number of input columns, as 100 NX + NU (checked on load) */
long hold_limits(void) { return 100 * NX + NU; }

void steering_first_order(long n, int pieces, const double *c1, const double *c2, double alpha1, double move1,
                          double alpha2, double move2, double deadband, double delta0, double *out) {
    const double *cs[2] = {c1, c2};
    const double alpha[2] = {alpha1, alpha2}, move[2] = {move1, move2};
    double d = delta0;
    for (long k = 0; k < n; k++) {
        out[k] = d;
        for (int p = 0; p < pieces; p++) {
            double e = cs[p][k] - d;
            if (e > deadband) e -= deadband;
            else if (e < -deadband) e += deadband;
            else continue;
            double m = alpha[p] * e;
            d += m > move[p] ? move[p] : (m < -move[p] ? -move[p] : m);
        }
    }
}

/* A: (R, S, n, n), B and B1: (R, S, n, p), index: (N), col: (m), u: (R, N, m), rows: (nr); out: (R, N, nr, m) */
void indexed_recursion(long R, long S, long N, long n, long p, long m, const double *A, const double *B,
                       const double *B1, const long *index, const long *col, const double *u, long nr,
                       const long *rows, double *out) {
    double z[16 * 16], next[16 * 16];
    for (long r = 0; r < R; r++) {
        const double *Ar = A + r * S * n * n, *Br = B + r * S * n * p, *ur = u + r * N * m;
        double *o = out + r * N * nr * m;
        memset(z, 0, sizeof(double) * n * m);
        for (long k = 0; k < N; k++) {
            const double *Ak = Ar + index[k] * n * n, *Bk = Br + index[k] * n * p, *uk = ur + k * m;
            const double *B1k = B1 ? B1 + (r * S + index[k]) * n * p : 0, *un = k + 1 < N ? uk + m : uk;
            for (long q = 0; q < nr; q++)
                for (long j = 0; j < m; j++) o[(k * nr + q) * m + j] = z[rows[q] * m + j];
            for (long i = 0; i < n; i++)
                for (long j = 0; j < m; j++) {
                    double s = 0.0;
                    for (long l = 0; l < n; l++) s += Ak[i * n + l] * z[l * m + j];
                    s += Bk[i * p + col[j]] * uk[j];
                    next[i * m + j] = B1k ? s + B1k[i * p + col[j]] * un[j] : s;
                }
            memcpy(z, next, sizeof(double) * n * m);
        }
    }
}

/* The first-order hold of each system of a stack (phi_step.h, identification.driving.phi_steps' twin):
 * A: (count, n, n), B: (count, n, p), n <= NX, p <= NU; Phi alike A, G0 and G1 alike B, so that
 * x+ = Phi x + G0 u_k + G1 u_k+1 (G1 = g2, G0 = g1 - g2); the first system whose Pade denominator is
 * singular, or -1. */
long first_order_hold(long count, long n, long p, double h, const double *A, const double *B, double *Phi,
                      double *G0, double *G1) {
    double Ac[NX][NX], P[NX][NX], g1[NX * NU], g2[NX * NU];
    for (long c = 0; c < count; c++) {
        for (long i = 0; i < n; i++)
            for (long j = 0; j < n; j++)
                Ac[i][j] = A[(c * n + i) * n + j];
        if (!phi_step((int)n, (int)p, Ac, B + c * n * p, h, P, g1, g2))
            return c;
        for (long i = 0; i < n; i++)
            for (long j = 0; j < n; j++)
                Phi[(c * n + i) * n + j] = P[i][j];
        for (long i = 0; i < n * p; i++) {
            G0[c * n * p + i] = g1[i] - g2[i];
            G1[c * n * p + i] = g2[i];
        }
    }
    return -1;
}
