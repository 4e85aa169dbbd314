/* FMI 3.0 co-simulation interface of a sampled model (sampled_instance.c holds the semantics).
 * Only the fmi3 functions leave the binary (built with hidden visibility; FMI3_Export marks the
 * API); FMI3_FUNCTION_PREFIX, when defined, prefixes every one of them (source-code FMUs). */
#include "fmi3Functions.h"

typedef struct {
    SampledInstance *si;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
} Fmi3Instance;

static void fmi3_log(void *env, const char *instance, int error, const char *message) {
    Fmi3Instance *c = (Fmi3Instance *)env;
    (void)instance;
    if (c && c->logger) c->logger(c->env, error ? fmi3Error : fmi3OK, error ? "logStatusError" : "logAll", message);
}

#define SI(c) (((Fmi3Instance *)(c))->si)

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
        fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
        const fmi3ValueReference required[], size_t nRequired, fmi3InstanceEnvironment env,
        fmi3LogMessageCallback logger, fmi3IntermediateUpdateCallback update) {
    (void)resources; (void)visible; (void)logging; (void)earlyReturnAllowed; (void)required; (void)nRequired;
    (void)update;
    Fmi3Instance *c = (Fmi3Instance *)calloc(1, sizeof(Fmi3Instance));
    if (!c) return NULL;
    c->env = env;
    c->logger = logger;
    const char *problem = (!token || strcmp(token, MODEL_TOKEN) != 0) ? "the instantiation token does not match this binary"
                        : eventModeUsed ? "event mode is not provided (the model has no clocks)" : NULL;
    if (problem) {
        fmi3_log(c, name ? name : "", 1, problem);
        free(c);
        return NULL;
    }
    c->si = si_new(name, fmi3_log, c);
    if (!c->si) { free(c); return NULL; }
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
        fmi3Boolean visible, fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback logger) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging;
    if (logger) logger(env, fmi3Error, "logStatusError", "only co-simulation is provided");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
        fmi3Boolean visible, fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
        fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lock, fmi3UnlockPreemptionCallback unlock) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)clockUpdate; (void)lock;
    (void)unlock;
    if (logger) logger(env, fmi3Error, "logStatusError", "only co-simulation is provided");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c) {
    if (!c) return;
    si_free(SI(c));
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolDef, fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stopDef, fmi3Float64 stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    if (si_setup(SI(c), start) != SI_OK) return fmi3Error;
    return (fmi3Status)si_enter_initialization(SI(c));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) { return (fmi3Status)si_exit_initialization(SI(c)); }
fmi3Status fmi3Terminate(fmi3Instance c) { return (fmi3Status)si_terminate(SI(c)); }

fmi3Status fmi3Reset(fmi3Instance c) {
    si_reset(SI(c));
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 v[], size_t nv) {
    if (nv != n) { si_log(SI(c), "fmi3GetFloat64: %zu values for %zu scalar variables", nv, n); return fmi3Error; }
    return (fmi3Status)si_get(SI(c), vr, n, v);
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3Float64 v[], size_t nv) {
    if (nv != n) { si_log(SI(c), "fmi3SetFloat64: %zu values for %zu scalar variables", nv, n); return fmi3Error; }
    return (fmi3Status)si_set(SI(c), vr, n, v);
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    (void)noSetPrior;
    fmi3Status status = (fmi3Status)si_do_step(SI(c), t, h);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = SI(c)->time;
    return status;
}

/* ---- not provided: every call is answered with an error and a message ------------------------ */
static fmi3Status fmi3_unsupported(fmi3Instance c, const char *call) {
    if (c) si_log(SI(c), "%s is not provided by this FMU", call);
    return fmi3Error;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3EnterEventMode");
}
fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetFloat32");
}
fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetInt8");
}
fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetUInt8");
}
fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetInt16");
}
fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetUInt16");
}
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetInt32");
}
fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetUInt32");
}
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetInt64");
}
fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetUInt64");
}
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Boolean values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetBoolean");
}
fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3String values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetString");
}
fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetBinary");
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[]) {
    (void)valueReferences; (void)nValueReferences; (void)values;
    return fmi3_unsupported(instance, "fmi3GetClock");
}
fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetFloat32");
}
fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetInt8");
}
fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetUInt8");
}
fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetInt16");
}
fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetUInt16");
}
fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetInt32");
}
fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetUInt32");
}
fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetInt64");
}
fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetUInt64");
}
fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Boolean values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetBoolean");
}
fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3String values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetString");
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3SetBinary");
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[]) {
    (void)valueReferences; (void)nValueReferences; (void)values;
    return fmi3_unsupported(instance, "fmi3SetClock");
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t* nDependencies) {
    (void)valueReference; (void)nDependencies;
    return fmi3_unsupported(instance, "fmi3GetNumberOfVariableDependencies");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[], fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
    return fmi3_unsupported(instance, "fmi3GetVariableDependencies");
}
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    (void)FMUState;
    return fmi3_unsupported(instance, "fmi3GetFMUState");
}
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    (void)FMUState;
    return fmi3_unsupported(instance, "fmi3SetFMUState");
}
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    (void)FMUState;
    return fmi3_unsupported(instance, "fmi3FreeFMUState");
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
    (void)FMUState; (void)size;
    return fmi3_unsupported(instance, "fmi3SerializedFMUStateSize");
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    (void)FMUState; (void)serializedState; (void)size;
    return fmi3_unsupported(instance, "fmi3SerializeFMUState");
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState* FMUState) {
    (void)serializedState; (void)size; (void)FMUState;
    return fmi3_unsupported(instance, "fmi3DeserializeFMUState");
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity;
    return fmi3_unsupported(instance, "fmi3GetDirectionalDerivative");
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity;
    return fmi3_unsupported(instance, "fmi3GetAdjointDerivative");
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3EnterConfigurationMode");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3ExitConfigurationMode");
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers;
    return fmi3_unsupported(instance, "fmi3GetIntervalDecimal");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers;
    return fmi3_unsupported(instance, "fmi3GetIntervalFraction");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return fmi3_unsupported(instance, "fmi3GetShiftDecimal");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3_unsupported(instance, "fmi3GetShiftFraction");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals;
    return fmi3_unsupported(instance, "fmi3SetIntervalDecimal");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3_unsupported(instance, "fmi3SetIntervalFraction");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return fmi3_unsupported(instance, "fmi3SetShiftDecimal");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3_unsupported(instance, "fmi3SetShiftFraction");
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3EvaluateDiscreteStates");
}
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate, fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged, fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime) {
    (void)discreteStatesNeedUpdate; (void)terminateSimulation; (void)nominalsOfContinuousStatesChanged; (void)valuesOfContinuousStatesChanged; (void)nextEventTimeDefined; (void)nextEventTime;
    return fmi3_unsupported(instance, "fmi3UpdateDiscreteStates");
}
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3EnterContinuousTimeMode");
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return fmi3_unsupported(instance, "fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return fmi3_unsupported(instance, "fmi3SetTime");
}
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    return fmi3_unsupported(instance, "fmi3SetContinuousStates");
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates) {
    (void)derivatives; (void)nContinuousStates;
    return fmi3_unsupported(instance, "fmi3GetContinuousStateDerivatives");
}
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators; (void)nEventIndicators;
    return fmi3_unsupported(instance, "fmi3GetEventIndicators");
}
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    return fmi3_unsupported(instance, "fmi3GetContinuousStates");
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) {
    (void)nominals; (void)nContinuousStates;
    return fmi3_unsupported(instance, "fmi3GetNominalsOfContinuousStates");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators) {
    (void)nEventIndicators;
    return fmi3_unsupported(instance, "fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates) {
    (void)nContinuousStates;
    return fmi3_unsupported(instance, "fmi3GetNumberOfContinuousStates");
}
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    (void)0;
    return fmi3_unsupported(instance, "fmi3EnterStepMode");
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)orders; (void)values; (void)nValues;
    return fmi3_unsupported(instance, "fmi3GetOutputDerivatives");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    (void)clockReference; (void)activationTime;
    return fmi3_unsupported(instance, "fmi3ActivateModelPartition");
}
