/* FMI 2.0 co-simulation test FMU with every FMI 2.0 type, direct feedthrough, structured names and
 * a terminate request (tests/test_fmu_import_conformance.py). Written against the FMI 2.0 C
 * signatures without the standard headers; functions it lacks are generated as stubs.
 *   Real:    k (parameter), u (input, rad.s-1), y_direct = k u (feedthrough), x = integral of u,
 *            body.speed = 2 x, stop_time (parameter: doStep past it returns fmi2Discard with
 *            fmi2Terminated = true)
 *   Integer: n_in (input), n_out = 2 n_in (feedthrough); Enumeration mode = 1 if u >= 0 else 2
 *   Boolean: flag_in (input), flag_out = !flag_in
 *   String:  label (parameter), label_out = label */
#include <stdlib.h>
#include <string.h>

typedef enum { OK, WARNING, DISCARD, ERROR, FATAL } Status;
enum { R_K, R_U, R_Y, R_X, R_SPEED, R_STOP, NR };
enum { I_N_IN, I_N_OUT, I_MODE, NI };
enum { B_IN, B_OUT, NB };

typedef struct { double r[NR]; int i[NI]; int b[NB]; char label[64]; int terminated; double time; } Model;

static void defaults(Model *m) {
    memset(m, 0, sizeof *m);
    m->r[R_K] = 3.0; m->r[R_STOP] = 1e9; m->i[I_MODE] = 1; m->b[B_OUT] = 1;
    strcpy(m->label, "plant");
}
static void outputs(Model *m) {
    m->r[R_Y] = m->r[R_K] * m->r[R_U];
    m->r[R_SPEED] = 2.0 * m->r[R_X];
    m->i[I_N_OUT] = 2 * m->i[I_N_IN];
    m->i[I_MODE] = m->r[R_U] >= 0 ? 1 : 2;
    m->b[B_OUT] = !m->b[B_IN];
}

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return "2.0"; }
Status fmi2SetDebugLogging(void *c, int on, size_t n, const char *const cat[]) { (void)c; (void)on; (void)n; (void)cat; return OK; }
void *fmi2Instantiate(const char *name, int type, const char *guid, const char *location, const void *cb,
                      int visible, int logging) {
    (void)name; (void)type; (void)guid; (void)location; (void)cb; (void)visible; (void)logging;
    Model *m = (Model *)calloc(1, sizeof(Model));
    if (m) defaults(m);
    return m;
}
void fmi2FreeInstance(void *c) { free(c); }
Status fmi2SetupExperiment(void *c, int tolDef, double tol, double start, int stopDef, double stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop; ((Model *)c)->time = start; return OK;
}
Status fmi2EnterInitializationMode(void *c) { (void)c; return OK; }
Status fmi2ExitInitializationMode(void *c) { outputs((Model *)c); return OK; }
Status fmi2Terminate(void *c) { (void)c; return OK; }
Status fmi2Reset(void *c) { defaults((Model *)c); return OK; }

Status fmi2GetReal(void *c, const unsigned vr[], size_t n, double v[]) {
    Model *m = (Model *)c; outputs(m);
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NR) return ERROR; v[i] = m->r[vr[i]]; }
    return OK;
}
Status fmi2SetReal(void *c, const unsigned vr[], size_t n, const double v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) { if (vr[i] != R_K && vr[i] != R_U && vr[i] != R_STOP) return ERROR; m->r[vr[i]] = v[i]; }
    return OK;
}
Status fmi2GetInteger(void *c, const unsigned vr[], size_t n, int v[]) {
    Model *m = (Model *)c; outputs(m);
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NI) return ERROR; v[i] = m->i[vr[i]]; }
    return OK;
}
Status fmi2SetInteger(void *c, const unsigned vr[], size_t n, const int v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) { if (vr[i] != I_N_IN) return ERROR; m->i[I_N_IN] = v[i]; }
    return OK;
}
Status fmi2GetBoolean(void *c, const unsigned vr[], size_t n, int v[]) {
    Model *m = (Model *)c; outputs(m);
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NB) return ERROR; v[i] = m->b[vr[i]]; }
    return OK;
}
Status fmi2SetBoolean(void *c, const unsigned vr[], size_t n, const int v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) { if (vr[i] != B_IN) return ERROR; m->b[B_IN] = v[i]; }
    return OK;
}
Status fmi2GetString(void *c, const unsigned vr[], size_t n, const char *v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) { if (vr[i] > 1) return ERROR; v[i] = m->label; }
    return OK;
}
Status fmi2SetString(void *c, const unsigned vr[], size_t n, const char *const v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != 0) return ERROR;
        strncpy(m->label, v[i], sizeof m->label - 1);
    }
    return OK;
}
Status fmi2DoStep(void *c, double t, double h, int noSet) {
    (void)noSet;
    Model *m = (Model *)c;
    if (t + h > m->r[R_STOP] + 1e-12) { m->terminated = 1; return DISCARD; }
    m->r[R_X] += h * m->r[R_U];
    m->time = t + h;
    return OK;
}
Status fmi2GetBooleanStatus(void *c, int kind, int *v) {
    if (kind != 3) return DISCARD;           /* fmi2Terminated */
    *v = ((Model *)c)->terminated;
    return OK;
}
Status fmi2GetRealStatus(void *c, int kind, double *v) {
    if (kind != 2) return DISCARD;           /* fmi2LastSuccessfulTime */
    *v = ((Model *)c)->time;
    return OK;
}
