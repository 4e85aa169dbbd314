/* The yaw model's segment simulation (identification.driving.YawModel.simulate_many) row by row:
 * the single-track model (components/models/tyre.py: bicycle, rlf, rlfr; linear tyres, or the
 * simplified Magic Formula F = D sin(C atan(B alpha)), D = mu F_z, B = C_alpha / (C D)) driven by
 * the wheel angle through the first-order lag with a first-order hold
 *
 *     d+ = a d + (1 - a) w_j + c (w_j+1 - w_j),   a = exp(-h / T),  c = 1 - (T / h)(1 - a),
 *
 * the cornering stiffnesses scaled by max(0.2, 1 + k (v - v_ref)) at the substep's mean speed
 * when k != 0, and each sample's step cut into SUB substeps of the L-stable Rosenbrock method
 * (Verwer's ROS2, gamma = 1 + 1/sqrt 2):
 *
 *     (I - gamma h J) k1 = f(z, u0),  (I - gamma h J) k2 = f(z + h k1, u1) - 2 k1,
 *     z+ = z + h (3 k1 + k2) / 2.
 *
 * With linear tyres (mu infinite) the model is linear, dz/dt = J(v) z + b(v) d, and each sample's
 * step is instead its exact discretisation at the sample's mean speed for the wheel angle linear
 * across the step (first-order hold, d0 -> d1):
 *
 *     z+ = expm(h J) z + h phi1(h J) b d0 + h phi2(h J) b (d1 - d0),
 *     phi1(X) = sum X^k / (k + 1)!,  phi2(X) = sum X^k / (k + 2)!
 *
 * (the top rows of expm([[h J, h b, 0], [0, 0, 1], [0, 0, 0]]); phi_step.h, by scaling and squaring
 * with a [6/6] Pade approximant and Horner's phi2, relative errors below 1e-16);
 * a speed the previous sample had reuses the step, and a row whose speeds and step parameters (all
 * but the lag's) an earlier row of the call had reuses that row's steps (a Jacobian's columns for
 * the delay, lag, offset or gain).
 *
 * A held input (phase given: zero-order hold) is stepped by simulate_row_held instead: each sample
 * step in two pieces, w_j for phase_j h then w_j+1, through the lag exactly, the linear model with
 * the lag's d as a state (held_step).
 *
 * Each row starts from the kinematic state gamma = v d / L, v_y = l_r gamma (slip angles 0). */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "phi_step.h"        /* NX, invert, matmul, phi_step: the exact first-order-hold step */

enum { P_A, P_C, P_LAG, P_DELAY, P_CF, P_CR, P_MU, P_SHAPE, P_SLOPE, P_VREF, P_SIGMA_F, P_SIGMA_R, P_M, P_I, P_LF, P_LR,
       P_FZF, P_FZR, N_PAR };
enum { BICYCLE = 0, RLF = 1, RLFR = 2 };

typedef struct { int model, n; const double *p; double Cf, Cr; } Row;


/* (F_y, dF_y/dalpha) of the simplified Magic Formula (k: NULL when the slope is not needed); an
 * infinite peak D: the linear tyre */
static inline void magic_formula(double alpha, double C, double D, double shape, double *F, double *k) {
    if (!isfinite(D)) {
        *F = C * alpha;
        if (k)
            *k = C;
        return;
    }
    double B = C / (shape * D), x = B * alpha, phase = shape * atan(x);
    *F = D * sin(phase);
    if (k)
        *k = D * cos(phase) * shape * B / (1.0 + x * x);
}


/* dz/dt and its Jacobian J (NULL: not needed) of the single-track model, z = [v_y, gamma (, alpha_f)
 * (, alpha_r)] */
static inline void rates(const Row *q, double v, double delta, const double *z, double *f, double J[NX][NX]) {
    const double *p = q->p;
    double m = p[P_M], I = p[P_I], lf = p[P_LF], lr = p[P_LR], mu = p[P_MU], shape = p[P_SHAPE];
    double vy = z[0], g = z[1];
    double a_f = q->model == BICYCLE ? (vy + lf * g) / v - delta : z[2];
    double a_r = q->model == RLFR ? z[3] : (vy - lr * g) / v;
    double Ff, kf = 0.0, Fr, kr = 0.0, dFf[NX] = {0.0}, dFr[NX] = {0.0};
    magic_formula(a_f, q->Cf, mu * p[P_FZF], shape, &Ff, J ? &kf : NULL);
    magic_formula(a_r, q->Cr, mu * p[P_FZR], shape, &Fr, J ? &kr : NULL);
    f[0] = -v * g - (Ff + Fr) / m;
    f[1] = (-lf * Ff + lr * Fr) / I;
    if (q->model != BICYCLE)
        f[2] = (vy + lf * g - v * (a_f + delta)) / p[P_SIGMA_F];
    if (q->model == RLFR)
        f[3] = (vy - lr * g - v * a_r) / p[P_SIGMA_R];
    if (!J)
        return;
    if (q->model == BICYCLE) {
        dFf[0] = kf / v;
        dFf[1] = kf * lf / v;
    } else {
        dFf[2] = kf;
    }
    if (q->model == RLFR) {
        dFr[3] = kr;
    } else {
        dFr[0] = kr / v;
        dFr[1] = -kr * lr / v;
    }
    for (int i = 0; i < q->n; i++) {
        J[0][i] = -(dFf[i] + dFr[i]) / m;
        J[1][i] = (-lf * dFf[i] + lr * dFr[i]) / I;
        J[2][i] = J[3][i] = 0.0;
    }
    J[0][1] -= v;
    if (q->model != BICYCLE) {
        double sf = p[P_SIGMA_F];
        J[2][0] = 1.0 / sf;
        J[2][1] = lf / sf;
        J[2][2] = -v / sf;
    }
    if (q->model == RLFR) {
        double sr = p[P_SIGMA_R];
        J[3][0] = 1.0 / sr;
        J[3][1] = -lr / sr;
        J[3][3] = -v / sr;
    }
}


/* One ROS2 step of length hs from inputs (v0, d0) to (v1, d1); 0 when I - gamma hs J is singular */
static inline int ros2_step(const Row *q, double hs, double v0, double v1, double d0, double d1, double *z) {
    const double gamma = 1.0 + 1.0 / sqrt(2.0);
    int n = q->n;
    double f0[NX], f1[NX], J[NX][NX], A[NX][NX], M[NX][NX], k1[NX], k2[NX], z1[NX] = {0.0};
    rates(q, v0, d0, z, f0, J);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            A[i][j] = (i == j ? 1.0 : 0.0) - gamma * hs * J[i][j];
    if (!invert(n, A, M))
        return 0;
    for (int i = 0; i < n; i++) {
        k1[i] = 0.0;
        for (int j = 0; j < n; j++)
            k1[i] += M[i][j] * f0[j];
        z1[i] = z[i] + hs * k1[i];
    }
    rates(q, v1, d1, z1, f1, NULL);
    for (int i = 0; i < n; i++) {
        k2[i] = 0.0;
        for (int j = 0; j < n; j++)
            k2[i] += M[i][j] * (f1[j] - 2.0 * k1[j]);
    }
    for (int i = 0; i < n; i++)
        z[i] = z[i] + hs * (1.5 * k1[i] + 0.5 * k2[i]);
    return 1;
}


/* The exact first-order-hold step of the linear model at speed v over h (see the top): P, g1, g2
 * with z+ = P z + g1 d0 + g2 (d1 - d0); 0 when the Pade denominator is singular */
static inline int exact_step(const Row *q, double v, double h, double P[NX][NX], double *g1, double *g2) {
    double zero[NX] = {0.0}, b[NX], J[NX][NX];
    rates(q, v, 1.0, zero, b, J);            /* linear tyres: f(0, 1) = b */
    return phi_step(q->n, 1, J, b, h, P, g1, g2);
}


/* The exact step over t of the linear model at speed v with the lag's wheel angle d as a state,
 * x = [z, d], for a held input w: x+ = P x + g w, P = expm(t A), g = t phi1(t A) B,
 * A = [[J, b], [0, -1/T]], B = [0, 1/T] (T = 0: A's corner and B 0; the caller sets d = w) */
static inline int held_step(const Row *q, double v, double t, double inv_T, double P[NX][NX], double *g) {
    double zero[NX] = {0.0}, b[NX], J[NX][NX], A[NX][NX] = {{0.0}}, B[NX] = {0.0}, g2[NX];
    int n = q->n;
    rates(q, v, 1.0, zero, b, J);
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++)
            A[i][j] = J[i][j];
        A[i][n] = b[i];
    }
    A[n][n] = -inv_T;
    B[n] = inv_T;
    return phi_step(n + 1, 1, A, B, t, P, g, g2);
}


/* The cornering stiffnesses at speed v: C x max(0.2, 1 + k (v - v_ref)) when k != 0 */
static inline void cornering(Row *q, double v) {
    const double *p = q->p;
    q->Cf = p[P_CF];
    q->Cr = p[P_CR];
    if (p[P_SLOPE] != 0.0) {
        double scale = 1.0 + p[P_SLOPE] * (v - p[P_VREF]);
        if (scale < 0.2)
            scale = 0.2;
        q->Cf *= scale;
        q->Cr *= scale;
    }
}


/* a stored step: P (NX x NX), g1, g2 (a held input's: its two pieces' P and g); rows remembered per speed row; the most doubles stored (128 MB): the
 * store only when a call has more rows than speed rows (several parameter sets) */
enum { STEP = NX * NX + 2 * NX, STEP_HELD = 2 * (NX * NX + NX), N_SLOT = 4, MAX_STORE = 1 << 24 };


/* One row over its L samples: w, v its wheel angle asked and speed, yaw and vy its outputs; steps
 * (NULL: none): the linear steps of an earlier row with these speeds and step parameters (filled)
 * or the place to store this row's */
static inline int simulate_row(Row *q, long L, int sub, double h, const double *w, const double *v, double *yaw,
                               double *vy, double *steps, int filled) {
    const double *p = q->p;
    double a = p[P_A], c = p[P_C], hs = h / sub;
    double z[NX] = {0.0}, d = w[0], P[NX][NX], g1[NX], g2[NX], v_cached = NAN;
    int n = q->n, linear = !isfinite(p[P_MU]);
    double r0 = v[0] * d / (p[P_LF] + p[P_LR]);
    z[0] = p[P_LR] * r0;
    z[1] = r0;
    for (long j = 0; j < L; j++) {
        yaw[j] = z[1];
        vy[j] = z[0];
        if (j == L - 1)
            break;
        double d_next = a * d + (1.0 - a) * w[j] + c * (w[j + 1] - w[j]);
        if (linear) {
            double vm = 0.5 * (v[j] + v[j + 1]), zn[NX], *st = steps ? steps + j * STEP : NULL;
            if (st && filled) {
                memcpy(P, st, sizeof P);
                memcpy(g1, st + NX * NX, sizeof g1);
                memcpy(g2, st + NX * NX + NX, sizeof g2);
            } else {
                if (vm != v_cached) {
                    cornering(q, vm);
                    if (!exact_step(q, vm, h, P, g1, g2))
                        return 0;
                    v_cached = vm;
                }
                if (st) {
                    memcpy(st, P, sizeof P);
                    memcpy(st + NX * NX, g1, sizeof g1);
                    memcpy(st + NX * NX + NX, g2, sizeof g2);
                }
            }
            for (int i = 0; i < n; i++) {
                zn[i] = g1[i] * d + g2[i] * (d_next - d);
                for (int k = 0; k < n; k++)
                    zn[i] += P[i][k] * z[k];
            }
            for (int i = 0; i < n; i++)
                z[i] = zn[i];
            d = d_next;
            continue;
        }
        for (int k = 0; k < sub; k++) {
            double s0 = (double)k / sub, s1 = (double)(k + 1) / sub;
            double v0 = v[j] + s0 * (v[j + 1] - v[j]), v1 = v[j] + s1 * (v[j + 1] - v[j]);
            cornering(q, 0.5 * (v0 + v1));
            if (!ros2_step(q, hs, v0, v1, d + s0 * (d_next - d), d + s1 * (d_next - d), z))
                return 0;
        }
        d = d_next;
    }
    return 1;
}


/* The held input's row (zero-order hold): each sample step in two pieces, w_j for phase[j] h then
 * w_j+1, through the lag exactly; linear tyres by held_step at the sample's mean speed (a speed and
 * phase the previous sample had reuse its steps), the Magic Formula by SUB ROS2 substeps per piece
 * on d = w + (d0 - w) exp(-s / T) at their ends (T = 0: d = w); steps as simulate_row's */
static inline int simulate_row_held(Row *q, long L, int sub, double h, const double *w, const double *v,
                                    const double *phase, double *yaw, double *vy, double *steps, int filled) {
    const double *p = q->p;
    double inv_T = p[P_LAG] > 1e-6 ? 1.0 / p[P_LAG] : 0.0, x[NX] = {0.0}, P[2][NX][NX], g[2][NX];
    double v_cached = NAN, phi_cached = NAN;
    int n = q->n, linear = !isfinite(p[P_MU]);
    double r0 = v[0] * w[0] / (p[P_LF] + p[P_LR]);
    x[0] = p[P_LR] * r0;
    x[1] = r0;
    x[n] = w[0];
    for (long j = 0; j < L; j++) {
        yaw[j] = x[1];
        vy[j] = x[0];
        if (j == L - 1)
            break;
        double phi = phase[j], vm = 0.5 * (v[j] + v[j + 1]), *st = steps ? steps + j * STEP_HELD : NULL;
        double start[2] = {0.0, phi * h}, length[2] = {phi * h, (1.0 - phi) * h}, omega[2] = {w[j], w[j + 1]};
        if (linear && st && filled) {
            memcpy(P, st, sizeof P);
            memcpy(g, st + 2 * NX * NX, sizeof g);
        } else if (linear) {
            if (vm != v_cached || phi != phi_cached) {
                cornering(q, vm);
                for (int k = 0; k < 2; k++)
                    if (length[k] > 0.0 && !held_step(q, vm, length[k], inv_T, P[k], g[k]))
                        return 0;
                v_cached = vm;
                phi_cached = phi;
            }
            if (st) {
                memcpy(st, P, sizeof P);
                memcpy(st + 2 * NX * NX, g, sizeof g);
            }
        }
        for (int k = 0; k < 2; k++) {
            double d0 = inv_T > 0.0 ? x[n] : omega[k], xn[NX];
            if (linear) {
                x[n] = d0;
                if (length[k] <= 0.0)
                    continue;
                for (int i = 0; i <= n; i++) {
                    xn[i] = g[k][i] * omega[k];
                    for (int l = 0; l <= n; l++)
                        xn[i] += P[k][i][l] * x[l];
                }
                memcpy(x, xn, sizeof xn);
                continue;
            }
            double hs = length[k] / sub;
            for (int i = 0; i < sub && length[k] > 0.0; i++) {
                double s0 = i * hs, s1 = (i + 1) * hs;
                double v0 = v[j] + (start[k] + s0) / h * (v[j + 1] - v[j]);
                double v1 = v[j] + (start[k] + s1) / h * (v[j + 1] - v[j]);
                cornering(q, 0.5 * (v0 + v1));
                if (!ros2_step(q, hs, v0, v1, omega[k] + (d0 - omega[k]) * exp(-s0 * inv_T),
                               omega[k] + (d0 - omega[k]) * exp(-s1 * inv_T), x))
                    return 0;
            }
            x[n] = omega[k] + (d0 - omega[k]) * exp(-length[k] * inv_T);
        }
    }
    return 1;
}


/* Where row i's linear steps are (or go) among the N_SLOT remembered for its speed row: *filled
 * when an earlier row had its step parameters (those from ``key``: P_CF, or P_LAG for a held input,
 * whose steps depend on its lag and delay); NULL without a store */
static double *slot_of(double *store, const double **keys, int *next, long S, long L, long i, const double *pi,
                       int key, long step, int *filled) {
    long s = i % S;
    *filled = 0;
    if (!store || !isinf(pi[P_MU]))
        return NULL;
    for (int k = 0; k < N_SLOT; k++) {
        const double *prev = keys[s * N_SLOT + k];
        if (prev && memcmp(prev + key, pi + key, (N_PAR - key) * sizeof(double)) == 0) {
            *filled = 1;
            return store + (s * N_SLOT + k) * (L - 1) * step;
        }
    }
    int k = next[s];
    next[s] = (k + 1) % N_SLOT;
    keys[s * N_SLOT + k] = pi;
    return store + (s * N_SLOT + k) * (L - 1) * step;
}


/* One row: simulate_row, or simulate_row_held when ``phase`` is given */
static inline int run_row(Row *q, long L, int sub, double h, const double *w, const double *v, const double *phase,
                          double *yaw, double *vy, double *steps, int filled) {
    if (phase)
        return simulate_row_held(q, L, sub, h, w, v, phase, yaw, vy, steps, filled);
    return simulate_row(q, L, sub, h, w, v, yaw, vy, steps, filled);
}


/* rows rows of L samples: row i driven by w[i L ..] at speed v[(i mod S) L ..], parameters
 * par[i N_PAR ..]; ``phase`` (NULL: the input linear between samples): a held input's switch in
 * each sample step, phase[i L + j] (simulate_row_held); writes the yaw rate and the lateral
 * velocity at the centre of gravity. Returns -1 on success, else the first row whose Rosenbrock
 * matrix (or Pade denominator) was singular. */
long single_track_simulate(int model, long rows, long S, long L, int sub, double h, const double *w,
                           const double *v, const double *par, const double *phase, double *yaw, double *vy) {
    long failed = -1, step = phase ? STEP_HELD : STEP;
    int key = phase ? P_LAG : P_CF;
    size_t size = (size_t)S * N_SLOT * (L > 1 ? L - 1 : 0) * step;          /* doubles */
    double *store = rows > S && size > 0 && size <= MAX_STORE ? malloc(size * sizeof(double)) : NULL;
    const double **keys = calloc((size_t)S * N_SLOT, sizeof(double *));
    int *next = calloc((size_t)S, sizeof(int));
    if (!keys || !next) {
        free(store);
        store = NULL;
    }
    for (long i = 0; i < rows && failed < 0; i++) {
        const double *pi = par + i * N_PAR, *ph = phase ? phase + i * L : NULL;
        int ok, filled;
        double *steps = slot_of(store, keys, next, S, L, i, pi, key, step, &filled);
        if (model == BICYCLE) {           /* one branch per model: its state count known to the compiler */
            Row q = {BICYCLE, 2, pi, 0.0, 0.0};
            ok = run_row(&q, L, sub, h, w + i * L, v + (i % S) * L, ph, yaw + i * L, vy + i * L, steps, filled);
        } else if (model == RLF) {
            Row q = {RLF, 3, pi, 0.0, 0.0};
            ok = run_row(&q, L, sub, h, w + i * L, v + (i % S) * L, ph, yaw + i * L, vy + i * L, steps, filled);
        } else {
            Row q = {RLFR, 4, pi, 0.0, 0.0};
            ok = run_row(&q, L, sub, h, w + i * L, v + (i % S) * L, ph, yaw + i * L, vy + i * L, steps, filled);
        }
        if (!ok)
            failed = i;
    }
    free(store);
    free((void *)keys);
    free(next);
    return failed;
}


long single_track_parameter_count(void) { return N_PAR; }
