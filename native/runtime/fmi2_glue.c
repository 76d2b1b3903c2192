/* FMI 2.0 co-simulation over the runtime (sew_slave.h): every function of fmi2Functions.h.
   What a co-simulation FMU of sewfmu does not provide (directional and input/output
   derivatives, asynchronous steps, model exchange) is refused with fmi2Error and a log line. */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "sew_slave.h"

typedef struct {
    SewSlave *slave;
    fmi2CallbackFunctions cb;
    char *name;
    int logging;
    int discarded;      /* the last doStep was discarded: fmi2Terminated is true */
} Fmi2Instance;

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

/* the line is passed as the format: sew_log wrote any '%' out in words */
static void log_line(void *env, SewStatus status, const char *line)
{
    Fmi2Instance *c = env;
    if (c->cb.logger && (c->logging || status != SEW_OK))
        c->cb.logger(c->cb.componentEnvironment, c->name, (fmi2Status)status,
                     category_of(status), line);
}

#define SLAVE(c) (((Fmi2Instance *)(c))->slave)
#define CHECK(c)                                                                                  \
    do {                                                                                          \
        if (!(c))                                                                                 \
            return fmi2Error;                                                                     \
    } while (0)

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    CHECK(c);
    if (sew_check_categories(SLAVE(c), "fmi2SetDebugLogging", nCategories,
                             (const char *const *)categories) != SEW_OK)
        return fmi2Error;
    ((Fmi2Instance *)c)->logging = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions)
        return NULL;
    const char *name = instanceName && instanceName[0] ? instanceName : "?";
    const char *why = NULL;
    if (fmuType != fmi2CoSimulation)
        why = "fmi2Instantiate: this FMU is for co-simulation only (fmuType must be "
              "fmi2CoSimulation)";
    else if (!fmuGUID || strcmp(fmuGUID, SEW_DESCRIPTION.token) != 0)
        why = "fmi2Instantiate: the GUID is not this FMU's (a modelDescription of another "
              "build?)";
    if (why) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, name, fmi2Error,
                              "logStatusError", why);
        return NULL;
    }
    Fmi2Instance *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->cb = *functions;
    c->logging = loggingOn ? 1 : 0;
    c->name = malloc(strlen(name) + 1);
    if (c->name)
        strcpy(c->name, name);
    c->slave = c->name ? sew_new(&SEW_DESCRIPTION, name, log_line, c) : NULL;
    if (!c->slave) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, name, fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        free(c->name);
        free(c);
        return NULL;
    }
    return c;
}

void fmi2FreeInstance(fmi2Component c)
{
    if (!c)
        return;
    sew_free(SLAVE(c));
    free(((Fmi2Instance *)c)->name);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    CHECK(c);
    SewSlave *s = SLAVE(c);
    if (s->phase != SEW_INSTANTIATED)
        return (fmi2Status)sew_refuse(s, "fmi2SetupExperiment: only before "
                                      "fmi2EnterInitializationMode");
    if (sew_check_start_time(s, "fmi2SetupExperiment", startTime) != SEW_OK)
        return fmi2Error;
    if (stopTimeDefined && !(stopTime >= startTime))
        return (fmi2Status)sew_refuse(s, "fmi2SetupExperiment: the stop time %g is before the "
                                      "start time %g", stopTime, startTime);
    s->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    CHECK(c);
    return (fmi2Status)sew_enter_initialization(SLAVE(c), "fmi2EnterInitializationMode",
                                                SLAVE(c)->time);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    CHECK(c);
    return (fmi2Status)sew_exit_initialization(SLAVE(c), "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    CHECK(c);
    return (fmi2Status)sew_terminate(SLAVE(c), "fmi2Terminate");
}

fmi2Status fmi2Reset(fmi2Component c)
{
    CHECK(c);
    sew_reset(SLAVE(c));
    ((Fmi2Instance *)c)->discarded = 0;
    return fmi2OK;
}

/* --- values ----------------------------------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    CHECK(c);
    return (fmi2Status)sew_get(SLAVE(c), "fmi2GetReal", SEW_REAL, vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    CHECK(c);
    return (fmi2Status)sew_set(SLAVE(c), "fmi2SetReal", SEW_REAL, vr, nvr, value);
}

/* Integer and Boolean values pass through doubles (sew_model.h: all values are doubles) */
static double *doubles(SewSlave *s, const char *call, size_t n)
{
    double *x = malloc((n > 0 ? n : 1) * sizeof(double));
    if (!x)
        sew_refuse(s, "%s: out of memory", call);
    return x;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    CHECK(c);
    double *x = doubles(SLAVE(c), "fmi2GetInteger", nvr);
    if (!x)
        return fmi2Error;
    SewStatus status = sew_get(SLAVE(c), "fmi2GetInteger", SEW_INTEGER, vr, nvr, x);
    for (size_t i = 0; i < nvr && value && status != SEW_ERROR; i++)
            value[i] = (fmi2Integer)x[i];
    free(x);
    return (fmi2Status)status;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    CHECK(c);
    double *x = doubles(SLAVE(c), "fmi2SetInteger", nvr);
    if (!x)
        return fmi2Error;
    for (size_t i = 0; i < nvr && value; i++)
        x[i] = (double)value[i];
    SewStatus status = sew_set(SLAVE(c), "fmi2SetInteger", SEW_INTEGER, vr, nvr,
                               value ? x : NULL);
    free(x);
    return (fmi2Status)status;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    CHECK(c);
    double *x = doubles(SLAVE(c), "fmi2GetBoolean", nvr);
    if (!x)
        return fmi2Error;
    SewStatus status = sew_get(SLAVE(c), "fmi2GetBoolean", SEW_BOOLEAN, vr, nvr, x);
    for (size_t i = 0; i < nvr && value && status != SEW_ERROR; i++)
        value[i] = x[i] != 0.0 ? fmi2True : fmi2False;
    free(x);
    return (fmi2Status)status;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    CHECK(c);
    double *x = doubles(SLAVE(c), "fmi2SetBoolean", nvr);
    if (!x)
        return fmi2Error;
    for (size_t i = 0; i < nvr && value; i++)
        x[i] = value[i] ? 1.0 : 0.0;
    SewStatus status = sew_set(SLAVE(c), "fmi2SetBoolean", SEW_BOOLEAN, vr, nvr,
                               value ? x : NULL);
    free(x);
    return (fmi2Status)status;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)value;
    CHECK(c);
    return (fmi2Status)sew_no_such_kind(SLAVE(c), "fmi2GetString", vr, nvr);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)value;
    CHECK(c);
    return (fmi2Status)sew_no_such_kind(SLAVE(c), "fmi2SetString", vr, nvr);
}

/* --- FMU state -------------------------------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK(c);
    return (fmi2Status)sew_state_get(SLAVE(c), "fmi2GetFMUstate", FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    CHECK(c);
    return (fmi2Status)sew_state_set(SLAVE(c), "fmi2SetFMUstate", FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK(c);
    return (fmi2Status)sew_state_free(SLAVE(c), "fmi2FreeFMUstate", FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    CHECK(c);
    return (fmi2Status)sew_state_size(SLAVE(c), "fmi2SerializedFMUstateSize", FMUstate, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    CHECK(c);
    return (fmi2Status)sew_state_serialize(SLAVE(c), "fmi2SerializeFMUstate", FMUstate,
                                           (unsigned char *)serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    CHECK(c);
    return (fmi2Status)sew_state_deserialize(SLAVE(c), "fmi2DeSerializeFMUstate",
                                             (const unsigned char *)serializedState, size,
                                             FMUstate);
}

/* --- what a sewfmu co-simulation FMU does not provide ----------------------------------------- */

#define REFUSE(c, call, why)                                                                      \
    do {                                                                                          \
        CHECK(c);                                                                                 \
        return (fmi2Status)sew_refuse(SLAVE(c), "%s: %s", call, why);                             \
    } while (0)

static const char *const NO_DERIVATIVES = "not provided (providesDirectionalDerivative, "
                                          "canInterpolateInputs and maxOutputDerivativeOrder are "
                                          "not declared)";
static const char *const NO_ME = "not provided: this FMU is for co-simulation only";
static const char *const NO_ASYNC = "not provided: doStep never returns fmi2Pending";

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown;
    (void)dvUnknown;
    REFUSE(c, "fmi2GetDirectionalDerivative", NO_DERIVATIVES);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    REFUSE(c, "fmi2SetRealInputDerivatives", NO_DERIVATIVES);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    REFUSE(c, "fmi2GetRealOutputDerivatives", NO_DERIVATIVES);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c);
    SewStatus status = sew_do_step(SLAVE(c), "fmi2DoStep", currentCommunicationPoint,
                                   communicationStepSize);
    ((Fmi2Instance *)c)->discarded = status == SEW_DISCARD;
    return (fmi2Status)status;
}

fmi2Status fmi2CancelStep(fmi2Component c) { REFUSE(c, "fmi2CancelStep", NO_ASYNC); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s, (void)value;
    REFUSE(c, "fmi2GetStatus", NO_ASYNC);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    CHECK(c);
    if (s == fmi2LastSuccessfulTime && value) {
        *value = SLAVE(c)->time;
        return fmi2OK;
    }
    REFUSE(c, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is provided");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s, (void)value;
    REFUSE(c, "fmi2GetIntegerStatus", NO_ASYNC);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    CHECK(c);
    if (s == fmi2Terminated && value) {
        /* true after a Discard, as pythonfmu's binary answers for the Python FMUs: a host that
           asks (fmpy's simulate_fmu, fmusim) stops there instead of retrying the same step
           without end; a master that retries shorter steps does not ask (pythonfmu keeps it
           set for good; here the next step taken clears it) */
        *value = ((Fmi2Instance *)c)->discarded ? fmi2True : fmi2False;
        return fmi2OK;
    }
    REFUSE(c, "fmi2GetBooleanStatus", "only fmi2Terminated is provided");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s, (void)value;
    REFUSE(c, "fmi2GetStringStatus", NO_ASYNC);
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { REFUSE(c, "fmi2EnterEventMode", NO_ME); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *fmi2eventInfo)
{
    (void)fmi2eventInfo;
    REFUSE(c, "fmi2NewDiscreteStates", NO_ME);
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    REFUSE(c, "fmi2EnterContinuousTimeMode", NO_ME);
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    REFUSE(c, "fmi2CompletedIntegratorStep", NO_ME);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    REFUSE(c, "fmi2SetTime", NO_ME);
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x, (void)nx;
    REFUSE(c, "fmi2SetContinuousStates", NO_ME);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    (void)derivatives, (void)nx;
    REFUSE(c, "fmi2GetDerivatives", NO_ME);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators, (void)ni;
    REFUSE(c, "fmi2GetEventIndicators", NO_ME);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x, (void)nx;
    REFUSE(c, "fmi2GetContinuousStates", NO_ME);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    (void)x_nominal, (void)nx;
    REFUSE(c, "fmi2GetNominalsOfContinuousStates", NO_ME);
}
