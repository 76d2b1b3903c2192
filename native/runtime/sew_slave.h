/* The runtime of a native sewfmu FMU, below either FMI version's glue (fmi2_glue.c, fmi3_glue.c):
   what components/slave.py's SewSlave and components/fmu_state.py do for the Python FMUs, over
   a model of sew_model.h and the table description.c gives (SEW_DESCRIPTION).

   It is stricter than the Python FMUs, which pythonfmu lets only log: an unknown value
   reference, a value outside its declared range, NaN or infinity, a write to an output or a
   calculated parameter, a parameter set after initialization and a garbled serialized state
   are refused with SEW_ERROR and the reason through the logger, the instance left as it was.
   A step the model cannot take (its advance fails, or leaves a non-finite state) is SEW_DISCARD,
   as with the Python FMUs, so that an adaptive master can retry it shorter. */
#ifndef SEW_SLAVE_H
#define SEW_SLAVE_H

#include <stddef.h>

#include "sew_model.h"

/* the same numbers as fmi2Status and fmi3Status */
typedef enum { SEW_OK = 0, SEW_WARNING = 1, SEW_DISCARD = 2, SEW_ERROR = 3, SEW_FATAL = 4 } SewStatus;

/* One log line "<instance> (<Model>): <reason>", without '%' (see sew_log in sew_slave.c). */
typedef void (*SewLogger)(void *env, SewStatus status, const char *line);

typedef enum {
    SEW_INSTANTIATED = 0,   /* before enterInitializationMode */
    SEW_INITIALIZING = 1,   /* initialization mode */
    SEW_STEPPING = 2,       /* after exitInitializationMode */
    SEW_TERMINATED = 3
} SewPhase;

typedef struct SewSlave {
    const SewDescription *d;
    const SewModel *model;
    char *instance;
    SewLogger log;
    void *env;
    SewPhase phase;

    double *p;              /* parameters, inputs as set */
    double *u;
    double *derived;        /* model->build's constants, valid while built */
    double *state;          /* the internal state (valid from exitInitializationMode) */
    double *row;            /* the outputs and calculated parameters now, valid while cached */
    unsigned char *fresh;   /* per input: set since the last step taken */
    unsigned char *held;    /* per input: a rate that acts as zero */
    int held_stale;         /* `held` is to be worked out again from `fresh` */
    int any_fresh;
    int built;              /* derived holds the constants of the parameters p */
    int cached;             /* row holds the outputs now */
    int cache_failed;       /* ... and they are NaN: the model could not give them */
    int initialized;        /* exitInitializationMode has run */
    double time, elapsed;   /* elapsed: since the inputs were last set (extrapolation) */
    char broken[SEW_WHY];   /* why every doStep is refused (bad parameters), or "" */

    int *by_vr;             /* value reference -> place in d->variables, -1: none */
    unsigned int n_vr;

    /* scratch, so that no step allocates */
    double *u_now, *saved_state, *scratch_state;
    char why[SEW_WHY];
    char last_error[SEW_WHY];
} SewSlave;

SewSlave *sew_new(const SewDescription *d, const char *instance, SewLogger log, void *env);
void sew_free(SewSlave *s);
/* back to the instantiated state with the start values (fmi2Reset, fmi3Reset) */
void sew_reset(SewSlave *s);

/* an Error line naming the call and the reason; returns SEW_ERROR */
SewStatus sew_refuse(SewSlave *s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void sew_log(SewSlave *s, SewStatus status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* SEW_ERROR with the reason where the model cannot start at start_time (not finite; before 0
   for a model of time from rest, sew_model.h's from_time_zero); SEW_OK */
SewStatus sew_check_start_time(SewSlave *s, const char *call, double start_time);
/* fmi2SetDebugLogging, fmi3SetDebugLogging: every category must be one the modelDescription
   declares (SEW_LOG_CATEGORIES); SEW_ERROR naming the first that is not and the known ones */
SewStatus sew_check_categories(SewSlave *s, const char *call, size_t n,
                               const char *const categories[]);
/* the LogCategories every sewfmu FMU declares (components/fmi3_layer.py, pythonfmu's), NULL
   ended; the glue logs each line under the one of its status */
extern const char *const SEW_LOG_CATEGORIES[];
SewStatus sew_enter_initialization(SewSlave *s, const char *call, double start_time);
SewStatus sew_exit_initialization(SewSlave *s, const char *call);
SewStatus sew_terminate(SewSlave *s, const char *call);
SewStatus sew_do_step(SewSlave *s, const char *call, double t, double h);

/* Values of the variables vr[0..n) of kind `kind`, all as doubles (an Integer as a whole
   double, a Boolean 0/1). `call` names the FMI call in the log. A set is all or nothing. */
SewStatus sew_get(SewSlave *s, const char *call, SewKind kind, const unsigned int *vr, size_t n,
                  double *values);
SewStatus sew_set(SewSlave *s, const char *call, SewKind kind, const unsigned int *vr, size_t n,
                  const double *values);
/* a call for a kind no sewfmu FMU declares (String, Float32, Int64, ...): n > 0 is refused */
SewStatus sew_no_such_kind(SewSlave *s, const char *call, const unsigned int *vr, size_t n);

/* FMU state (sew_state.c) */
SewStatus sew_state_get(SewSlave *s, const char *call, void **state);
SewStatus sew_state_set(SewSlave *s, const char *call, const void *state);
SewStatus sew_state_free(SewSlave *s, const char *call, void **state);
SewStatus sew_state_size(SewSlave *s, const char *call, const void *state, size_t *size);
SewStatus sew_state_serialize(SewSlave *s, const char *call, const void *state, unsigned char *out,
                              size_t size);
SewStatus sew_state_deserialize(SewSlave *s, const char *call, const unsigned char *in,
                                size_t size, void **state);

/* the inputs as the model takes them, held and extrapolated by dt (into s->u_now) */
const double *sew_extrapolated_inputs(SewSlave *s, double dt);
/* the variable of value reference vr, or NULL */
const SewVariable *sew_variable(const SewSlave *s, unsigned int vr);

#endif
