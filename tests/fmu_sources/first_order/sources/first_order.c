/* A third-party-style FMI 2.0 co-simulation FMU for the tests: first-order lag
 *     tau dy/dt = k u - y,   exact over a step with u held:  y+ = k u + (y - k u) exp(-h / tau)
 * doStep returns fmi2Error once t >= fail_at (when fail_at >= 0), to test error handling. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"

enum { VR_K, VR_TAU, VR_FAIL_AT, VR_Y0, VR_U, VR_Y, NVR };

typedef struct { double v[NVR]; fmi2CallbackFunctions cb; } Lag;

static void defaults(Lag *s) {
    s->v[VR_K] = 2.0; s->v[VR_TAU] = 0.5; s->v[VR_FAIL_AT] = -1.0; s->v[VR_Y0] = 0.0;
    s->v[VR_U] = 0.0; s->v[VR_Y] = 0.0;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String k[]) {
    (void)c; (void)on; (void)n; (void)k; return fmi2OK;
}
fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String loc,
                              const fmi2CallbackFunctions *cb, fmi2Boolean vis, fmi2Boolean log) {
    (void)name; (void)guid; (void)loc; (void)vis; (void)log;
    if (type != fmi2CoSimulation) return NULL;
    Lag *s = (Lag *)calloc(1, sizeof(Lag));
    if (s && cb) s->cb = *cb;
    if (s) defaults(s);
    return s;
}
void fmi2FreeInstance(fmi2Component c) { free(c); }
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real t0, fmi2Boolean d, fmi2Real e) {
    (void)c; (void)a; (void)b; (void)t0; (void)d; (void)e; return fmi2OK;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Lag *s = (Lag *)c; s->v[VR_Y] = s->v[VR_Y0]; return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { defaults((Lag *)c); return fmi2OK; }
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NVR) return fmi2Error; v[i] = ((Lag *)c)->v[vr[i]]; }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    for (size_t i = 0; i < n; i++) { if (vr[i] >= NVR || vr[i] == VR_Y) return fmi2Error; ((Lag *)c)->v[vr[i]] = v[i]; }
    return fmi2OK;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference r[], size_t n, fmi2Integer v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference r[], size_t n, const fmi2Integer v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference r[], size_t n, fmi2Boolean v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference r[], size_t n, const fmi2Boolean v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference r[], size_t n, fmi2String v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference r[], size_t n, const fmi2String v[]) { (void)c; (void)r; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) { (void)c; (void)s; (void)n; return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) { (void)c; (void)s; (void)b; (void)n; return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) { (void)c; (void)b; (void)n; (void)s; return fmi2Error; }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference a[], size_t na, const fmi2ValueReference b[], size_t nb, const fmi2Real x[], fmi2Real y[]) {
    (void)c; (void)a; (void)na; (void)b; (void)nb; (void)x; (void)y; return fmi2Error;
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference r[], size_t n, const fmi2Integer o[], const fmi2Real v[]) { (void)c; (void)r; (void)n; (void)o; (void)v; return fmi2Error; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference r[], size_t n, const fmi2Integer o[], fmi2Real v[]) { (void)c; (void)r; (void)n; (void)o; (void)v; return fmi2Error; }
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean nop) {
    (void)nop;
    Lag *s = (Lag *)c;
    if (s->v[VR_FAIL_AT] >= 0.0 && t >= s->v[VR_FAIL_AT]) {
        if (s->cb.logger) s->cb.logger(s->cb.componentEnvironment, "first_order", fmi2Error, "logStatusError", "failing on purpose");
        return fmi2Error;
    }
    double target = s->v[VR_K] * s->v[VR_U];
    s->v[VR_Y] = target + (s->v[VR_Y] - target) * exp(-h / s->v[VR_TAU]);
    return fmi2OK;
}
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
