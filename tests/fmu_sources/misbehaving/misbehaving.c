/* FMI 2.0 co-simulation test FMU that misbehaves on purpose (tests/test_fmu_isolation.py): from
 * doStep at t >= fail_time it crashes (fail_mode 1: a segmentation fault), ends its process
 * (2: exit(3)) or never returns (3: an endless loop). Before that, x = t.
 *   Real:    fail_time (parameter), x (output) ; Integer: fail_mode (parameter, 0: behaves) */
#include <stdlib.h>
#include <string.h>

typedef enum { OK, WARNING, DISCARD, ERROR, FATAL } Status;
typedef struct { double fail_time, x; int fail_mode; } Model;

void *fmi2Instantiate(const char *name, int type, const char *guid, const char *location, const void *cb,
                      int visible, int logging) {
    (void)name; (void)type; (void)guid; (void)location; (void)cb; (void)visible; (void)logging;
    Model *m = (Model *)calloc(1, sizeof(Model));
    if (m) { m->fail_time = 1e9; }
    return m;
}
void fmi2FreeInstance(void *c) { free(c); }
Status fmi2SetupExperiment(void *c, int tolDef, double tol, double start, int stopDef, double stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop; ((Model *)c)->x = start; return OK;
}
Status fmi2EnterInitializationMode(void *c) { (void)c; return OK; }
Status fmi2ExitInitializationMode(void *c) { (void)c; return OK; }
Status fmi2Terminate(void *c) { (void)c; return OK; }
Status fmi2Reset(void *c) { Model *m = (Model *)c; m->x = 0; m->fail_time = 1e9; m->fail_mode = 0; return OK; }
Status fmi2GetReal(void *c, const unsigned vr[], size_t n, double v[]) {
    Model *m = (Model *)c;
    for (size_t i = 0; i < n; i++) v[i] = vr[i] == 0 ? m->fail_time : m->x;
    return OK;
}
Status fmi2SetReal(void *c, const unsigned vr[], size_t n, const double v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] != 0) return ERROR; ((Model *)c)->fail_time = v[i]; }
    return OK;
}
Status fmi2GetInteger(void *c, const unsigned vr[], size_t n, int v[]) {
    for (size_t i = 0; i < n; i++) v[i] = ((Model *)c)->fail_mode;
    (void)vr; return OK;
}
Status fmi2SetInteger(void *c, const unsigned vr[], size_t n, const int v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] != 0) return ERROR; ((Model *)c)->fail_mode = v[i]; }
    return OK;
}
Status fmi2DoStep(void *c, double t, double h, int noSet) {
    (void)noSet;
    Model *m = (Model *)c;
    if (t >= m->fail_time - 1e-12) {
        if (m->fail_mode == 1) { volatile int *p = NULL; *p = 1; }
        if (m->fail_mode == 2) exit(3);
        if (m->fail_mode == 3) { volatile int spin = 1; while (spin) { } }
    }
    m->x = t + h;
    return OK;
}
