/* The C host's FMI 3.0 co-simulation calls (see host.h). */
#include "host.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3FunctionTypes.h"

typedef struct {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3EnterInitializationModeTYPE *enter_initialization;
    fmi3ExitInitializationModeTYPE *exit_initialization;
    fmi3TerminateTYPE *terminate;
    fmi3DoStepTYPE *do_step;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt32TYPE *set_int32;
    fmi3SetBooleanTYPE *set_boolean;
    fmi3GetFloat64TYPE *get_float64;
    fmi3GetInt32TYPE *get_int32;
    fmi3GetBooleanTYPE *get_boolean;
    fmi3GetFMUStateTYPE *get_state;
    fmi3SetFMUStateTYPE *set_state;
    fmi3FreeFMUStateTYPE *free_state;
    fmi3SerializedFMUStateSizeTYPE *serialized_size;
    fmi3SerializeFMUStateTYPE *serialize;
    fmi3DeserializeFMUStateTYPE *deserialize;
} Fmi3;

static Fmi3 *fns(Host *h) { return (Fmi3 *)h->fns; }

/* the FMU's log lines, to stderr (FMI 3.0's message is plain text) */
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    (void)env;
    fprintf(stderr, "[%s] %s: %s\n", host_status_name((int)status), category ? category : "",
            message ? message : "");
}

static int bind(Host *h)
{
    Fmi3 *f = calloc(1, sizeof *f);
    if (!f) return -1;
    h->fns = f;
#define BIND(field, name) if (!(f->field = (name##TYPE *)host_symbol(h, #name))) return -1
    BIND(instantiate, fmi3InstantiateCoSimulation);
    BIND(free_instance, fmi3FreeInstance);
    BIND(enter_initialization, fmi3EnterInitializationMode);
    BIND(exit_initialization, fmi3ExitInitializationMode);
    BIND(terminate, fmi3Terminate);
    BIND(do_step, fmi3DoStep);
    BIND(set_float64, fmi3SetFloat64);
    BIND(set_int32, fmi3SetInt32);
    BIND(set_boolean, fmi3SetBoolean);
    BIND(get_float64, fmi3GetFloat64);
    BIND(get_int32, fmi3GetInt32);
    BIND(get_boolean, fmi3GetBoolean);
    BIND(get_state, fmi3GetFMUState);
    BIND(set_state, fmi3SetFMUState);
    BIND(free_state, fmi3FreeFMUState);
    BIND(serialized_size, fmi3SerializedFMUStateSize);
    BIND(serialize, fmi3SerializeFMUState);
    BIND(deserialize, fmi3DeserializeFMUState);
#undef BIND
    return 0;
}

static int instantiate(Host *h)
{
    Fmi3 *f = fns(h);
    h->call = "fmi3InstantiateCoSimulation";
    h->instance = f->instantiate("host", h->token, h->resources, fmi3False, fmi3True,
                                 fmi3False, fmi3False, NULL, 0, h, logger, NULL);
    return h->instance ? fmi3OK : fmi3Error;
}

static int set(Host *h, const HostVar *v)
{
    Fmi3 *f = fns(h);
    const fmi3ValueReference vr = v->vr;
    if (v->kind == HOST_INT) {
        const fmi3Int32 x = (fmi3Int32)v->value;
        h->call = "fmi3SetInt32";
        return f->set_int32(h->instance, &vr, 1, &x, 1);
    }
    if (v->kind == HOST_BOOL) {
        const fmi3Boolean x = v->value != 0.0;
        h->call = "fmi3SetBoolean";
        return f->set_boolean(h->instance, &vr, 1, &x, 1);
    }
    h->call = "fmi3SetFloat64";
    return f->set_float64(h->instance, &vr, 1, &v->value, 1);
}

static int get(Host *h, const HostVar *v, double *value)
{
    Fmi3 *f = fns(h);
    const fmi3ValueReference vr = v->vr;
    int status;
    if (v->kind == HOST_INT) {
        fmi3Int32 x = 0;
        h->call = "fmi3GetInt32";
        status = f->get_int32(h->instance, &vr, 1, &x, 1);
        *value = x;
    } else if (v->kind == HOST_BOOL) {
        fmi3Boolean x = fmi3False;
        h->call = "fmi3GetBoolean";
        status = f->get_boolean(h->instance, &vr, 1, &x, 1);
        *value = x ? 1.0 : 0.0;
    } else {
        h->call = "fmi3GetFloat64";
        status = f->get_float64(h->instance, &vr, 1, value, 1);
    }
    return status;
}

static int enter_initialization(Host *h)
{
    h->call = "fmi3EnterInitializationMode";
    return fns(h)->enter_initialization(h->instance, fmi3False, 0.0, h->start, fmi3True,
                                        h->stop);
}

static int exit_initialization(Host *h)
{
    h->call = "fmi3ExitInitializationMode";
    return fns(h)->exit_initialization(h->instance);
}

static int do_step(Host *h, double t, double step)
{
    fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
    fmi3Float64 last = t;
    int status;
    h->call = "fmi3DoStep";
    status = fns(h)->do_step(h->instance, t, step, fmi3True, &event, &terminate, &early, &last);
    /* this host allows no early return and runs no event mode: either is a failure here */
    if (status == fmi3OK && (terminate || early)) {
        fprintf(stderr, "host: fmi3DoStep at t=%.17g asked to %s\n", t,
                terminate ? "terminate" : "return early");
        return fmi3Error;
    }
    return status;
}

static int get_state(Host *h, void **state)
{
    fmi3FMUState s = NULL;
    int status;
    h->call = "fmi3GetFMUState";
    status = fns(h)->get_state(h->instance, &s);
    *state = s;
    return status;
}

static int set_state(Host *h, void *state)
{
    h->call = "fmi3SetFMUState";
    return fns(h)->set_state(h->instance, state);
}

static int free_state(Host *h, void **state)
{
    fmi3FMUState s = *state;
    int status;
    h->call = "fmi3FreeFMUState";
    status = fns(h)->free_state(h->instance, &s);
    *state = s;
    return status;
}

static int serialize(Host *h, void *state, unsigned char **bytes, size_t *size)
{
    int status;
    h->call = "fmi3SerializedFMUStateSize";
    status = fns(h)->serialized_size(h->instance, state, size);
    if (status != fmi3OK) return status;
    *bytes = malloc(*size ? *size : 1);
    if (!*bytes) return fmi3Fatal;
    h->call = "fmi3SerializeFMUState";
    return fns(h)->serialize(h->instance, state, (fmi3Byte *)*bytes, *size);
}

static int deserialize(Host *h, const unsigned char *bytes, size_t size, void **state)
{
    fmi3FMUState s = NULL;
    int status;
    h->call = "fmi3DeserializeFMUState";
    status = fns(h)->deserialize(h->instance, (const fmi3Byte *)bytes, size, &s);
    *state = s;
    return status;
}

static int terminate(Host *h)
{
    h->call = "fmi3Terminate";
    return fns(h)->terminate(h->instance);
}

static void free_instance(Host *h)
{
    if (h->instance) fns(h)->free_instance(h->instance);
    h->instance = NULL;
}

const HostOps HOST_FMI3 = {
    bind, instantiate, set, get, enter_initialization, exit_initialization, do_step,
    get_state, set_state, free_state, serialize, deserialize, terminate, free_instance,
};
