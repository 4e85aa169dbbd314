/* Pose EKF (components/pose_ekf.py): state [x, y, psi] of the rear-axle point R; predict with the
 * kinematic bicycle from the previous sample's speed and wheel angle, update with the GPS
 * position; the covariance's six entries written out. */
typedef struct { double s[3], P[6], prev_v, prev_delta; int has_prev; } ModelState;

static void model_start(ModelState *st, const double *p) {
    memset(st, 0, sizeof *st);
    st->s[0] = p[P_x0]; st->s[1] = p[P_y0]; st->s[2] = p[P_psi0];
    double p0 = p[P_position0_std] * p[P_position0_std], h0 = p[P_heading0_std] * p[P_heading0_std];
    st->P[0] = p0; st->P[3] = p0; st->P[5] = h0;
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    double *s = st->s, *P = st->P, dt = MODEL_PERIOD;
    if (st->has_prev) {
        double v = st->prev_v, c = cos(s[2]), sn = sin(s[2]);
        s[0] += dt * v * c; s[1] += dt * v * sn; s[2] += dt * v * tan(st->prev_delta) / p[P_wheelbase];
        double f13 = -dt * v * sn, f23 = dt * v * c, qp = p[P_position_process_std] * p[P_position_process_std];
        double qh = p[P_heading_process_std] * p[P_heading_process_std];
        double p11 = P[0], p12 = P[1], p13 = P[2], p22 = P[3], p23 = P[4], p33 = P[5];
        P[0] = p11 + 2 * f13 * p13 + f13 * f13 * p33 + qp;
        P[1] = p12 + f13 * p23 + f23 * p13 + f13 * f23 * p33;
        P[2] = p13 + f13 * p33;
        P[3] = p22 + 2 * f23 * p23 + f23 * f23 * p33 + qp;
        P[4] = p23 + f23 * p33;
        P[5] = p33 + qh;
    }
    if (in[IN_fix_valid] > 0.5) {
        double r = p[P_position_noise_std] * p[P_position_noise_std];
        double p11 = P[0], p12 = P[1], p13 = P[2], p22 = P[3], p23 = P[4], p33 = P[5];
        double s11 = p11 + r, s22 = p22 + r, det = s11 * s22 - p12 * p12;
        double ex = in[IN_gps_x] - s[0], ey = in[IN_gps_y] - s[1];
        double k11 = (p11 * s22 - p12 * p12) / det, k12 = (p12 * s11 - p11 * p12) / det;
        double k21 = (p12 * s22 - p22 * p12) / det, k22 = (p22 * s11 - p12 * p12) / det;
        double k31 = (p13 * s22 - p23 * p12) / det, k32 = (p23 * s11 - p13 * p12) / det;
        s[0] += k11 * ex + k12 * ey; s[1] += k21 * ex + k22 * ey; s[2] += k31 * ex + k32 * ey;
        P[0] = p11 - (k11 * p11 + k12 * p12); P[1] = p12 - (k11 * p12 + k12 * p22);
        P[2] = p13 - (k11 * p13 + k12 * p23); P[3] = p22 - (k21 * p12 + k22 * p22);
        P[4] = p23 - (k21 * p13 + k22 * p23); P[5] = p33 - (k31 * p13 + k32 * p23);
    }
    st->prev_v = in[IN_speed]; st->prev_delta = in[IN_steer_angle]; st->has_prev = 1;
    s[2] = atan2(sin(s[2]), cos(s[2]));
    double lr = p[P_l_r];
    out[OUT_x_rear] = s[0]; out[OUT_y_rear] = s[1]; out[OUT_heading] = s[2];
    out[OUT_x_cg] = s[0] + lr * cos(s[2]); out[OUT_y_cg] = s[1] + lr * sin(s[2]);
    out[OUT_heading_std] = sqrt(P[5]);
}
