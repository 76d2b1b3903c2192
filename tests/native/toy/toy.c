/* A toy model and its description for tests/native/test_native_runtime.py: the runtime's own
   paths that sewfmu's models seldom take. One parameter k, one input u with its rate u_dot (a
   Taylor chain of two), one state x (dx/dt = k·u over a step, as x += k·u·h) and the outputs
   x and u as extrapolated now. Its advance refuses a step when u > 10 (a model's -1), and
   leaves x infinite when u > 5 (a state the runtime must not keep). */
#include <math.h>
#include <stdio.h>

#include "sew_model.h"

static int toy_build(const double *p, double *derived, char *why)
{
    if (p[0] == 3.0) {
        snprintf(why, SEW_WHY, "parameter k: 3 is unlucky");
        return -1;
    }
    derived[0] = 2.0 * p[0];
    return 0;
}

static void toy_initialize(const double *p, const double *derived, const double *u,
                           double *state)
{
    (void)p, (void)derived;
    state[0] = u[0];
}

static int toy_advance(const double *p, const double *derived, double *state, const double *u,
                       double t, double h, char *why)
{
    (void)derived, (void)t;
    if (u[0] > 10.0) {
        snprintf(why, SEW_WHY, "u = %g is too large for a step", u[0]);
        state[0] = -1.0;             /* a model that scribbles before it refuses */
        return -1;
    }
    state[0] = u[0] > 5.0 ? HUGE_VAL : state[0] + p[0] * u[0] * h;
    return 0;
}

static int toy_outputs(const double *p, const double *derived, const double *state,
                       const double *u, double t, double *row, char *why)
{
    (void)p, (void)derived, (void)t, (void)why;
    row[0] = state[0];
    row[1] = u[0];
    return 0;
}

const SewModel SEW_MODEL_Toy = {"Toy", 1, 1, toy_build, toy_initialize, toy_advance,
                                toy_outputs, 0};

static const SewVariable VARIABLES[] = {
    {"k", 0u, SEW_REAL, SEW_PARAMETER, 0, 1.0, 0.0, 100.0, ""},
    {"u", 1u, SEW_REAL, SEW_INPUT, 0, 0.0, -100.0, 100.0, "m"},
    {"u_dot", 2u, SEW_REAL, SEW_INPUT, 1, 0.0, -1e6, 1e6, "m/s"},
    {"x", 3u, SEW_REAL, SEW_OUTPUT, 0, 0.0, -HUGE_VAL, HUGE_VAL, "m"},
    {"u_now", 4u, SEW_REAL, SEW_OUTPUT, 1, 0.0, -HUGE_VAL, HUGE_VAL, "m"},
};

static const int CHAINS[][3] = {{0, 1, -1}};

const SewDescription SEW_DESCRIPTION = {"Toy", "toy-token", &SEW_MODEL_Toy, 5, VARIABLES,
                                        1, 2, 2, 1, CHAINS};
