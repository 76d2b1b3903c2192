/* The machine's main shaft: the C twin of components/shaft.py's MainShaft (the FMU MainShaft,
   components/shaft_fmu.py). Stateless: the angle, speed and acceleration are closed-form
   functions of time, a cycloidal speed ramp of duration ramp_time and then constant speed. */
/* twin-of: components/shaft.py sha256:cf6a79e1c52105db */
#include <math.h>
#include <stdio.h>

#include "parameters.h"
#include "sew_model.h"

#define SEW_PI 3.141592653589793

enum { OMEGA0, RAMP_TIME };     /* ShaftParams' fields */
enum { PHI, OMEGA, EPSILON };   /* the FMU's outputs */

static const SewParamInfo PARAMS[] = {
    SEW_PARAM("omega0", "rad/s", SEW_POSITIVE), SEW_PARAM("ramp_time", "s", SEW_NONNEGATIVE),
};

static int shaft_build(const double *p, double *derived, char *why)
{
    (void)derived;
    return sew_validate(PARAMS, 2, p, why);
}

/* MainShaft.state(t) */
static int shaft_outputs(const double *p, const double *derived, const double *state,
                         const double *u, double t, double *row, char *why)
{
    (void)derived, (void)state, (void)u;
    double w = p[OMEGA0], tr = p[RAMP_TIME];
    if (t < 0.0) {
        /* state(t) is for t >= 0 (the shaft starts at rest at t = 0): before, the Python model
           gives NaN (no ramp) or the ramp's formula run backwards, neither the shaft's motion */
        snprintf(why, SEW_WHY, "t = %g s is before the shaft starts (t = 0): the shaft's model "
                 "is defined for t >= 0 only", t);
        return -1;
    }
    if (t >= tr) {
        /* the ramp covers omega0*tr/2 of angle (mean speed omega0/2) */
        row[PHI] = w * (t - 0.5 * tr);
        row[OMEGA] = w;
        row[EPSILON] = 0.0;
        return 0;
    }
    double v = t / tr;
    double two_pi_u = 2.0 * SEW_PI * v;
    row[OMEGA] = w * (v - sin(two_pi_u) / (2.0 * SEW_PI));
    /* math.pi ** 2: the correctly rounded square, as SEW_PI * SEW_PI */
    row[PHI] = w * tr * (0.5 * v * v + (cos(two_pi_u) - 1.0) / (4.0 * (SEW_PI * SEW_PI)));
    row[EPSILON] = w / tr * (1.0 - cos(two_pi_u));
    return 0;
}

const SewModel SEW_MODEL_MainShaft = {
    "MainShaft", 0, 0, shaft_build, NULL, NULL, shaft_outputs, 1,
};
