/* The C host's FMI 2.0 co-simulation calls (see host.h). */
#include "host.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_initialization;
    fmi2ExitInitializationModeTYPE *exit_initialization;
    fmi2TerminateTYPE *terminate;
    fmi2DoStepTYPE *do_step;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2GetBooleanTYPE *get_boolean;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *serialized_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
    fmi2CallbackFunctions callbacks;  /* the FMU may keep a pointer to it: it lives here */
} Fmi2;

static Fmi2 *fns(Host *h) { return (Fmi2 *)h->fns; }

/* the FMU's log lines, to stderr (FMI 2.0's message is a printf format) */
static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] %s %s: ", host_status_name((int)status), instance ? instance : "",
            category ? category : "");
    va_start(args, message);
    vfprintf(stderr, message ? message : "", args);
    va_end(args);
    fputc('\n', stderr);
}

static int bind(Host *h)
{
    Fmi2 *f = calloc(1, sizeof *f);
    if (!f) return -1;
    h->fns = f;
#define BIND(field, name) if (!(f->field = (name##TYPE *)host_symbol(h, #name))) return -1
    BIND(instantiate, fmi2Instantiate);
    BIND(free_instance, fmi2FreeInstance);
    BIND(setup_experiment, fmi2SetupExperiment);
    BIND(enter_initialization, fmi2EnterInitializationMode);
    BIND(exit_initialization, fmi2ExitInitializationMode);
    BIND(terminate, fmi2Terminate);
    BIND(do_step, fmi2DoStep);
    BIND(set_real, fmi2SetReal);
    BIND(set_integer, fmi2SetInteger);
    BIND(set_boolean, fmi2SetBoolean);
    BIND(get_real, fmi2GetReal);
    BIND(get_integer, fmi2GetInteger);
    BIND(get_boolean, fmi2GetBoolean);
    BIND(get_state, fmi2GetFMUstate);
    BIND(set_state, fmi2SetFMUstate);
    BIND(free_state, fmi2FreeFMUstate);
    BIND(serialized_size, fmi2SerializedFMUstateSize);
    BIND(serialize, fmi2SerializeFMUstate);
    BIND(deserialize, fmi2DeSerializeFMUstate);
#undef BIND
    f->callbacks.logger = logger;
    f->callbacks.allocateMemory = calloc;
    f->callbacks.freeMemory = free;
    return 0;
}

static int instantiate(Host *h)
{
    Fmi2 *f = fns(h);
    h->call = "fmi2Instantiate";
    h->instance = f->instantiate("host", fmi2CoSimulation, h->token, h->resources, &f->callbacks,
                                 fmi2False, fmi2True);
    if (!h->instance) return fmi2Error;
    /* FMI 2.0 takes the experiment's times here; 3.0 at enterInitializationMode */
    h->call = "fmi2SetupExperiment";
    return f->setup_experiment(h->instance, fmi2False, 0.0, h->start, fmi2True, h->stop);
}

static int set(Host *h, const HostVar *v)
{
    Fmi2 *f = fns(h);
    const fmi2ValueReference vr = v->vr;
    if (v->kind == HOST_INT) {
        const fmi2Integer x = (fmi2Integer)v->value;
        h->call = "fmi2SetInteger";
        return f->set_integer(h->instance, &vr, 1, &x);
    }
    if (v->kind == HOST_BOOL) {
        const fmi2Boolean x = v->value != 0.0 ? fmi2True : fmi2False;
        h->call = "fmi2SetBoolean";
        return f->set_boolean(h->instance, &vr, 1, &x);
    }
    h->call = "fmi2SetReal";
    return f->set_real(h->instance, &vr, 1, &v->value);
}

static int get(Host *h, const HostVar *v, double *value)
{
    Fmi2 *f = fns(h);
    const fmi2ValueReference vr = v->vr;
    int status;
    if (v->kind == HOST_INT) {
        fmi2Integer x = 0;
        h->call = "fmi2GetInteger";
        status = f->get_integer(h->instance, &vr, 1, &x);
        *value = x;
    } else if (v->kind == HOST_BOOL) {
        fmi2Boolean x = fmi2False;
        h->call = "fmi2GetBoolean";
        status = f->get_boolean(h->instance, &vr, 1, &x);
        *value = x ? 1.0 : 0.0;
    } else {
        h->call = "fmi2GetReal";
        status = f->get_real(h->instance, &vr, 1, value);
    }
    return status;
}

static int enter_initialization(Host *h)
{
    h->call = "fmi2EnterInitializationMode";
    return fns(h)->enter_initialization(h->instance);
}

static int exit_initialization(Host *h)
{
    h->call = "fmi2ExitInitializationMode";
    return fns(h)->exit_initialization(h->instance);
}

static int do_step(Host *h, double t, double step)
{
    h->call = "fmi2DoStep";
    return fns(h)->do_step(h->instance, t, step, fmi2True);
}

static int get_state(Host *h, void **state)
{
    fmi2FMUstate s = NULL;
    int status;
    h->call = "fmi2GetFMUstate";
    status = fns(h)->get_state(h->instance, &s);
    *state = s;
    return status;
}

static int set_state(Host *h, void *state)
{
    h->call = "fmi2SetFMUstate";
    return fns(h)->set_state(h->instance, state);
}

static int free_state(Host *h, void **state)
{
    fmi2FMUstate s = *state;
    int status;
    h->call = "fmi2FreeFMUstate";
    status = fns(h)->free_state(h->instance, &s);
    *state = s;
    return status;
}

static int serialize(Host *h, void *state, unsigned char **bytes, size_t *size)
{
    int status;
    h->call = "fmi2SerializedFMUstateSize";
    status = fns(h)->serialized_size(h->instance, state, size);
    if (status != fmi2OK) return status;
    *bytes = malloc(*size ? *size : 1);
    if (!*bytes) return fmi2Fatal;
    h->call = "fmi2SerializeFMUstate";
    return fns(h)->serialize(h->instance, state, (fmi2Byte *)*bytes, *size);
}

static int deserialize(Host *h, const unsigned char *bytes, size_t size, void **state)
{
    fmi2FMUstate s = NULL;
    int status;
    h->call = "fmi2DeSerializeFMUstate";
    status = fns(h)->deserialize(h->instance, (const fmi2Byte *)bytes, size, &s);
    *state = s;
    return status;
}

static int terminate(Host *h)
{
    h->call = "fmi2Terminate";
    return fns(h)->terminate(h->instance);
}

static void free_instance(Host *h)
{
    if (h->instance) fns(h)->free_instance(h->instance);
    h->instance = NULL;
}

const HostOps HOST_FMI2 = {
    bind, instantiate, set, get, enter_initialization, exit_initialization, do_step,
    get_state, set_state, free_state, serialize, deserialize, terminate, free_instance,
};
