/* Tractor yaw plant (components/tractor_yaw_plant.py, components/models/yaw_dynamics.py): the
 * linear yaw dynamics of YAW_MODEL (0 bicycle, 1 RLF, 2 RLFR; state [v_y, gamma, alpha_f, alpha_r];
 * 3 the transfer function TF_A, TF_B, TF_C of order TF_ORDER in controllable canonical form, not
 * speed dependent, gamma = TF_C z and v_y = l_r gamma)
 * at the longitudinal speed, discretised exactly over the period (zero-order hold: [Ad Bd; 0 I] =
 * expm([A B; 0 0] h), the speed quantised to speed_cache_resolution as the Python cache does),
 * and the pose at the CG by the midpoint rule; below min_speed the slip equations use min_speed
 * and the yaw rate is scaled by v / min_speed. Extensions: steer_angle_offset, cornering speed
 * slope, side slope (a lateral acceleration into dv_y/dt; the roll and pitch it gives, models/terrain.py),
 * antenna lever arm with its height turned by the roll and pitch. Steering geometry: with STEER_TAN
 * the dynamics are driven by tan(delta), delta clipped to +-MAX_TAN_ANGLE (the turn without slip
 * v tan(delta) / L; tractor_yaw_plant.steer_input). */
#if YAW_MODEL == 3
#define NS TF_ORDER
#else
#define NS (YAW_MODEL + 2)
#endif
#define NA (NS + 2)                     /* augmented: states, delta, lateral acceleration */
#define GRAVITY 9.81
#define CACHE_KEY 12                    /* what the discretisation depends on: speed and parameters */
#define MODEL_HAS_OUTPUTS 1             /* model_outputs: y_k = g(x_k), read by the compiled loop */

#define CACHE_SLOTS 64                  /* direct-mapped by the quantised speed */

/* E = expm([A B; 0 0] h) is kept per key (the quantised speed and the parameters it depends on):
 * each speed's exponential is computed once, as the Python plant caches it */
typedef struct { double key[CACHE_KEY], E[NA][NA]; int used; } CacheSlot;
typedef struct { double z[NS], x, y, psi, v_out, gamma_out, vy_out; CacheSlot cache[CACHE_SLOTS]; } ModelState;

static void model_start(ModelState *st, const double *p) {
    memset(st, 0, sizeof *st);
    st->x = p[P_x0]; st->y = p[P_y0]; st->psi = p[P_psi0];
}

/* exp(M) for an NA x NA matrix: scaling and squaring with a degree-12 Taylor polynomial
 * (the scaled norm is at most 1/4; as yaw_dynamics.expm_batched). */
static void expm_small(double M[NA][NA], double E[NA][NA]) {
    double norm = 0.0;
    for (int j = 0; j < NA; j++) {
        double col = 0.0;
        for (int i = 0; i < NA; i++) col += fabs(M[i][j]);
        norm = col > norm ? col : norm;
    }
    int squarings = norm > 0.25 ? (int)ceil(log2(norm / 0.25)) : 0;
    double scale = ldexp(1.0, -squarings), X[NA][NA], term[NA][NA], tmp[NA][NA];
    for (int i = 0; i < NA; i++)
        for (int j = 0; j < NA; j++) { X[i][j] = M[i][j] * scale; term[i][j] = E[i][j] = (i == j); }
    for (int k = 1; k <= 12; k++) {
        for (int i = 0; i < NA; i++)
            for (int j = 0; j < NA; j++) {
                double s = 0.0;
                for (int l = 0; l < NA; l++) s += term[i][l] * X[l][j];
                tmp[i][j] = s / k;
            }
        for (int i = 0; i < NA; i++)
            for (int j = 0; j < NA; j++) { term[i][j] = tmp[i][j]; E[i][j] += tmp[i][j]; }
    }
    for (int q = 0; q < squarings; q++) {
        for (int i = 0; i < NA; i++)
            for (int j = 0; j < NA; j++) {
                double s = 0.0;
                for (int l = 0; l < NA; l++) s += E[i][l] * E[l][j];
                tmp[i][j] = s;
            }
        memcpy(E, tmp, sizeof tmp);
    }
}

/* A (NS x NS) and B (delta column) of yaw_dynamics.state_space at speed v */
#if YAW_MODEL == 3
static void state_space(const double *p, double v, double cscale, double A[NS][NS], double B[NS]) {
    (void)p; (void)v; (void)cscale;
    for (int i = 0; i < NS; i++) {
        for (int j = 0; j < NS; j++) A[i][j] = TF_A[i * NS + j];
        B[i] = TF_B[i];
    }
}
#else
static void state_space(const double *p, double v, double cscale, double A[NS][NS], double B[NS]) {
    double m = p[P_m], I = p[P_I], lf = p[P_l_f], lr = p[P_l_r];
    double Cf = p[P_C_f] * cscale, Cr = p[P_C_r] * cscale, sf = p[P_sigma_f];
    memset(A, 0, sizeof(double) * NS * NS);
    memset(B, 0, sizeof(double) * NS);
#if YAW_MODEL == 0
    (void)sf;
    A[0][0] = -(Cf + Cr) / (m * v); A[0][1] = -v - (Cf * lf - Cr * lr) / (m * v);
    A[1][0] = -(lf * Cf - lr * Cr) / (I * v); A[1][1] = -(lf * lf * Cf + lr * lr * Cr) / (I * v);
    B[0] = Cf / m; B[1] = lf * Cf / I;
#elif YAW_MODEL == 1
    A[0][0] = -Cr / (m * v); A[0][1] = -v + Cr * lr / (m * v); A[0][2] = -Cf / m;
    A[1][0] = lr * Cr / (I * v); A[1][1] = -lr * lr * Cr / (I * v); A[1][2] = -lf * Cf / I;
    A[2][0] = 1.0 / sf; A[2][1] = lf / sf; A[2][2] = -v / sf;
    B[2] = -v / sf;
#else
    double sr = p[P_sigma_r];
    A[0][1] = -v; A[0][2] = -Cf / m; A[0][3] = -Cr / m;
    A[1][2] = -lf * Cf / I; A[1][3] = lr * Cr / I;
    A[2][0] = 1.0 / sf; A[2][1] = lf / sf; A[2][2] = -v / sf;
    A[3][0] = 1.0 / sr; A[3][1] = -lr / sr; A[3][3] = -v / sr;
    B[2] = -v / sf;
#endif
}
#endif

/* (gamma, v_y) of the dynamic state z before the low-speed scaling */
static void yaw_rate_lateral(const double *z, const double *p, double *gamma, double *vy) {
#if YAW_MODEL == 3
    double g = 0.0;
    for (int i = 0; i < NS; i++) g += TF_C[i] * z[i];
    *gamma = g;
    *vy = p[P_l_r] * g;
#else
    (void)p;
    *gamma = z[1];
    *vy = z[0];
#endif
}

/* outputs of t_k (tractor_yaw_plant._set_outputs) */
static void model_outputs(const ModelState *st, const double *p, double *out) {
    double lr = p[P_l_r], c = cos(st->psi), s = sin(st->psi), v = st->v_out, gamma = st->gamma_out;
    out[OUT_yaw_rate] = gamma; out[OUT_lateral_velocity] = st->vy_out; out[OUT_heading] = st->psi;
    out[OUT_x_cg] = st->x; out[OUT_y_cg] = st->y;
    out[OUT_x_rear] = st->x - lr * c; out[OUT_y_rear] = st->y - lr * s;
    double v_lat_rear = st->vy_out - lr * gamma;
    out[OUT_vel_east_rear] = v * c - v_lat_rear * s;
    out[OUT_vel_north_rear] = v * s + v_lat_rear * c;
    /* the plane's gradient and the attitude at the heading (terrain.attitude, terrain.lever_offset) */
    double tn = -tan(p[P_slope_angle]), gx = tn * cos(p[P_slope_downhill_heading]), gy = tn * sin(p[P_slope_downhill_heading]);
    double pitch = atan(gx * c + gy * s), roll = atan((-gx * s + gy * c) * cos(pitch));
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch);
    double fa = p[P_antenna_forward] * cp - p[P_antenna_left] * sp * sr - p[P_antenna_height] * sp * cr;
    double fb = p[P_antenna_left] * cr - p[P_antenna_height] * sr;
    double dx = c * fa - s * fb, dy = s * fa + c * fb;
    out[OUT_roll] = roll; out[OUT_pitch] = pitch;
    out[OUT_x_antenna] = out[OUT_x_rear] + dx; out[OUT_y_antenna] = out[OUT_y_rear] + dy;
    out[OUT_vel_east_antenna] = out[OUT_vel_east_rear] - gamma * dy;
    out[OUT_vel_north_antenna] = out[OUT_vel_north_rear] + gamma * dx;
    double pull = GRAVITY * sin(p[P_slope_angle]);
    out[OUT_slope_pull_east] = pull * cos(p[P_slope_downhill_heading]);
    out[OUT_slope_pull_north] = pull * sin(p[P_slope_downhill_heading]);
}

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    model_outputs(st, p, out);
    /* step over [t_k, t_k+1) with the inputs of t_k */
    double h = MODEL_PERIOD, speed_in = in[IN_speed], delta = in[IN_steer_angle] + p[P_steer_angle_offset];
#if STEER_TAN
    delta = tan(delta > MAX_TAN_ANGLE ? MAX_TAN_ANGLE : (delta < -MAX_TAN_ANGLE ? -MAX_TAN_ANGLE : delta));
#endif
    double vmin = p[P_min_speed], speed = fabs(speed_in), v_eff = speed >= vmin ? speed : vmin;
    double low = speed >= vmin ? 1.0 : speed / vmin, res = p[P_speed_cache_resolution];
    double vq = nearbyint(v_eff / res) * res;
    double cscale = 1.0;
    if (p[P_cornering_speed_slope] != 0.0) {
        cscale = 1.0 + p[P_cornering_speed_slope] * (vq - p[P_cornering_reference_speed]);
        cscale = cscale > 0.2 ? cscale : 0.2;
    }
    double key[CACHE_KEY] = {vq, p[P_m], p[P_I], p[P_l_f], p[P_l_r], p[P_C_f], p[P_C_r], p[P_sigma_f],
                             p[P_sigma_r], p[P_cornering_speed_slope], p[P_cornering_reference_speed], h};
    CacheSlot *slot = &st->cache[(unsigned long)nearbyint(v_eff / res) % CACHE_SLOTS];
    double (*E)[NA] = slot->E;
    if (!slot->used || memcmp(key, slot->key, sizeof key) != 0) {
        double A[NS][NS], B[NS], M[NA][NA];
        state_space(p, vq, cscale, A, B);
        memset(M, 0, sizeof M);
        for (int i = 0; i < NS; i++) {
            for (int j = 0; j < NS; j++) M[i][j] = A[i][j] * h;
            M[i][NS] = B[i] * h;
        }
        M[0][NS + 1] = h;                               /* E = [1, 0, ...]: lateral acceleration */
        expm_small(M, slot->E);
        memcpy(slot->key, key, sizeof key);
        slot->used = 1;
    }
    double a_lat = GRAVITY * sin(p[P_slope_angle]) * sin(p[P_slope_downhill_heading] - st->psi);
    double gamma0, vy0, gamma1, vy1, z[NS];
    yaw_rate_lateral(st->z, p, &gamma0, &vy0);
    for (int i = 0; i < NS; i++) {
        double acc = E[i][NS] * delta + (p[P_slope_angle] != 0.0 ? E[i][NS + 1] * a_lat : 0.0);
        for (int j = 0; j < NS; j++) acc += E[i][j] * st->z[j];
        z[i] = acc;
    }
    memcpy(st->z, z, sizeof z);
    yaw_rate_lateral(z, p, &gamma1, &vy1);
    gamma1 *= low; vy1 *= low;
    gamma0 *= low; vy0 *= low;
    double psi_mid = st->psi + 0.25 * h * (gamma0 + gamma1), vy_mid = 0.5 * (vy0 + vy1);
    double cm = cos(psi_mid), sm = sin(psi_mid);
    st->x += h * (speed_in * cm - vy_mid * sm);
    st->y += h * (speed_in * sm + vy_mid * cm);
    st->psi += 0.5 * h * (gamma0 + gamma1);
    st->v_out = speed_in; st->gamma_out = gamma1; st->vy_out = vy1;
}
