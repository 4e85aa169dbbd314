/* Speed Kalman filter (components/speed_kf.py): constant-velocity model per axis (white
 * acceleration q), GPS position and velocity measured; both axes share one 2x2 covariance
 * [[a, b], [b, c]]; the first sample initialises the state. */
typedef struct { double s[4], P[3]; int started; } ModelState;   /* s = [x, v_east, y, v_north] */

static void model_start(ModelState *st, const double *p) {
    memset(st, 0, sizeof *st);
    st->P[0] = p[P_position_noise_std] * p[P_position_noise_std];
    st->P[2] = p[P_velocity_noise_std] * p[P_velocity_noise_std];
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    double z[4] = {in[IN_x], in[IN_vel_east], in[IN_y], in[IN_vel_north]};
    if (!st->started) {
        memcpy(st->s, z, sizeof z);
        st->started = 1;
    } else {
        double T = MODEL_PERIOD, q = p[P_acceleration_psd];
        double q11 = q * T * T * T / 3, q12 = q * T * T / 2, q22 = q * T;
        double rp = p[P_position_noise_std] * p[P_position_noise_std], rv = p[P_velocity_noise_std] * p[P_velocity_noise_std];
        double a = st->P[0], b = st->P[1], c = st->P[2], *s = st->s;
        s[0] += T * s[1];
        s[2] += T * s[3];
        double a1 = a + 2 * T * b + T * T * c + q11, b1 = b + T * c + q12, c1 = c + q22;
        a = a1; b = b1; c = c1;
        if (in[IN_fix_valid] > 0.5) {
            double det = (a + rp) * (c + rv) - b * b;
            double k11 = (a * (c + rv) - b * b) / det, k12 = b * rp / det;
            double k21 = b * rv / det, k22 = (c * (a + rp) - b * b) / det;
            for (int i = 0; i <= 2; i += 2) {
                double ep = z[i] - s[i], ev = z[i + 1] - s[i + 1];
                s[i] += k11 * ep + k12 * ev;
                s[i + 1] += k21 * ep + k22 * ev;
            }
            double a2 = a - (k11 * a + k12 * b), b2 = b - (k11 * b + k12 * c), c2 = c - (k21 * b + k22 * c);
            a = a2; b = b2; c = c2;
        }
        st->P[0] = a; st->P[1] = b; st->P[2] = c;
    }
    out[OUT_vel_east] = st->s[1];
    out[OUT_vel_north] = st->s[3];
    out[OUT_speed] = hypot(st->s[1], st->s[3]);
}
