/* FMU state of a native sewfmu FMU (get, set, free, serialize, deserialize): what
   components/fmu_state.py keeps for the Python FMUs (the parameters, the inputs, the time, the
   internal state, which rates are held), so that a restored state repeats the following steps
   bit for bit.

   Serialized, a state is: the magic "SEWFMUS1", the model name and the FMU's token (each a
   32-bit length and its bytes), the payload's size (32 bits), the payload, and a 64-bit FNV-1a
   checksum of all that comes before it; numbers little-endian. Anything else (another FMU's
   state, a truncated or altered one, values outside the declared ranges) is refused with an
   Error, and nothing is restored. */
#include "sew_slave.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SEW_STATE_MAGIC 0x53455753u       /* a live state object: "SEWS" */
static const unsigned char SERIAL_MAGIC[8] = {'S', 'E', 'W', 'F', 'M', 'U', 'S', '1'};

typedef struct {
    uint32_t magic;
    const SewDescription *d;   /* the FMU it is a state of */
    int phase, initialized;
    double time, elapsed;
    char broken[SEW_WHY];
    double *values;            /* parameters, inputs, internal state */
    unsigned char *flags;      /* fresh, held (one per input each) */
} Snapshot;

static size_t n_values(const SewDescription *d)
{
    return (size_t)d->n_params + (size_t)d->n_inputs + (size_t)d->model->n_state;
}

static Snapshot *snapshot_new(const SewDescription *d)
{
    Snapshot *k = calloc(1, sizeof *k);
    if (!k)
        return NULL;
    k->values = calloc(n_values(d) + 1, sizeof(double));
    k->flags = calloc(2 * (size_t)d->n_inputs + 1, 1);
    if (!k->values || !k->flags) {
        free(k->values);
        free(k->flags);
        free(k);
        return NULL;
    }
    k->magic = SEW_STATE_MAGIC;
    k->d = d;
    return k;
}

static void snapshot_free(Snapshot *k)
{
    if (!k)
        return;
    k->magic = 0;
    free(k->values);
    free(k->flags);
    free(k);
}

static const Snapshot *own_snapshot(const SewSlave *s, const void *state)
{
    const Snapshot *k = state;
    return k && k->magic == SEW_STATE_MAGIC && k->d == s->d ? k : NULL;
}

static void take(const SewSlave *s, Snapshot *k)
{
    const SewDescription *d = s->d;
    size_t np = (size_t)d->n_params, ni = (size_t)d->n_inputs;
    k->phase = (int)s->phase;
    k->initialized = s->initialized;
    k->time = s->time;
    k->elapsed = s->elapsed;
    memcpy(k->broken, s->broken, sizeof k->broken);
    memcpy(k->values, s->p, np * sizeof(double));
    memcpy(k->values + np, s->u, ni * sizeof(double));
    memcpy(k->values + np + ni, s->state, (size_t)d->model->n_state * sizeof(double));
    memcpy(k->flags, s->fresh, ni);
    memcpy(k->flags + ni, s->held, ni);
}

SewStatus sew_state_get(SewSlave *s, const char *call, void **state)
{
    if (!state)
        return sew_refuse(s, "%s: no place given for the state", call);
    Snapshot *k = *state ? (Snapshot *)own_snapshot(s, *state) : snapshot_new(s->d);
    if (!k)
        return sew_refuse(s, "%s: %s", call, *state ? "the state given to overwrite is not a "
                          "state of this FMU" : "out of memory");
    take(s, k);
    *state = k;
    return SEW_OK;
}

SewStatus sew_state_set(SewSlave *s, const char *call, const void *state)
{
    const Snapshot *k = own_snapshot(s, state);
    const SewDescription *d = s->d;
    size_t np = (size_t)d->n_params, ni = (size_t)d->n_inputs;
    if (!k)
        return sew_refuse(s, "%s: not a state of this FMU; the instance is left as it was", call);
    if (memcmp(s->p, k->values, np * sizeof(double)) != 0)
        s->built = 0;
    s->phase = (SewPhase)k->phase;
    s->initialized = k->initialized;
    s->time = k->time;
    s->elapsed = k->elapsed;
    memcpy(s->broken, k->broken, sizeof s->broken);
    memcpy(s->p, k->values, np * sizeof(double));
    memcpy(s->u, k->values + np, ni * sizeof(double));
    memcpy(s->state, k->values + np + ni, (size_t)d->model->n_state * sizeof(double));
    memcpy(s->fresh, k->flags, ni);
    memcpy(s->held, k->flags + ni, ni);
    s->any_fresh = 0;
    for (size_t i = 0; i < ni; i++)
        s->any_fresh |= s->fresh[i];
    s->held_stale = 1;
    s->cached = 0;
    return SEW_OK;
}

SewStatus sew_state_free(SewSlave *s, const char *call, void **state)
{
    if (!state || !*state)
        return SEW_OK;
    Snapshot *k = (Snapshot *)own_snapshot(s, *state);
    if (!k)
        return sew_refuse(s, "%s: not a state of this FMU", call);
    snapshot_free(k);
    *state = NULL;
    return SEW_OK;
}

/* --- serialized ------------------------------------------------------------------------------- */

static size_t payload_size(const SewDescription *d)
{
    /* phase, initialized; time, elapsed; the values; the flags; broken's length and bytes */
    return 2 + 16 + 8 * n_values(d) + 2 * (size_t)d->n_inputs + 2 + (SEW_WHY - 1);
}

static size_t serial_size(const SewDescription *d)
{
    return sizeof SERIAL_MAGIC + 4 + strlen(d->model_name) + 4 + strlen(d->token) + 4
           + payload_size(d) + 8;
}

static uint64_t fnv1a(const unsigned char *bytes, size_t n)
{
    uint64_t h = 14695981039346656037ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= bytes[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static void put_u(unsigned char **at, uint64_t x, int bytes)
{
    for (int i = 0; i < bytes; i++)
        *(*at)++ = (unsigned char)(x >> (8 * i));
}

static uint64_t get_u(const unsigned char **at, int bytes)
{
    uint64_t x = 0;
    for (int i = 0; i < bytes; i++)
        x |= (uint64_t)*(*at)++ << (8 * i);
    return x;
}

static void put_f(unsigned char **at, double x)
{
    uint64_t bits;
    memcpy(&bits, &x, 8);
    put_u(at, bits, 8);
}

static double get_f(const unsigned char **at)
{
    uint64_t bits = get_u(at, 8);
    double x;
    memcpy(&x, &bits, 8);
    return x;
}

static void put_text(unsigned char **at, const char *text)
{
    size_t n = strlen(text);
    put_u(at, n, 4);
    memcpy(*at, text, n);
    *at += n;
}

SewStatus sew_state_size(SewSlave *s, const char *call, const void *state, size_t *size)
{
    if (!own_snapshot(s, state) || !size)
        return sew_refuse(s, "%s: not a state of this FMU", call);
    *size = serial_size(s->d);
    return SEW_OK;
}

SewStatus sew_state_serialize(SewSlave *s, const char *call, const void *state,
                              unsigned char *out, size_t size)
{
    const Snapshot *k = own_snapshot(s, state);
    const SewDescription *d = s->d;
    if (!k)
        return sew_refuse(s, "%s: not a state of this FMU", call);
    if (!out || size != serial_size(d))
        return sew_refuse(s, "%s: the buffer must be of %lu bytes, got %lu", call,
                          (unsigned long)serial_size(d), (unsigned long)size);
    unsigned char *at = out;
    memcpy(at, SERIAL_MAGIC, sizeof SERIAL_MAGIC);
    at += sizeof SERIAL_MAGIC;
    put_text(&at, d->model_name);
    put_text(&at, d->token);
    put_u(&at, payload_size(d), 4);
    put_u(&at, (uint64_t)k->phase, 1);
    put_u(&at, (uint64_t)k->initialized, 1);
    put_f(&at, k->time);
    put_f(&at, k->elapsed);
    for (size_t i = 0; i < n_values(d); i++)
        put_f(&at, k->values[i]);
    memcpy(at, k->flags, 2 * (size_t)d->n_inputs);
    at += 2 * (size_t)d->n_inputs;
    size_t broken = strlen(k->broken);
    put_u(&at, broken, 2);
    memset(at, 0, SEW_WHY - 1);
    memcpy(at, k->broken, broken);
    at += SEW_WHY - 1;
    put_u(&at, fnv1a(out, (size_t)(at - out)), 8);
    return SEW_OK;
}

/* 0 if text of the length stored at *at is `expected` (moving past it) */
static int same_text(const unsigned char **at, const unsigned char *end, const char *expected)
{
    if (end - *at < 4)
        return -1;
    uint64_t n = get_u(at, 4);
    if (n != strlen(expected) || (uint64_t)(end - *at) < n || memcmp(*at, expected, n) != 0)
        return -1;
    *at += n;
    return 0;
}

/* why the values of a deserialized state are not ones this FMU can hold, or NULL */
static const char *bad_values(const SewDescription *d, const Snapshot *k, char *why)
{
    if (k->phase < SEW_INSTANTIATED || k->phase > SEW_TERMINATED || k->initialized > 1
        || k->initialized != (k->phase >= SEW_STEPPING))
        return "its mode is not one of this FMU's";
    if (!isfinite(k->time) || !(k->elapsed >= 0.0 && k->elapsed < HUGE_VAL))
        return "its time is not a finite number";
    for (int i = 0; i < d->n_variables; i++) {
        const SewVariable *v = &d->variables[i];
        double x;
        if (v->causality == SEW_PARAMETER)
            x = k->values[v->index];
        else if (v->causality == SEW_INPUT)
            x = k->values[d->n_params + v->index];
        else
            continue;
        if (!(x >= v->min && x <= v->max) || (v->kind == SEW_INTEGER && x != floor(x))) {
            snprintf(why, SEW_WHY, "%s = %g is outside its declared range", v->name, x);
            return why;
        }
    }
    for (size_t i = (size_t)d->n_params + (size_t)d->n_inputs; i < n_values(d); i++)
        if (!isfinite(k->values[i]))
            return "its internal state is not finite";
    for (int i = 0; i < 2 * d->n_inputs; i++)
        if (k->flags[i] > 1)
            return "its flags are not 0 or 1";
    return NULL;
}

SewStatus sew_state_deserialize(SewSlave *s, const char *call, const unsigned char *in,
                                size_t size, void **state)
{
    const SewDescription *d = s->d;
    const unsigned char *at = in, *end = in + size;
    char why[SEW_WHY];
    const char *bad = NULL;
    if (!state)
        return sew_refuse(s, "%s: no place given for the state", call);
    if (!in || size != serial_size(d) || memcmp(in, SERIAL_MAGIC, sizeof SERIAL_MAGIC) != 0)
        bad = size && in && memcmp(in, SERIAL_MAGIC, size < 8 ? size : 8) == 0
                  ? "its size is not that of this FMU's state"
                  : "it does not begin as a serialized sewfmu state";
    else if (fnv1a(in, size - 8) != (at = in + size - 8, get_u(&at, 8)))
        bad = "its checksum does not match (altered or truncated)";
    if (!bad) {
        at = in + sizeof SERIAL_MAGIC;
        if (same_text(&at, end, d->model_name) != 0)
            bad = "it is the state of another model";
        else if (same_text(&at, end, d->token) != 0)
            bad = "it is the state of another build of this FMU (another token)";
        else if (get_u(&at, 4) != payload_size(d))
            bad = "its payload's size is not that of this FMU's state";
    }
    if (bad)
        return sew_refuse(s, "%s: not a state of this FMU (%s); nothing was restored", call, bad);
    Snapshot *k = snapshot_new(d);
    if (!k)
        return sew_refuse(s, "%s: out of memory", call);
    k->phase = (int)get_u(&at, 1);
    k->initialized = (int)get_u(&at, 1);
    k->time = get_f(&at);
    k->elapsed = get_f(&at);
    for (size_t i = 0; i < n_values(d); i++)
        k->values[i] = get_f(&at);
    memcpy(k->flags, at, 2 * (size_t)d->n_inputs);
    at += 2 * (size_t)d->n_inputs;
    size_t broken = (size_t)get_u(&at, 2);
    if (broken >= SEW_WHY || memchr(at, '\0', broken) != NULL) {
        bad = "its reason for refusing steps is garbled";
    } else {
        memcpy(k->broken, at, broken);
        k->broken[broken] = '\0';
        bad = bad_values(d, k, why);
    }
    if (bad) {
        snapshot_free(k);
        return sew_refuse(s, "%s: not a state of this FMU (%s); nothing was restored", call, bad);
    }
    *state = k;      /* a new state: one the host had there is its own to free */
    return SEW_OK;
}
