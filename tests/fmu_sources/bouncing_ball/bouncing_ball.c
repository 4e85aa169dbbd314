/* FMI 2.0 model-exchange test FMU: a ball falling from h0 and bouncing with restitution e
 * (tests/test_fmu_import_conformance.py). States h, v; dh/dt = v, dv/dt = -g; event indicator h;
 * at an impact (h <= 0 moving down) v := -e v. Written against the FMI 2.0 C signatures without
 * the standard headers; functions it lacks are generated as stubs. */
#include <stdlib.h>
#include <string.h>

typedef enum { OK, WARNING, DISCARD, ERROR, FATAL } Status;
enum { VR_H, VR_DER_H, VR_V, VR_DER_V, VR_G, VR_E, VR_H0, NVR };
typedef struct { double r[NVR]; double time; int bounces; } Ball;
typedef struct { int newDiscreteStatesNeeded, terminateSimulation, nominalsChanged, valuesChanged, nextEventTimeDefined;
                 double nextEventTime; } EventInfo;

static void defaults(Ball *b) { memset(b, 0, sizeof *b); b->r[VR_G] = 9.81; b->r[VR_E] = 0.7; b->r[VR_H0] = 1.0; }
static void derivatives(Ball *b) { b->r[VR_DER_H] = b->r[VR_V]; b->r[VR_DER_V] = -b->r[VR_G]; }

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return "2.0"; }
Status fmi2SetDebugLogging(void *c, int on, size_t n, const char *const cat[]) { (void)c; (void)on; (void)n; (void)cat; return OK; }
void *fmi2Instantiate(const char *name, int type, const char *guid, const char *location, const void *cb,
                      int visible, int logging) {
    (void)name; (void)guid; (void)location; (void)cb; (void)visible; (void)logging;
    if (type != 0) return NULL;                  /* model exchange only */
    Ball *b = (Ball *)calloc(1, sizeof(Ball));
    if (b) defaults(b);
    return b;
}
void fmi2FreeInstance(void *c) { free(c); }
Status fmi2SetupExperiment(void *c, int tolDef, double tol, double start, int stopDef, double stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop; ((Ball *)c)->time = start; return OK;
}
Status fmi2EnterInitializationMode(void *c) { (void)c; return OK; }
Status fmi2ExitInitializationMode(void *c) { Ball *b = (Ball *)c; b->r[VR_H] = b->r[VR_H0]; b->r[VR_V] = 0.0; derivatives(b); return OK; }
Status fmi2Terminate(void *c) { (void)c; return OK; }
Status fmi2Reset(void *c) { defaults((Ball *)c); return OK; }
Status fmi2GetReal(void *c, const unsigned vr[], size_t n, double v[]) {
    Ball *b = (Ball *)c; derivatives(b);
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NVR) return ERROR; v[i] = b->r[vr[i]]; }
    return OK;
}
Status fmi2SetReal(void *c, const unsigned vr[], size_t n, const double v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] < VR_G || vr[i] >= NVR) return ERROR; ((Ball *)c)->r[vr[i]] = v[i]; }
    return OK;
}
Status fmi2GetInteger(void *c, const unsigned vr[], size_t n, int v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] != 0) return ERROR; v[i] = ((Ball *)c)->bounces; }
    return OK;
}
Status fmi2EnterEventMode(void *c) { (void)c; return OK; }
Status fmi2NewDiscreteStates(void *c, EventInfo *info) {
    Ball *b = (Ball *)c;
    memset(info, 0, sizeof *info);
    if (b->r[VR_H] <= 1e-9 && b->r[VR_V] < 0) {
        b->r[VR_H] = 0.0;
        b->r[VR_V] = -b->r[VR_E] * b->r[VR_V];
        b->bounces += 1;
        info->valuesChanged = 1;
    }
    return OK;
}
Status fmi2EnterContinuousTimeMode(void *c) { (void)c; return OK; }
Status fmi2CompletedIntegratorStep(void *c, int noSet, int *enterEventMode, int *terminate) {
    (void)c; (void)noSet; *enterEventMode = 0; *terminate = 0; return OK;
}
Status fmi2SetTime(void *c, double t) { ((Ball *)c)->time = t; return OK; }
Status fmi2SetContinuousStates(void *c, const double x[], size_t nx) {
    if (nx != 2) return ERROR;
    ((Ball *)c)->r[VR_H] = x[0]; ((Ball *)c)->r[VR_V] = x[1]; return OK;
}
Status fmi2GetDerivatives(void *c, double dx[], size_t nx) {
    Ball *b = (Ball *)c;
    if (nx != 2) return ERROR;
    derivatives(b); dx[0] = b->r[VR_DER_H]; dx[1] = b->r[VR_DER_V]; return OK;
}
Status fmi2GetEventIndicators(void *c, double z[], size_t nz) { if (nz != 1) return ERROR; z[0] = ((Ball *)c)->r[VR_H]; return OK; }
Status fmi2GetContinuousStates(void *c, double x[], size_t nx) {
    if (nx != 2) return ERROR;
    x[0] = ((Ball *)c)->r[VR_H]; x[1] = ((Ball *)c)->r[VR_V]; return OK;
}
Status fmi2GetNominalsOfContinuousStates(void *c, double x[], size_t nx) { (void)c; for (size_t i = 0; i < nx; i++) x[i] = 1.0; return OK; }
