/* FMI 2.0 co-simulation interface of a sampled model (sampled_instance.c holds the semantics).
 * Only the fmi2 functions leave the binary (built with hidden visibility; FMI2_Export marks the
 * API); FMI2_FUNCTION_PREFIX, when defined, prefixes every one of them (source-code FMUs). */
#include "fmi2Functions.h"

typedef struct {
    SampledInstance *si;
    fmi2CallbackFunctions cb;
} Fmi2Instance;

static void fmi2_log(void *env, const char *instance, int error, const char *message) {
    Fmi2Instance *c = (Fmi2Instance *)env;
    if (c && c->cb.logger)
        c->cb.logger(c->cb.componentEnvironment, instance, error ? fmi2Error : fmi2OK,
                     error ? "logStatusError" : "logAll", "%s", message);
}

#define SI(c) (((Fmi2Instance *)(c))->si)

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String token, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    (void)location; (void)visible; (void)logging;
    Fmi2Instance *c = (Fmi2Instance *)calloc(1, sizeof(Fmi2Instance));
    if (!c) return NULL;
    if (cb) c->cb = *cb;
    const char *problem = type != fmi2CoSimulation ? "only co-simulation is provided"
                        : (!token || strcmp(token, MODEL_TOKEN) != 0) ? "the GUID does not match this binary" : NULL;
    if (problem) {
        fmi2_log(c, name ? name : "", 1, problem);
        free(c);
        return NULL;
    }
    c->si = si_new(name, fmi2_log, c);
    if (!c->si) { free(c); return NULL; }
    return c;
}

void fmi2FreeInstance(fmi2Component c) {
    if (!c) return;
    si_free(SI(c));
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    return (fmi2Status)si_setup(SI(c), start);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return (fmi2Status)si_enter_initialization(SI(c)); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return (fmi2Status)si_exit_initialization(SI(c)); }
fmi2Status fmi2Terminate(fmi2Component c) { return (fmi2Status)si_terminate(SI(c)); }

fmi2Status fmi2Reset(fmi2Component c) {
    si_reset(SI(c));
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    return (fmi2Status)si_get(SI(c), vr, n, v);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    return (fmi2Status)si_set(SI(c), vr, n, v);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    (void)noSetPrior;
    return (fmi2Status)si_do_step(SI(c), t, h);
}

/* ---- not provided: every call is answered with an error and a message ------------------------ */
static fmi2Status fmi2_unsupported(fmi2Component c, const char *call) {
    if (c) si_log(SI(c), "%s is not provided by this FMU", call);
    return fmi2Error;
}

#define NO_VARIABLES(kind, T)                                                                   \
    fmi2Status fmi2Get##kind(fmi2Component c, const fmi2ValueReference vr[], size_t n, T v[]) { \
        (void)vr; (void)v; return n ? fmi2_unsupported(c, "fmi2Get" #kind) : fmi2OK;          \
    }                                                                                           \
    fmi2Status fmi2Set##kind(fmi2Component c, const fmi2ValueReference vr[], size_t n, const T v[]) { \
        (void)vr; (void)v; return n ? fmi2_unsupported(c, "fmi2Set" #kind) : fmi2OK;          \
    }
NO_VARIABLES(Integer, fmi2Integer)
NO_VARIABLES(Boolean, fmi2Boolean)
NO_VARIABLES(String, fmi2String)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return fmi2_unsupported(c, "fmi2GetFMUstate"); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)s; return fmi2_unsupported(c, "fmi2SetFMUstate"); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return fmi2_unsupported(c, "fmi2FreeFMUstate"); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)s; (void)n; return fmi2_unsupported(c, "fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)s; (void)b; (void)n; return fmi2_unsupported(c, "fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    (void)b; (void)n; (void)s; return fmi2_unsupported(c, "fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[]) {
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fmi2_unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    (void)vr; (void)n; (void)order; (void)v; return fmi2_unsupported(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real v[]) {
    (void)vr; (void)n; (void)order; (void)v; return fmi2_unsupported(c, "fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { return fmi2_unsupported(c, "fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) {
    (void)c; (void)k; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) {
    if (k == fmi2LastSuccessfulTime && c) { *v = SI(c)->time; return fmi2OK; }
    return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) {
    (void)c; (void)k; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) {
    if (k == fmi2Terminated) { (void)c; *v = fmi2False; return fmi2OK; }
    return fmi2Discard;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) {
    (void)c; (void)k; (void)v; return fmi2Discard;
}
