/* Figure-8 reference (components/figure8_reference.py, components/models/figure8_path.py): arc
 * length s(t) = v t^2 / (2 T) for t < T, v (t - T/2) after; the pose on two straights crossing at
 * the origin, tangent to circles of radius r centred at (+-c, 0). No inputs; outputs at t_k. */
#include <math.h>
#include <string.h>

typedef struct { double t; } ModelState;       /* time since the start */

static void model_start(ModelState *st, const double *par) { (void)par; st->t = 0.0; }

static void figure8_pose(double s, double r, double c, double pose[5]) {
    double th = asin(r / c), d = 2.0 * sqrt(c * c - r * r), arc = r * (M_PI + 2.0 * th), half = d / 2.0;
    double lap = 2.0 * d + 2.0 * arc;
    s = fmod(s, lap);
    if (s < 0) s += lap;
    if (s < half) { pose[0] = s * cos(th); pose[1] = s * sin(th); pose[2] = th; pose[3] = 0.0; pose[4] = 0.0; return; }
    s -= half;
    if (s < arc) {
        double phi = th + M_PI / 2.0 - s / r;
        pose[0] = c + r * cos(phi); pose[1] = r * sin(phi); pose[2] = th - s / r; pose[3] = -1.0 / r; pose[4] = 1.0;
        return;
    }
    s -= arc;
    if (s < d) {
        double h = M_PI - th, x0 = half * cos(-th), y0 = half * sin(-th);
        pose[0] = x0 + s * cos(h); pose[1] = y0 + s * sin(h); pose[2] = h; pose[3] = 0.0; pose[4] = 0.0;
        return;
    }
    s -= d;
    if (s < arc) {
        double phi = -th - M_PI / 2.0 + M_PI + s / r;
        pose[0] = -c + r * cos(phi); pose[1] = r * sin(phi); pose[2] = M_PI - th + s / r; pose[3] = 1.0 / r; pose[4] = 1.0;
        return;
    }
    s -= arc;
    pose[0] = -half * cos(th) + s * cos(th); pose[1] = -half * sin(th) + s * sin(th); pose[2] = th; pose[3] = 0.0;
    pose[4] = 0.0;
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    (void)in;
    double v = p[P_speed], T = p[P_ramp_time], tau = st->t > 0 ? st->t : 0.0, s, sdot, pose[5];
    if (tau < T) { s = v * tau * tau / (2.0 * T); sdot = v * tau / T; }
    else { s = v * (tau - T / 2.0); sdot = v; }
    figure8_pose(s, p[P_radius], p[P_centre_offset], pose);
    out[OUT_x_ref] = pose[0] + p[P_x_origin];
    out[OUT_y_ref] = pose[1] + p[P_y_origin];
    out[OUT_xdot_ref] = sdot * cos(pose[2]);
    out[OUT_ydot_ref] = sdot * sin(pose[2]);
    out[OUT_heading_ref] = pose[2];
    out[OUT_yaw_rate_ref] = sdot * pose[3];
    out[OUT_speed_ref] = sdot;
    out[OUT_segment] = pose[4];
    out[OUT_path_length] = s;
    st->t += MODEL_PERIOD;
}
