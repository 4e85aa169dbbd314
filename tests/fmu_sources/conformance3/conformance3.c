/* FMI 3.0 co-simulation test FMU with arrays and the non-Float64 types, feedthrough and a
 * terminate request (tests/test_fmu_import_conformance.py). Written against the FMI 3.0 C
 * signatures without the standard headers; functions it lacks are generated as stubs.
 *   Float64 k (parameter), u (input), gains[3] (input), scaled[3] = k gains u (feedthrough)
 *   Int32 count = number of steps taken; UInt8 small (input), UInt16 small_twice = 2 small
 *   Float32 u32 = u; Boolean on = u > 0; Enumeration gear = 3; String name (parameter)
 *   stop_time (parameter): doStep past it sets terminateSimulation */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef enum { OK, WARNING, DISCARD, ERROR, FATAL } Status;
enum { VR_TIME = 1, VR_K, VR_U, VR_GAINS, VR_SCALED, VR_COUNT, VR_SMALL, VR_SMALL2, VR_U32, VR_ON, VR_GEAR,
       VR_NAME, VR_STOP };
typedef struct { double k, u, gains[3], stop, time; int32_t count; uint8_t small; char name[64]; } Model;

static void defaults(Model *m) {
    memset(m, 0, sizeof *m);
    m->k = 1.0; m->gains[0] = 1.0; m->gains[1] = 2.0; m->gains[2] = 3.0; m->stop = 1e9;
    strcpy(m->name, "arrays");
}

const char *fmi3GetVersion(void) { return "3.0"; }
void *fmi3InstantiateCoSimulation(const char *name, const char *token, const char *resources, bool visible,
                                  bool logging, bool eventMode, bool earlyReturn, const uint32_t *req,
                                  size_t nreq, void *env, void *log, void *intermediate) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)eventMode;
    (void)earlyReturn; (void)req; (void)nreq; (void)env; (void)log; (void)intermediate;
    Model *m = (Model *)calloc(1, sizeof(Model));
    if (m) defaults(m);
    return m;
}
void fmi3FreeInstance(void *c) { free(c); }
Status fmi3EnterInitializationMode(void *c, bool tolDef, double tol, double start, bool stopDef, double stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop; ((Model *)c)->time = start; return OK;
}
Status fmi3ExitInitializationMode(void *c) { (void)c; return OK; }
Status fmi3Terminate(void *c) { (void)c; return OK; }
Status fmi3Reset(void *c) { defaults((Model *)c); return OK; }

Status fmi3GetFloat64(void *c, const uint32_t vr[], size_t n, double v[], size_t nv) {
    Model *m = (Model *)c;
    size_t j = 0;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case VR_TIME: v[j++] = m->time; break;
        case VR_K: v[j++] = m->k; break;
        case VR_U: v[j++] = m->u; break;
        case VR_STOP: v[j++] = m->stop; break;
        case VR_GAINS: for (int e = 0; e < 3; e++) v[j++] = m->gains[e]; break;
        case VR_SCALED: for (int e = 0; e < 3; e++) v[j++] = m->k * m->gains[e] * m->u; break;
        default: return ERROR;
        }
    }
    return j == nv ? OK : ERROR;
}
Status fmi3SetFloat64(void *c, const uint32_t vr[], size_t n, const double v[], size_t nv) {
    Model *m = (Model *)c;
    size_t j = 0;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case VR_K: m->k = v[j++]; break;
        case VR_U: m->u = v[j++]; break;
        case VR_STOP: m->stop = v[j++]; break;
        case VR_GAINS: for (int e = 0; e < 3; e++) m->gains[e] = v[j++]; break;
        default: return ERROR;
        }
    }
    return j == nv ? OK : ERROR;
}
Status fmi3GetFloat32(void *c, const uint32_t vr[], size_t n, float v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_U32) return ERROR; v[i] = (float)((Model *)c)->u; }
    return OK;
}
Status fmi3GetInt32(void *c, const uint32_t vr[], size_t n, int32_t v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_COUNT) return ERROR; v[i] = ((Model *)c)->count; }
    return OK;
}
Status fmi3GetUInt8(void *c, const uint32_t vr[], size_t n, uint8_t v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_SMALL) return ERROR; v[i] = ((Model *)c)->small; }
    return OK;
}
Status fmi3SetUInt8(void *c, const uint32_t vr[], size_t n, const uint8_t v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_SMALL) return ERROR; ((Model *)c)->small = v[i]; }
    return OK;
}
Status fmi3GetUInt16(void *c, const uint32_t vr[], size_t n, uint16_t v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_SMALL2) return ERROR; v[i] = (uint16_t)(2 * ((Model *)c)->small); }
    return OK;
}
Status fmi3GetBoolean(void *c, const uint32_t vr[], size_t n, bool v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_ON) return ERROR; v[i] = ((Model *)c)->u > 0; }
    return OK;
}
Status fmi3GetInt64(void *c, const uint32_t vr[], size_t n, int64_t v[], size_t nv) {
    (void)c; (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_GEAR) return ERROR; v[i] = 3; }
    return OK;
}
Status fmi3GetString(void *c, const uint32_t vr[], size_t n, const char *v[], size_t nv) {
    (void)nv; for (size_t i = 0; i < n; i++) { if (vr[i] != VR_NAME) return ERROR; v[i] = ((Model *)c)->name; }
    return OK;
}
Status fmi3SetString(void *c, const uint32_t vr[], size_t n, const char *const v[], size_t nv) {
    (void)nv;
    for (size_t i = 0; i < n; i++) { if (vr[i] != VR_NAME) return ERROR; strncpy(((Model *)c)->name, v[i], 63); }
    return OK;
}
Status fmi3DoStep(void *c, double t, double h, bool noSet, bool *event, bool *terminate, bool *early, double *last) {
    (void)noSet;
    Model *m = (Model *)c;
    *event = false; *early = false;
    if (t + h > m->stop + 1e-12) { *terminate = true; *last = t; return OK; }
    *terminate = false;
    m->count += 1;
    m->time = t + h;
    *last = m->time;
    return OK;
}
