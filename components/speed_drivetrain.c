/* Speed drivetrain (components/speed_drivetrain.py): a valve with a dead-band moves the pedal at
 * a rate proportional to its opening; the speed lags the pedal's steady-state speed
 * v_ss = v_max ((p - p0) / (1 - p0))^n with time constant tau, integrated in SUBSTEPS substeps. */
#define MODEL_HAS_OUTPUTS 1                /* model_outputs: y_k = g(x_k), read by the compiled loop */
typedef struct { double pedal, v; } ModelState;

static void model_start(ModelState *st, const double *p) { st->pedal = p[P_pedal0]; st->v = p[P_speed0]; }

static double steady_state_speed(double pedal, double v_max, double p0, double expo) {
    double x = (pedal - p0) / (1.0 - p0);
    x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    return v_max * pow(x, expo);
}

static double valve_opening(double voltage, double neutral, double deadband, double full_scale) {
    double e = voltage - neutral, excess = fabs(e) - deadband;
    if (excess <= 0.0) return 0.0;
    double o = excess / (full_scale - deadband);
    return copysign(o < 1.0 ? o : 1.0, e);
}

static void model_outputs(const ModelState *st, const double *p, double *out) {
    (void)p;
    out[OUT_pedal_position] = st->pedal;
    out[OUT_speed] = st->v;
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    model_outputs(st, p, out);
    double h = MODEL_PERIOD / SUBSTEPS, vn = p[P_neutral_voltage];
    double opening = valve_opening(in[IN_pedal_valve_voltage], vn, p[P_deadband], p[P_voltage_max] - vn);
    double decay = exp(-h / p[P_time_constant]), rate = h * opening * p[P_pedal_rate_max];
    double pedal = st->pedal, v = st->v;
    if (rate == 0.0 || (pedal == 0.0 && rate < 0.0) || (pedal == 1.0 && rate > 0.0)) {
        double v_ss = steady_state_speed(pedal, p[P_max_speed], p[P_pedal_dead_zone], p[P_speed_exponent]);
        v = v_ss + (v - v_ss) * pow(decay, SUBSTEPS);
    } else {
        for (int i = 0; i < SUBSTEPS; i++) {
            pedal += rate;
            pedal = pedal < 0.0 ? 0.0 : (pedal > 1.0 ? 1.0 : pedal);
            double v_ss = steady_state_speed(pedal, p[P_max_speed], p[P_pedal_dead_zone], p[P_speed_exponent]);
            v = v_ss + (v - v_ss) * decay;
        }
    }
    st->pedal = pedal;
    st->v = v;
}
