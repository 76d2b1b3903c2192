/* FMI 3.0 co-simulation over the runtime (sew_slave.h): the calls a sewfmu FMU provides
   (fmi3_unsupported.c refuses the others: event mode, clocks, configuration mode, derivatives,
   model exchange, scheduled execution). Value reference 0 is the independent variable `time`,
   as in the Python FMUs' FMI 3.0 layer. The typed calls of kinds it declares no variable of
   (Float32, Int64, String, Binary, ...) refuse any value reference as unknown. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_glue.h"

static const char *category_of(SewStatus status)
{
    switch (status) {
    case SEW_WARNING: return "logStatusWarning";
    case SEW_DISCARD: return "logStatusDiscard";
    case SEW_ERROR: return "logStatusError";
    case SEW_FATAL: return "logStatusFatal";
    default: return "logAll";
    }
}

/* errors and discarded steps always (they say why a call failed); other lines while the host
   asked for logging */
static void log_line(void *env, SewStatus status, const char *line)
{
    Fmi3Instance *c = env;
    if (c->log && (c->logging || status >= SEW_DISCARD))
        c->log(c->env, (fmi3Status)status, category_of(status), line);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    CHECK(c);
    if (sew_check_categories(SLAVE(c), "fmi3SetDebugLogging", nCategories, categories)
        != SEW_OK)
        return fmi3Error;
    ((Fmi3Instance *)c)->logging = loggingOn ? 1 : 0;
    return fmi3OK;
}

static void refuse_instantiation(fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                 const char *why)
{
    if (log)
        log(env, fmi3Error, "logStatusError", why);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath, (void)visible, (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables, (void)intermediateUpdate;
    if (!instantiationToken || strcmp(instantiationToken, SEW_DESCRIPTION.token) != 0) {
        refuse_instantiation(instanceEnvironment, logMessage,
                             "fmi3InstantiateCoSimulation: the instantiationToken is not this "
                             "FMU's (a modelDescription of another build?)");
        return NULL;
    }
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        refuse_instantiation(instanceEnvironment, logMessage,
                             "fmi3InstantiateCoSimulation: event mode and intermediate "
                             "variables are not provided (hasEventMode is not declared)");
        return NULL;
    }
    Fmi3Instance *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->env = instanceEnvironment;
    c->log = logMessage;
    c->logging = loggingOn ? 1 : 0;
    c->slave = sew_new(&SEW_DESCRIPTION, instanceName && instanceName[0] ? instanceName : "?",
                       log_line, c);
    if (!c->slave) {
        refuse_instantiation(instanceEnvironment, logMessage,
                             "fmi3InstantiateCoSimulation: out of memory");
        free(c);
        return NULL;
    }
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn;
    refuse_instantiation(instanceEnvironment, logMessage,
                         "fmi3InstantiateModelExchange: not provided: this FMU is for "
                         "co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    refuse_instantiation(instanceEnvironment, logMessage,
                         "fmi3InstantiateScheduledExecution: not provided: this FMU is for "
                         "co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c)
{
    if (!c)
        return;
    sew_free(SLAVE(c));
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    (void)toleranceDefined, (void)tolerance;
    CHECK(c);
    if (stopTimeDefined && !(stopTime >= startTime))
        return (fmi3Status)sew_refuse(SLAVE(c), "fmi3EnterInitializationMode: the stop time %g "
                                      "is before the start time %g", stopTime, startTime);
    return (fmi3Status)sew_enter_initialization(SLAVE(c), "fmi3EnterInitializationMode",
                                                startTime);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c)
{
    CHECK(c);
    return (fmi3Status)sew_exit_initialization(SLAVE(c), "fmi3ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance c)
{
    CHECK(c);
    return (fmi3Status)sew_terminate(SLAVE(c), "fmi3Terminate");
}

fmi3Status fmi3Reset(fmi3Instance c)
{
    CHECK(c);
    sew_reset(SLAVE(c));
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c);
    SewStatus status = sew_do_step(SLAVE(c), "fmi3DoStep", currentCommunicationPoint,
                                   communicationStepSize);
    if (eventHandlingNeeded)
        *eventHandlingNeeded = fmi3False;
    /* false after a Discard too, as the Python FMU's (pythonfmu3, Fmi3StepResult): FMI 3.0
       leaves the choice to the importer (retry shorter from a saved state, or stop), and
       fmpy and fmusim stop at a Discard status */
    if (terminateSimulation)
        *terminateSimulation = fmi3False;
    if (earlyReturn)
        *earlyReturn = fmi3False;
    if (lastSuccessfulTime)
        *lastSuccessfulTime = SLAVE(c)->time;
    return (fmi3Status)status;
}

/* --- values ----------------------------------------------------------------------------------- */

static fmi3Status count_mismatch(fmi3Instance c, const char *call, size_t nvr, size_t nValues)
{
    return (fmi3Status)sew_refuse(SLAVE(c), "%s: %lu values for %lu value references (this FMU "
                                  "has scalar variables only)", call, (unsigned long)nValues,
                                  (unsigned long)nvr);
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3GetFloat64", nvr, nValues);
    return (fmi3Status)sew_get(SLAVE(c), "fmi3GetFloat64", SEW_REAL, vr, nvr, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3SetFloat64", nvr, nValues);
    return (fmi3Status)sew_set(SLAVE(c), "fmi3SetFloat64", SEW_REAL, vr, nvr, values);
}

/* Int32 and Boolean values pass through doubles (sew_model.h: all values are doubles) */
static double *doubles(fmi3Instance c, const char *call, size_t n)
{
    double *x = malloc((n > 0 ? n : 1) * sizeof(double));
    if (!x)
        sew_refuse(SLAVE(c), "%s: out of memory", call);
    return x;
}

fmi3Status fmi3GetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3GetInt32", nvr, nValues);
    double *x = doubles(c, "fmi3GetInt32", nvr);
    if (!x)
        return fmi3Error;
    SewStatus status = sew_get(SLAVE(c), "fmi3GetInt32", SEW_INTEGER, vr, nvr, x);
    for (size_t i = 0; i < nvr && values && status != SEW_ERROR; i++)
        values[i] = (fmi3Int32)x[i];
    free(x);
    return (fmi3Status)status;
}

fmi3Status fmi3SetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3SetInt32", nvr, nValues);
    double *x = doubles(c, "fmi3SetInt32", nvr);
    if (!x)
        return fmi3Error;
    for (size_t i = 0; i < nvr && values; i++)
        x[i] = (double)values[i];
    SewStatus status = sew_set(SLAVE(c), "fmi3SetInt32", SEW_INTEGER, vr, nvr,
                               values ? x : NULL);
    free(x);
    return (fmi3Status)status;
}

fmi3Status fmi3GetBoolean(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3GetBoolean", nvr, nValues);
    double *x = doubles(c, "fmi3GetBoolean", nvr);
    if (!x)
        return fmi3Error;
    SewStatus status = sew_get(SLAVE(c), "fmi3GetBoolean", SEW_BOOLEAN, vr, nvr, x);
    for (size_t i = 0; i < nvr && values && status != SEW_ERROR; i++)
        values[i] = x[i] != 0.0 ? fmi3True : fmi3False;
    free(x);
    return (fmi3Status)status;
}

fmi3Status fmi3SetBoolean(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues)
{
    CHECK(c);
    if (nValues != nvr)
        return count_mismatch(c, "fmi3SetBoolean", nvr, nValues);
    double *x = doubles(c, "fmi3SetBoolean", nvr);
    if (!x)
        return fmi3Error;
    for (size_t i = 0; i < nvr && values; i++)
        x[i] = values[i] ? 1.0 : 0.0;
    SewStatus status = sew_set(SLAVE(c), "fmi3SetBoolean", SEW_BOOLEAN, vr, nvr,
                               values ? x : NULL);
    free(x);
    return (fmi3Status)status;
}

/* the kinds of which this FMU has no variable: any value reference is unknown */
#define NO_SUCH_KIND(name, type, qual)                                                            \
    fmi3Status name(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,                    \
                    qual type values[], size_t nValues)                                           \
    {                                                                                             \
        (void)values, (void)nValues;                                                              \
        CHECK(c);                                                                                 \
        return (fmi3Status)sew_no_such_kind(SLAVE(c), #name, vr, nvr);                            \
    }

NO_SUCH_KIND(fmi3GetFloat32, fmi3Float32, )
NO_SUCH_KIND(fmi3GetInt8, fmi3Int8, )
NO_SUCH_KIND(fmi3GetUInt8, fmi3UInt8, )
NO_SUCH_KIND(fmi3GetInt16, fmi3Int16, )
NO_SUCH_KIND(fmi3GetUInt16, fmi3UInt16, )
NO_SUCH_KIND(fmi3GetUInt32, fmi3UInt32, )
NO_SUCH_KIND(fmi3GetInt64, fmi3Int64, )
NO_SUCH_KIND(fmi3GetUInt64, fmi3UInt64, )
NO_SUCH_KIND(fmi3GetString, fmi3String, )
NO_SUCH_KIND(fmi3SetFloat32, fmi3Float32, const)
NO_SUCH_KIND(fmi3SetInt8, fmi3Int8, const)
NO_SUCH_KIND(fmi3SetUInt8, fmi3UInt8, const)
NO_SUCH_KIND(fmi3SetInt16, fmi3Int16, const)
NO_SUCH_KIND(fmi3SetUInt16, fmi3UInt16, const)
NO_SUCH_KIND(fmi3SetUInt32, fmi3UInt32, const)
NO_SUCH_KIND(fmi3SetInt64, fmi3Int64, const)
NO_SUCH_KIND(fmi3SetUInt64, fmi3UInt64, const)
NO_SUCH_KIND(fmi3SetString, fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    CHECK(c);
    return (fmi3Status)sew_no_such_kind(SLAVE(c), "fmi3GetBinary", vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    CHECK(c);
    return (fmi3Status)sew_no_such_kind(SLAVE(c), "fmi3SetBinary", vr, nvr);
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[])
{
    (void)values;
    CHECK(c);
    return (fmi3Status)sew_no_such_kind(SLAVE(c), "fmi3GetClock", vr, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)values;
    CHECK(c);
    return (fmi3Status)sew_no_such_kind(SLAVE(c), "fmi3SetClock", vr, nvr);
}

/* --- FMU state -------------------------------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    CHECK(c);
    return (fmi3Status)sew_state_get(SLAVE(c), "fmi3GetFMUState", FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState)
{
    CHECK(c);
    return (fmi3Status)sew_state_set(SLAVE(c), "fmi3SetFMUState", FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *FMUState)
{
    CHECK(c);
    return (fmi3Status)sew_state_free(SLAVE(c), "fmi3FreeFMUState", FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t *size)
{
    CHECK(c);
    return (fmi3Status)sew_state_size(SLAVE(c), "fmi3SerializedFMUStateSize", FMUState, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    CHECK(c);
    return (fmi3Status)sew_state_serialize(SLAVE(c), "fmi3SerializeFMUState", FMUState,
                                           serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    CHECK(c);
    return (fmi3Status)sew_state_deserialize(SLAVE(c), "fmi3DeserializeFMUState",
                                             serializedState, size, FMUState);
}
