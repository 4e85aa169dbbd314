/* The first-order lag of ../first_order as an FMI 3.0 co-simulation FMU (test only):
 *     y+ = k u + (y - k u) exp(-h / tau)
 * Written against the FMI 3.0 C signatures without the standard headers; the FMI 3 functions
 * it does not support are generated as stubs that return fmi3Error (see tests/test_fmu.py). */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

typedef enum { OK, WARNING, DISCARD, ERROR, FATAL } Status;
enum { VR_K = 1, VR_TAU, VR_Y0, VR_U, VR_Y, NVR };
typedef struct { double v[NVR]; } Lag;

static void defaults(Lag *s) {
    s->v[VR_K] = 2.0; s->v[VR_TAU] = 0.5; s->v[VR_Y0] = 0.0; s->v[VR_U] = 0.0; s->v[VR_Y] = 0.0;
}

const char *fmi3GetVersion(void) { return "3.0"; }

void *fmi3InstantiateCoSimulation(const char *name, const char *token, const char *resources, bool visible,
                                  bool logging, bool eventMode, bool earlyReturn, const uint32_t *req,
                                  size_t nreq, void *env, void *log, void *intermediate) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)eventMode;
    (void)earlyReturn; (void)req; (void)nreq; (void)env; (void)log; (void)intermediate;
    Lag *s = (Lag *)calloc(1, sizeof(Lag));
    if (s) defaults(s);
    return s;
}
void fmi3FreeInstance(void *c) { free(c); }
Status fmi3EnterInitializationMode(void *c, bool tolDef, double tol, double start, bool stopDef, double stop) {
    (void)c; (void)tolDef; (void)tol; (void)start; (void)stopDef; (void)stop; return OK;
}
Status fmi3ExitInitializationMode(void *c) { Lag *s = (Lag *)c; s->v[VR_Y] = s->v[VR_Y0]; return OK; }
Status fmi3Terminate(void *c) { (void)c; return OK; }
Status fmi3Reset(void *c) { defaults((Lag *)c); return OK; }
Status fmi3GetFloat64(void *c, const uint32_t vr[], size_t n, double v[], size_t nv) {
    (void)nv;
    for (size_t i = 0; i < n; i++) { if (vr[i] < 1 || vr[i] >= NVR) return ERROR; v[i] = ((Lag *)c)->v[vr[i]]; }
    return OK;
}
Status fmi3SetFloat64(void *c, const uint32_t vr[], size_t n, const double v[], size_t nv) {
    (void)nv;
    for (size_t i = 0; i < n; i++) { if (vr[i] < 1 || vr[i] >= VR_Y) return ERROR; ((Lag *)c)->v[vr[i]] = v[i]; }
    return OK;
}
Status fmi3DoStep(void *c, double t, double h, bool noSet, bool *event, bool *terminate, bool *early, double *last) {
    (void)noSet;
    Lag *s = (Lag *)c;
    double target = s->v[VR_K] * s->v[VR_U];
    s->v[VR_Y] = target + (s->v[VR_Y] - target) * exp(-h / s->v[VR_TAU]);
    *event = false; *terminate = false; *early = false; *last = t + h;
    return OK;
}
