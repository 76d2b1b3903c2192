/* What a mechanism's C model gives the runtime, and what the builder writes for each FMU.

   The runtime (sew_slave.c) carries, for every model, what components/slave.py's SewSlave does
   for the Python FMUs: parameters and inputs with their declared ranges, the held rates and the
   Taylor extrapolation of inputs inside a step, the time check, a step that fails leaving the
   instance as it was, FMU state. It is stricter where the Python FMUs can only log: a value
   outside its range, NaN, an unknown value reference or a write to an output is refused with
   an error status. A model (native/models/) only computes: it is the C twin of its Python model
   in components/, the same operations in the same order, so that the numbers agree to the last
   bits on one platform (docs/architecture.md says why twins, and how they are held equal).

   All values are doubles: an Integer parameter is a whole double, a Boolean output 0.0 or 1.0.
   Every array is in the order the Python slave class declares: parameters as the fields of its
   parameter dataclass, inputs as its `inputs` ports, the row as its `outputs` then `calculated`
   ports. */
#ifndef SEW_MODEL_H
#define SEW_MODEL_H

#include <stddef.h>

/* room for a refusal's reason, NUL included */
#define SEW_WHY 1024

typedef struct SewModel {
    const char *name;          /* the FMU's modelName, e.g. "PunchContact" */
    int n_derived;             /* doubles of constants `build` works out from the parameters */
    int n_state;               /* doubles of internal state between steps (0: stateless); all
                                  finite: the runtime discards a step that leaves one that is
                                  not (slave.py's state_is_finite) */

    /* Check the parameters p and work out the constants into derived (n_derived doubles).
       0, or -1 with the reason in why, naming the parameter as the Python model does
       ("parameter m: must be > 0, got -1", or a linkage that cannot assemble). */
    int (*build)(const double *p, double *derived, char *why);

    /* The internal state at the end of initialization (or before it, for outputs read then),
       from the held inputs u (rates the host did not set are 0). Unused when n_state is 0. */
    void (*initialize)(const double *p, const double *derived, const double *u, double *state);

    /* Advance the state from t to t + h. u: the inputs extrapolated to t, as
       slave.extrapolated_inputs(elapsed). 0, or -1 with the reason in why (the step the Python
       model refuses: ZenoError, StepTooLong); the runtime then restores the state. NULL when
       the model has no state (a linkage, the shaft). */
    int (*advance)(const double *p, const double *derived, double *state, const double *u,
                   double t, double h, char *why);

    /* The outputs and calculated parameters now, into row: t the current time, u the inputs
       extrapolated to now, state the current (or, before initialization, a freshly initialized)
       state. 0, or -1 with the reason in why (the runtime then gives NaN and logs it). */
    int (*outputs)(const double *p, const double *derived, const double *state, const double *u,
                   double t, double *row, char *why);

    /* 1: the model is a closed form of time from rest at t = 0 (the shaft), defined for t >= 0
       only, and the runtime refuses a negative start time saying so; 0: any start time (the
       model takes its time from its inputs, or only steps) */
    int from_time_zero;
} SewModel;

typedef enum { SEW_REAL = 0, SEW_INTEGER = 1, SEW_BOOLEAN = 2 } SewKind;
/* SEW_INDEPENDENT: FMI 3.0's `time` (value reference 0), read as the current time */
typedef enum {
    SEW_PARAMETER = 0, SEW_INPUT = 1, SEW_OUTPUT = 2, SEW_CALCULATED = 3, SEW_INDEPENDENT = 4
} SewCausality;

/* One variable as the FMU's modelDescription declares it (written by the builder from the
   Python FMU's modelDescription, so the two FMUs declare the same). */
typedef struct {
    const char *name;
    unsigned int vr;           /* its value reference in this FMU's modelDescription */
    SewKind kind;
    SewCausality causality;
    int index;                 /* its place: p[index], u[index] or row[index] (outputs, then
                                  calculated parameters, in one row) */
    double start;              /* parameters and inputs */
    double min, max;           /* the declared range; -HUGE_VAL / HUGE_VAL where none */
    const char *unit;
} SewVariable;

/* What the builder writes for one FMU (description.c, in its sources). */
typedef struct {
    const char *model_name;
    const char *token;         /* FMI 2.0 guid / FMI 3.0 instantiationToken */
    const SewModel *model;
    int n_variables;
    const SewVariable *variables;
    int n_params, n_inputs, n_row;
    /* Taylor chains of inputs (value, rate[, acceleration]) as input indices, -1 where a chain
       is shorter than 3: the Python slave's taylor_inputs */
    int n_chains;
    const int (*chains)[3];
} SewDescription;

extern const SewDescription SEW_DESCRIPTION;

/* Each model file defines one of these, e.g. `const SewModel SEW_MODEL_PunchContact`. */
#define SEW_MODEL(name) SEW_MODEL_##name

#endif
