/* Yaw-rate MPC (components/yaw_rate_mpc.py): the condensed MPC of the design compiled in (NX, NC,
 * MPC_*); the internal model is driven by the measured wheel angle after the first sample when
 * MEASURED_INPUT; guidance_laws.c: mpc_step. */
#include "guidance_laws.c"

typedef struct { MPCState mpc; int started; } ModelState;

static void model_start(ModelState *st, const double *p) { (void)p; memset(st, 0, sizeof *st); }

static void model_sample(ModelState *st, const double *p, const double *in, double *out) {
    double status;
    out[OUT_steer_angle_cmd] = mpc_step(&st->mpc, p[P_steer_limit], p[P_steer_rate_limit] * MODEL_PERIOD,
                                        in[IN_yaw_rate_ref], in[IN_yaw_rate], in[IN_steer_angle],
                                        MEASURED_INPUT && st->started, &status);
    out[OUT_qp_status] = status;
    st->started = 1;
}
