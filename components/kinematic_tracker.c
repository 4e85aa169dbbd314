/* Kinematic tracker (components/kinematic_tracker.py): no state; guidance_laws.c: tracker_law. */
#include "guidance_laws.c"

typedef struct { int unused; } ModelState;

static void model_start(ModelState *st, const double *p) { (void)p; st->unused = 0; }

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    (void)st;
    double tr[4];
    tracker_law(in[IN_x_ref], in[IN_y_ref], in[IN_xdot_ref], in[IN_ydot_ref], in[IN_x], in[IN_y], in[IN_heading],
                in[IN_yaw_rate_ref], in[IN_lateral_velocity], p[P_k_s], p[P_k_c], p[P_l_r], p[P_lookahead], tr);
    out[OUT_speed_desired] = tr[0]; out[OUT_yaw_rate_desired] = tr[1]; out[OUT_error_x] = tr[2]; out[OUT_error_y] = tr[3];
}
