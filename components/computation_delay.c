/* Computation delay (components/computation_delay.py): the commands pass through a FIFO of
 * DELAY_SAMPLES samples (0: straight through, direct feedthrough). */
#ifndef DELAY_CAPACITY                     /* the FIFO's room: the delay itself, or a bound when the */
#define DELAY_CAPACITY DELAY_SAMPLES       /* delay is a run-time value (the compiled loop)          */
#endif
typedef struct { double steer[DELAY_CAPACITY + 1], volts[DELAY_CAPACITY + 1]; int head, filled; } ModelState;

static void model_start(ModelState *st, const double *par) { (void)par; memset(st, 0, sizeof *st); }

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    (void)p;
    const int n = DELAY_SAMPLES + 1;
    st->steer[st->head] = in[IN_steer_angle_cmd];
    st->volts[st->head] = in[IN_pedal_valve_voltage];
    st->head = (st->head + 1) % n;
    if (st->filled < n) st->filled++;
    int oldest = st->filled < n ? 0 : st->head;          /* deque(maxlen=n)[0] */
    out[OUT_steer_angle_cmd_out] = st->steer[oldest];
    out[OUT_pedal_valve_voltage_out] = st->volts[oldest];
}
