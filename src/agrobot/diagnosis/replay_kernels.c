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
 * - expm_stack: exp of each matrix of a stack (components.models.yaw_dynamics.expm_batched: scaling
 *   and squaring with a degree-12 Taylor polynomial, the squarings given), the first-order hold's
 *   augmented generators (diagnosis.replay.first_order_hold). */
#include <string.h>

long replay_kernels_version(void) { return 2; }

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

/* exp of each matrix of a stack, M: (count, q, q), q <= 16, into E alike: expm_batched's degree-12
 * Taylor series of M / 2^squarings, squared back. */
void expm_stack(long count, long q, long squarings, const double *M, double *E) {
    double X[256], T[256], tmp[256];
    double scale = 1.0;
    for (long s = 0; s < squarings; s++) scale *= 2.0;
    for (long c = 0; c < count; c++) {
        double *e = E + c * q * q;
        for (long i = 0; i < q * q; i++) {
            X[i] = M[c * q * q + i] / scale;
            T[i] = e[i] = (i / q == i % q) ? 1.0 : 0.0;
        }
        for (int k = 1; k < 13; k++) {
            for (long i = 0; i < q; i++)
                for (long j = 0; j < q; j++) {
                    double s = 0.0;
                    for (long l = 0; l < q; l++) s += T[i * q + l] * X[l * q + j];
                    tmp[i * q + j] = s;
                }
            for (long i = 0; i < q * q; i++) {
                T[i] = tmp[i] / k;
                e[i] += T[i];
            }
        }
        for (long s = 0; s < squarings; s++) {
            for (long i = 0; i < q; i++)
                for (long j = 0; j < q; j++) {
                    double acc = 0.0;
                    for (long l = 0; l < q; l++) acc += e[i * q + l] * e[l * q + j];
                    tmp[i * q + j] = acc;
                }
            memcpy(e, tmp, sizeof(double) * q * q);
        }
    }
}
