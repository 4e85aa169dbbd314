/* GPS sensor (components/gps_sensor.py): the antenna's position and velocity LAG samples late,
 * with white noise, an optional Gauss-Markov bias (b+ = phi b + sqrt(1 - phi^2) sigma_b w) and
 * outages (an outage starts with dropout_probability per sample and lasts dropout_duration).
 * Random numbers: xoshiro256** seeded by the parameter `seed` (splitmix64), normals by Box-Muller;
 * the stream differs from numpy's, the distributions are the same. */
#ifndef LAG_CAPACITY                       /* the history's room: the lag itself, or a bound when the */
#define LAG_CAPACITY LAG                   /* lag is a run-time value (the compiled loop)             */
#endif
typedef struct {
    double hist[LAG_CAPACITY + 1][4];
    int head, filled, outage_left;
    double last_fix_time, t, bias[2], held[4];
    unsigned long long rng[4];
    double spare;
    int has_spare;
} ModelState;

static unsigned long long splitmix64(unsigned long long *x) {
    unsigned long long z = (*x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static unsigned long long rotl(unsigned long long x, int k) { return (x << k) | (x >> (64 - k)); }

static double uniform01(ModelState *st) {                 /* xoshiro256**, 53 bits in [0, 1) */
    unsigned long long *s = st->rng, r = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0]; s[3] ^= s[1]; s[1] ^= s[2]; s[0] ^= s[3]; s[2] ^= t; s[3] = rotl(s[3], 45);
    return (double)(r >> 11) * 0x1.0p-53;
}

static double normal(ModelState *st) {
    if (st->has_spare) { st->has_spare = 0; return st->spare; }
    double u1 = uniform01(st), u2 = uniform01(st);
    double r = sqrt(-2.0 * log(1.0 - u1)), a = 2.0 * M_PI * u2;
    st->spare = r * sin(a);
    st->has_spare = 1;
    return r * cos(a);
}

static void model_start(ModelState *st, const double *p) {
    memset(st, 0, sizeof *st);
    unsigned long long seed = (unsigned long long)p[P_seed];
    for (int i = 0; i < 4; i++) st->rng[i] = splitmix64(&seed);
    if (p[P_bias_std] > 0) { st->bias[0] = normal(st) * p[P_bias_std]; st->bias[1] = normal(st) * p[P_bias_std]; }
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    const int n = LAG + 1;
    double *slot = st->hist[st->head];
    slot[0] = in[IN_x_true]; slot[1] = in[IN_y_true]; slot[2] = in[IN_vel_east_true]; slot[3] = in[IN_vel_north_true];
    st->head = (st->head + 1) % n;
    if (st->filled < n) st->filled++;
    const double *old = st->hist[st->filled < n ? 0 : st->head];
    double t = st->t;
    st->t += MODEL_PERIOD;
    if (st->outage_left == 0 && p[P_dropout_probability] > 0 && uniform01(st) < p[P_dropout_probability]) {
        int steps = (int)nearbyint(p[P_dropout_duration] / MODEL_PERIOD);
        st->outage_left = steps > 1 ? steps : 1;
    }
    double noise[4];
    for (int i = 0; i < 4; i++) noise[i] = normal(st);
    if (p[P_bias_std] > 0) {
        double phi = exp(-MODEL_PERIOD / p[P_bias_time_constant]), k = sqrt(1 - phi * phi) * p[P_bias_std];
        double w0 = normal(st), w1 = normal(st);
        st->bias[0] = phi * st->bias[0] + k * w0;
        st->bias[1] = phi * st->bias[1] + k * w1;
    }
    if (st->outage_left > 0) {
        st->outage_left -= 1;
        out[OUT_x] = st->held[0]; out[OUT_y] = st->held[1];
        out[OUT_vel_east] = st->held[2]; out[OUT_vel_north] = st->held[3];
        out[OUT_fix_valid] = out[OUT_fix_quality] = 0.0;
        out[OUT_fix_age] = t - st->last_fix_time;
        return;
    }
    double sp = p[P_position_noise_std], sv = p[P_velocity_noise_std];
    st->held[0] = old[0] + sp * noise[0] + st->bias[0];
    st->held[1] = old[1] + sp * noise[1] + st->bias[1];
    st->held[2] = old[2] + sv * noise[2];
    st->held[3] = old[3] + sv * noise[3];
    out[OUT_x] = st->held[0]; out[OUT_y] = st->held[1];
    out[OUT_vel_east] = st->held[2]; out[OUT_vel_north] = st->held[3];
    out[OUT_fix_valid] = 1.0;
    out[OUT_fix_quality] = 4.0;                 /* GGA quality: RTK fixed */
    st->last_fix_time = t;
    out[OUT_fix_age] = LATENCY;
}
