/* Steering hydraulics (components/steering_hydraulics.py): a PI on the quantised wheel angle
 * drives the valve voltage; the valve (dead-band, first-order spool lag) sets the wheel rate;
 * mechanical stops; SUBSTEPS substeps per period. Optional command transport delay of
 * DELAY_STEPS periods (a FIFO), angle dead-band, quantisation guard and extra rate limit. */
#ifndef DELAY_CAPACITY                     /* the FIFO's room: the delay itself, or a bound when the */
#define DELAY_CAPACITY DELAY_STEPS         /* delay is a run-time value (the compiled loop)          */
#endif
#define MODEL_HAS_OUTPUTS 1                /* model_outputs: y_k = g(x_k), read by the compiled loop */
typedef struct {
    double delta, opening, integral, voltage, rate;
    double history[DELAY_CAPACITY + 1];
    int head, filled;
} ModelState;

static double quantize(double value, double resolution) {
    return resolution > 0 ? resolution * nearbyint(value / resolution) : value;    /* round half to even */
}

static void model_start(ModelState *st, const double *p) {
    memset(st, 0, sizeof *st);
    st->delta = p[P_delta0];
    st->voltage = 6.0;                     /* the output's declared start, as the Python component */
    for (int i = 0; i < DELAY_STEPS; i++) st->history[i] = 0.0;
    st->filled = DELAY_STEPS;
    st->head = DELAY_STEPS % (DELAY_STEPS + 1);
}

static void model_outputs(const ModelState *st, const double *p, double *out) {
    out[OUT_steer_angle] = st->delta;
    out[OUT_steer_angle_measured] = quantize(st->delta, p[P_potentiometer_resolution]);
    out[OUT_valve_voltage] = st->voltage;
    out[OUT_steer_rate] = st->rate;
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    model_outputs(st, p, out);
    const int n = DELAY_STEPS + 1;
    st->history[st->head] = in[IN_steer_angle_cmd];
    st->head = (st->head + 1) % n;
    if (st->filled < n) st->filled++;
    double cmd = st->history[st->filled < n ? 0 : st->head];
    double h = MODEL_PERIOD / SUBSTEPS, vn = p[P_neutral_voltage], db = p[P_deadband];
    double opening_scale = 1.0 / (p[P_voltage_max] - vn - db);
    double rate_step = h * p[P_max_flow] / p[P_volume_per_rad];
    double lim = p[P_angle_limit], res = p[P_potentiometer_resolution];
    double alpha = 1.0 - exp(-h / p[P_valve_time_constant]);
    double kp = p[P_kp], ki_h = p[P_ki] * h, v_lo = p[P_voltage_min] - vn, v_hi = p[P_voltage_max] - vn;
    double i_lim = p[P_integral_limit], integral = st->integral;
    double dead = p[P_angle_deadband] + (p[P_quantization_guard] != 0.0 ? 0.5 * res : 0.0);
    double max_move = p[P_rate_limit] > 0 ? p[P_rate_limit] * h : INFINITY;
    double delta = st->delta, opening = st->opening, v_rel = 0.0;
    double inv_res = res > 0 ? 1.0 / res : 0.0;
    for (int k = 0; k < SUBSTEPS; k++) {
        double error = cmd - (inv_res != 0.0 ? res * nearbyint(delta * inv_res) : delta);
        if (dead != 0.0) error = error > dead ? error - dead : (error < -dead ? error + dead : 0.0);
        double raw = kp * error + integral;
        int windup;
        if (raw > v_hi) { v_rel = v_hi; windup = error > 0; }
        else if (raw < v_lo) { v_rel = v_lo; windup = error < 0; }
        else { v_rel = raw; windup = 0; }
        if (!windup) {
            integral += ki_h * error;
            integral = integral > i_lim ? i_lim : (integral < -i_lim ? -i_lim : integral);
        }
        double target;
        if (v_rel > db) { target = (v_rel - db) * opening_scale; target = target > 1.0 ? 1.0 : target; }
        else if (v_rel < -db) { target = (v_rel + db) * opening_scale; target = target < -1.0 ? -1.0 : target; }
        else target = 0.0;
        opening += alpha * (target - opening);
        double move = rate_step * opening;
        move = move > max_move ? max_move : (move < -max_move ? -max_move : move);
        delta += move;
        delta = delta > lim ? lim : (delta < -lim ? -lim : delta);
    }
    st->integral = integral;
    st->voltage = vn + v_rel;
    st->delta = delta;
    st->opening = opening;
    double r = opening * rate_step;
    r = r > max_move ? max_move : (r < -max_move ? -max_move : r);
    st->rate = fabs(delta) < lim ? r / h : 0.0;
}
