/* Speed PID cascade (components/speed_pid.py): outer speed -> pedal position with feed-forward,
 * inner pedal position -> valve voltage; guidance_laws.c: pid_update. */
#include "guidance_laws.c"

typedef struct { PIDState outer, inner; } ModelState;

static void model_start(ModelState *st, const double *p) { (void)p; memset(st, 0, sizeof *st); }

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    double h = MODEL_PERIOD, v_d = in[IN_speed_desired], vn = p[P_neutral_voltage];
    double pedal_cmd = pid_update(&st->outer, p[P_kp], p[P_ki], p[P_kd], 0.0, 1.0, p[P_integral_limit],
                                  v_d - in[IN_speed], h, p[P_feedforward] * v_d);
    double volts = pid_update(&st->inner, p[P_inner_kp], p[P_inner_ki], p[P_inner_kd], p[P_voltage_min] - vn,
                              p[P_voltage_max] - vn, INFINITY, pedal_cmd - in[IN_pedal_position], h, 0.0);
    out[OUT_pedal_position_cmd] = pedal_cmd;
    out[OUT_pedal_valve_voltage] = vn + volts;
}
