/* The guidance laws the controller FMUs share (included by their model cores): the speed PID
 * update, the kinematic tracker and, where the core defines the MPC's design (NX, NC, MPC_*), one
 * step of the condensed yaw-rate MPC. Equations: components/models/pid.py,
 * components/kinematic_tracker.py, components/models/condensed_mpc.py. */
#include <math.h>
#include <string.h>

typedef struct { double integral, prev_error; int has_prev; } PIDState;


/* DiscretePID.update: u = clip(offset + kp e + I + kd de/dt), I clamped, frozen while saturated */
static double pid_update(PIDState *s, double kp, double ki, double kd, double umin, double umax,
                         double ilim, double e, double dt, double offset) {
    double deriv = (!s->has_prev || kd == 0.0) ? 0.0 : (e - s->prev_error) / dt;
    s->prev_error = e;
    s->has_prev = 1;
    double raw = offset + kp * e + s->integral + kd * deriv;
    double u = raw < umin ? umin : (raw > umax ? umax : raw);
    int saturated_same_way = (raw > umax && e > 0) || (raw < umin && e < 0);
    if (!saturated_same_way) {
        double i = s->integral + ki * e * dt;
        s->integral = i < -ilim ? -ilim : (i > ilim ? ilim : i);
    }
    return u;
}

/* Kinematic tracker (paper section VI): out = {v_d, gamma_d, e_x, e_y}.
 * v_d, gamma_d from the saturated position errors; with a look-ahead a > l_r:
 * gamma_d = (l_r gamma_fb + (a - l_r) gamma_r) / a (components/kinematic_tracker.py). */
static void tracker_law(double x_ref, double y_ref, double xdot_ref, double ydot_ref, double x, double y,
                        double heading, double yaw_rate_ref, double crab, double k_s, double k_c, double l_r,
                        double lookahead, double out[4]) {
    double ex = x_ref - x, ey = y_ref - y;
    double xd = xdot_ref + k_s * tanh(k_c * ex);
    double yd = ydot_ref + k_s * tanh(k_c * ey);
    double cs = cos(heading), sn = sin(heading);
    double v_d = cs * xd + sn * yd, gamma_d = (-sn * xd + cs * yd - crab) / l_r;
    double share = l_r / (lookahead != 0.0 ? lookahead : l_r);
    if (share != 1.0) gamma_d = share * gamma_d + (1.0 - share) * yaw_rate_ref;
    out[0] = v_d; out[1] = gamma_d; out[2] = ex; out[3] = ey;
}

#ifdef NX
#define QP_API static
#include "qp_active_set.c"

typedef struct { double z[NX + 2], w[2 * NX]; } MPCState;      /* [x; u_prev; y - r], W = [A x + B u; A x] */

/* One MPC step (condensed_mpc.CondensedTrackingMPC.step); returns the command, sets *status. */
static double mpc_step(MPCState *c, double umax, double dumax, double r, double y, double applied,
                       int use_applied, double *status) {
    double *z = c->z, g[NC], A[2 * NC * NC], lo[2 * NC], up[2 * NC], du[NC];
    if (use_applied)
        for (int i = 0; i < NX; i++) z[i] = c->w[NX + i] + MPC_B[i] * applied;
    double u_prev = z[NX];
    z[NX + 1] = y - r;
    for (int i = 0; i < NC; i++) {
        g[i] = 0.0;
        for (int j = 0; j < NX + 2; j++) g[i] += MPC_G[i * (NX + 2) + j] * z[j];
    }
    memset(A, 0, sizeof A);
    for (int i = 0; i < NC; i++) {
        A[i * NC + i] = 1.0;                              /* |du_i| <= du_max */
        lo[i] = -dumax; up[i] = dumax;
        for (int j = 0; j < NC; j++) A[(NC + i) * NC + j] = MPC_S[i * NC + j];
        lo[NC + i] = -umax - u_prev; up[NC + i] = umax - u_prev;
    }
    int flag = agrobot_qp_solve(NC, 2 * NC, MPC_H, g, A, lo, up, du);
    double du0 = du[0];
    if (flag <= 0 || du0 != du0) du0 = 0.0;               /* hold the previous command */
    *status = flag > 0 ? 1.0 : (double)flag;
    double u = u_prev + du0;
    u = u < -umax ? -umax : (u > umax ? umax : u);
    z[NX] = u;
    for (int i = 0; i < 2 * NX; i++) {
        double s = 0.0;
        for (int j = 0; j < NX + 2; j++) s += MPC_ADVANCE[i * (NX + 2) + j] * z[j];
        c->w[i] = s;
    }
    for (int i = 0; i < NX; i++) z[i] = c->w[i];
    return u;
}

#endif
