/* One instance of a sampled model (a model core defining ModelState, model_start, model_sample and
 * the MODEL_* constants), with the co-simulation semantics both FMI wrappers share:
 *
 * - sample instants t_k = t0 + k * MODEL_PERIOD; at an instant the outputs are y_k = g(x_k, u_k),
 *   computed when an output is read after an input or parameter changed (get after set recomputes,
 *   any number of times); doStep(t_k, h) commits x_k+1 = f(x_k, u_k) once;
 * - between instants the outputs hold: a communication step h divides MODEL_PERIOD (h = period
 *   included), or is a whole multiple m of it and is taken as m samples with the inputs held (a
 *   master's default step); doStep must start where the last one ended;
 * - the call sequence is checked (instantiated -> initialization -> step -> terminated; reset from
 *   any), an input or parameter that is NaN or infinite is refused; each refusal is an error status
 *   with a logger message that names the variable or the call.
 * Parameters are tunable, or fixed (MODEL_PAR_FIXED: set before the initialization ends).
 * Value references: parameters 0.., time VR_TIME, inputs VR_INPUT0.., outputs VR_OUTPUT0.. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef MODEL_PAR_FIXED
#define MODEL_PAR_FIXED 0     /* 1: parameters are set before the initialization ends (variability fixed) */
#endif
#define VR_TIME 999u            /* FMI 3.0's independent variable */
#define VR_INPUT0 1000u
#define VR_OUTPUT0 2000u
#define SI_INPUT_BOUND 1e9      /* |input| at most (SI): the declared min/max of every input (sampled_fmu.INPUT_BOUND) */

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED } Mode;
typedef enum { SI_OK = 0, SI_ERROR = 3 } SIStatus;        /* fmi2/fmi3 OK and Error have these values */

typedef void (*SILogger)(void *env, const char *instance, int error, const char *message);

typedef struct {
    double par[MODEL_NPAR], in[MODEL_NIN + 1], out[MODEL_NOUT];
    ModelState state, next;       /* x_k, and x_k+1 computed with the outputs of the pending sample */
    Mode mode;
    double t0, time;              /* start time and the current communication point */
    int pending;                  /* outputs and `next` are up to date with the inputs of `time` */
    int stepped;                  /* a sample has been committed (the state no longer follows par) */
    SILogger log;
    void *log_env;
    char *name;
} SampledInstance;

static void si_log(SampledInstance *s, const char *fmt, ...) {
    char message[512];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    if (s && s->log) s->log(s->log_env, s->name ? s->name : "", 1, message);
}

static void si_reset(SampledInstance *s) {
    memcpy(s->par, MODEL_PAR_START, sizeof s->par);
#ifdef MODEL_IN_START
    memcpy(s->in, MODEL_IN_START, sizeof(double) * MODEL_NIN);   /* the inputs' declared starts */
#else
    memset(s->in, 0, sizeof s->in);
#endif
    memset(s->out, 0, sizeof s->out);
    model_start(&s->state, s->par);
    s->mode = MODE_INSTANTIATED;
    s->t0 = s->time = 0.0;
    s->pending = 0;
    s->stepped = 0;
}

static SampledInstance *si_new(const char *name, SILogger log, void *env) {
    SampledInstance *s = (SampledInstance *)calloc(1, sizeof(SampledInstance));
    if (!s) return NULL;
    s->log = log;
    s->log_env = env;
    s->name = (char *)malloc(strlen(name ? name : "") + 1);
    if (s->name) strcpy(s->name, name ? name : "");
    si_reset(s);
    return s;
}

static void si_free(SampledInstance *s) {
    if (!s) return;
    free(s->name);
    free(s);
}

static int si_check_mode(SampledInstance *s, const char *call, unsigned allowed) {
    static const char *const names[] = {"instantiated", "initialization", "step", "terminated"};
    if (allowed & (1u << s->mode)) return 1;
    si_log(s, "%s is not allowed in %s mode", call, names[s->mode]);
    return 0;
}
#define IN_MODES(...) si_modes((Mode[]){__VA_ARGS__}, sizeof((Mode[]){__VA_ARGS__}) / sizeof(Mode))
static unsigned si_modes(const Mode *modes, size_t n) {
    unsigned mask = 0;
    for (size_t i = 0; i < n; i++) mask |= 1u << modes[i];
    return mask;
}

static double si_grid_offset(const SampledInstance *s, double t) {
    /* (t - t0) / period - nearest integer, in periods */
    double k = (t - s->t0) / MODEL_PERIOD;
    return k - floor(k + 0.5);
}

static int si_at_sample(const SampledInstance *s) {
    return fabs(si_grid_offset(s, s->time)) < 1e-6;
}

/* The outputs of the current communication point (a sample instant recomputes when stale). */
static void si_refresh(SampledInstance *s) {
    if (s->pending || !si_at_sample(s)) return;
    if (!s->stepped) model_start(&s->state, s->par);      /* the initial state follows the parameters */
    s->next = s->state;
    model_sample(&s->next, s->par, s->in, s->out);
    s->pending = 1;
}

static SIStatus si_setup(SampledInstance *s, double start_time) {
    if (!si_check_mode(s, "setting up the experiment", IN_MODES(MODE_INSTANTIATED, MODE_INITIALIZATION)))
        return SI_ERROR;
    s->t0 = s->time = start_time;
    s->pending = 0;
    return SI_OK;
}

static SIStatus si_enter_initialization(SampledInstance *s) {
    if (!si_check_mode(s, "entering initialization mode", IN_MODES(MODE_INSTANTIATED))) return SI_ERROR;
    s->mode = MODE_INITIALIZATION;
    return SI_OK;
}

static SIStatus si_exit_initialization(SampledInstance *s) {
    if (!si_check_mode(s, "exiting initialization mode", IN_MODES(MODE_INITIALIZATION))) return SI_ERROR;
    s->mode = MODE_STEP;
    return SI_OK;
}

static SIStatus si_terminate(SampledInstance *s) {
    if (!si_check_mode(s, "terminate", IN_MODES(MODE_STEP, MODE_INITIALIZATION))) return SI_ERROR;
    s->mode = MODE_TERMINATED;
    return SI_OK;
}

static SIStatus si_get(SampledInstance *s, const unsigned vr[], size_t n, double v[]) {
    if (n && !si_check_mode(s, "reading a variable",
                            IN_MODES(MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED, MODE_INSTANTIATED)))
        return SI_ERROR;
    for (size_t i = 0; i < n; i++) {
        unsigned r = vr[i];
        if (r < MODEL_NPAR) v[i] = s->par[r];
        else if (r == VR_TIME) v[i] = s->time;
        else if (r >= VR_INPUT0 && r < VR_INPUT0 + MODEL_NIN) v[i] = s->in[r - VR_INPUT0];
        else if (r >= VR_OUTPUT0 && r < VR_OUTPUT0 + MODEL_NOUT) {
            if (s->mode == MODE_INSTANTIATED) {
                si_log(s, "output %s cannot be read before initialization mode",
                       MODEL_OUT_NAMES[r - VR_OUTPUT0]);
                return SI_ERROR;
            }
            si_refresh(s);
            v[i] = s->out[r - VR_OUTPUT0];
        } else {
            si_log(s, "no variable has value reference %u", r);
            return SI_ERROR;
        }
    }
    return SI_OK;
}

static SIStatus si_set(SampledInstance *s, const unsigned vr[], size_t n, const double v[]) {
    if (n && !si_check_mode(s, "setting a variable", IN_MODES(MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP)))
        return SI_ERROR;
    for (size_t i = 0; i < n; i++) {
        unsigned r = vr[i];
        const char *what;
        double *slot;
        if (r < MODEL_NPAR) {
            what = MODEL_PAR_NAMES[r];
            slot = &s->par[r];
            if (MODEL_PAR_FIXED && s->mode == MODE_STEP) {
                si_log(s, "%s is a fixed parameter: set it before the initialization ends", what);
                return SI_ERROR;
            }
        } else if (r >= VR_INPUT0 && r < VR_INPUT0 + MODEL_NIN) {
            what = MODEL_IN_NAMES[r - VR_INPUT0];
            slot = &s->in[r - VR_INPUT0];
        } else if (r >= VR_OUTPUT0 && r < VR_OUTPUT0 + MODEL_NOUT) {
            si_log(s, "%s is an output and cannot be set", MODEL_OUT_NAMES[r - VR_OUTPUT0]);
            return SI_ERROR;
        } else {
            si_log(s, "no variable has value reference %u", r);
            return SI_ERROR;
        }
        if (!isfinite(v[i])) {
            si_log(s, "%s = %g refused: the value must be finite", what, v[i]);
            return SI_ERROR;
        }
        if (r >= VR_INPUT0 && fabs(v[i]) > SI_INPUT_BOUND) {      /* the declared range: the state is never poisoned */
            si_log(s, "%s = %g refused: beyond its declared range [-%g, %g]", what, v[i], SI_INPUT_BOUND, SI_INPUT_BOUND);
            return SI_ERROR;
        }
        if (*slot != v[i]) s->pending = 0;
        *slot = v[i];
    }
    return SI_OK;
}

/* One step of h <= MODEL_PERIOD from the current point: commit the sample due there, if any. */
static void si_advance(SampledInstance *s, double h) {
    if (si_at_sample(s)) {
        si_refresh(s);
        s->state = s->next;
        s->stepped = 1;
    }
    s->time += h;
    if (fabs(si_grid_offset(s, s->time)) < 1e-6) {        /* land exactly on the grid: no drift */
        double k = floor((s->time - s->t0) / MODEL_PERIOD + 0.5);
        s->time = s->t0 + k * MODEL_PERIOD;
    }
    s->pending = 0;
}

/* doStep(t, h): t must be the current communication point; h divides the period, or is a whole
 * multiple m of it starting on a sample instant (m samples, the inputs held over them). */
static SIStatus si_do_step(SampledInstance *s, double t, double h) {
    if (!si_check_mode(s, "doStep", IN_MODES(MODE_STEP))) return SI_ERROR;
    double tol = 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0) + 1e-9 * MODEL_PERIOD;
    if (fabs(t - s->time) > tol) {
        si_log(s, "doStep from t = %.9g s, but the last step ended at t = %.9g s", t, s->time);
        return SI_ERROR;
    }
    double per = MODEL_PERIOD / h, times = h / MODEL_PERIOD;
    int divides = h > 0.0 && per >= 1.0 - 1e-9 && fabs(per - floor(per + 0.5)) <= 1e-6 * per;
    int multiple = h > 0.0 && times >= 1.0 - 1e-9 && fabs(times - floor(times + 0.5)) <= 1e-6 * times;
    if (!divides && !multiple) {
        si_log(s, "communication step %.9g s is neither a whole multiple of the sample period %.9g s nor divides it "
               "(step / period = %.6g): use a step of n x %.9g s or %.9g s / n", h, (double)MODEL_PERIOD, times,
               (double)MODEL_PERIOD, (double)MODEL_PERIOD);
        return SI_ERROR;
    }
    if (divides) {
        si_advance(s, h);
        return SI_OK;
    }
    if (!si_at_sample(s)) {
        si_log(s, "a communication step of %.9g s (%.0f sample periods) must start on a sample instant; t = %.9g s is "
               "between two", h, floor(times + 0.5), t);
        return SI_ERROR;
    }
    for (long m = (long)floor(times + 0.5); m > 0; m--) si_advance(s, MODEL_PERIOD);
    return SI_OK;
}
