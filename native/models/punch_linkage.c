/* twin-of: components/punch_linkage.py sha256:0bed7a164e56ef54 */
/* twin-of: components/punch_fmu.py sha256:bf257e4c55e423a8 */
/* The punch drive of the ultrasonic sewing machine (SEW_MODEL_PunchLinkage): the six-bar that
   lifts the punch, or the paper's required displacement function, as shaft angle phi -> the
   punch's kinematic excitation xi = xi0 - psi. The C twin of components/punch_linkage.py's
   PunchLinkage; its row is PunchLinkageSlave's outputs (components/punch_fmu.py). Stateless: the
   crank angle and slider height of the slider's top are worked out once, in build. */
#include <errno.h>
#include <math.h>
#include <stdio.h>

#include "kinematics.h"
#include "parameters.h"
#include "sew_model.h"

/* PunchLinkageParams' fields, in order */
enum {
    MODE, L_O1A, L_AB, L_O2B, L_O2C, ANGLE_BO2C, L_CD, X_O2, Y_O2, X_D, XI0, PSI_M, PHI_DESCENT,
    PHI_DWELL, PHI_RETURN, N_PARAMS
};
/* what build works out: the crank angle of the slider's top and its height there */
enum { ALPHA0, Y_TOP, N_DERIVED };

#define SIX_BAR 0
#define ASSEMBLY_SAMPLES 3600     /* the assembly check samples the crank turn every 0.1° */

#define LENGTH(name, allowed) SEW_PARAM(name, "m", allowed)
#define ANGLE(name, allowed) SEW_PARAM(name, "rad", allowed)

static const SewParamInfo PARAMS[N_PARAMS] = {
    {"mode", "1", SEW_CHOICE, 2, {0, 1, 0, 0}},
    LENGTH("L_O1A", SEW_POSITIVE), LENGTH("L_AB", SEW_POSITIVE), LENGTH("L_O2B", SEW_POSITIVE),
    LENGTH("L_O2C", SEW_POSITIVE), ANGLE("angle_BO2C", SEW_POSITIVE),
    LENGTH("L_CD", SEW_POSITIVE), LENGTH("x_O2", SEW_ANY), LENGTH("y_O2", SEW_ANY),
    LENGTH("x_D", SEW_ANY), LENGTH("xi0", SEW_NONNEGATIVE), LENGTH("psi_m", SEW_POSITIVE),
    ANGLE("phi_descent", SEW_POSITIVE), ANGLE("phi_dwell", SEW_NONNEGATIVE),
    ANGLE("phi_return", SEW_POSITIVE),
};

/* Python's float % (the sign of the divisor), as CPython's float_rem */
static double py_mod(double x, double y)
{
    double mod = fmod(x, y);
    if (mod != 0.0) {
        if ((y < 0) != (mod < 0))
            mod += y;
    } else {
        mod = copysign(0.0, y);
    }
    return mod;
}

/* Python's x ** 2 of a float, as CPython's float_pow: libm's pow, and OverflowError where it
   leaves the range (errno ERANGE, kept for a result that is not 0). The exponent is volatile:
   a compiler folds pow(x, 2.0) into x * x, which differs from glibc's pow in the last bit of
   about 1 square in 1500. */
static int py_square(double x, double *out, char *why)
{
    volatile double two = 2.0;
    double r;
    if (x == 0.0 || isnan(x) || isinf(x)) {
        *out = x == 0.0 ? 0.0 : fabs(x);
        return 0;
    }
    x = fabs(x);                 /* an even power of a negative number */
    if (x == 1.0) {
        *out = 1.0;
        return 0;
    }
    errno = 0;
    r = pow(x, two);
    if (errno == 0 && isinf(r))
        errno = ERANGE;
    else if (errno == ERANGE && r == 0.0)
        errno = 0;
    if (errno != 0) {
        snprintf(why, SEW_WHY, "(34, 'Numerical result out of range')");
        return -1;
    }
    *out = r;
    return 0;
}

/* PunchLinkage._chain's slider D for crank angle alpha (CCW from +x) and its derivatives */
static int slider(const double *p, double alpha, double rate, double accel, SewMotion *d,
                  char *why)
{
    SewMotion o1 = sew_at_rest(0.0, 0.0), o2 = sew_at_rest(p[X_O2], p[Y_O2]), a, b, c;
    SewAngle rocker;
    a = sew_point_on_link(o1, p[L_O1A], sew_angle(alpha, rate, accel), 0.0);
    /* B on the +x side of A -> O2, i.e. on the right of that (upward) line */
    if (sew_dyad_rrr(a, p[L_AB], o2, p[L_O2B], SEW_RIGHT, "coupler AB / rocker O2B", &b, why)
        != 0 || sew_link_angle(o2, b, &rocker, why) != 0)
        return -1;
    c = sew_point_on_link(o2, p[L_O2C], rocker, -p[ANGLE_BO2C]);
    /* D below C on the vertical line x = x_D */
    return sew_dyad_rrp(c, p[L_CD], p[X_D], 0.0, SEW_PI / 2, -1, "rod CD / slider line", d, why);
}

/* the assembly check's heights, reduced as it goes to the first highest (max of the list) */
typedef struct {
    const double *p;
    int k, highest;
    double y_highest;
} Heights;

static int height(void *context, double alpha, char *why)
{
    Heights *h = context;
    SewMotion d;
    if (slider(h->p, alpha, 0.0, 0.0, &d, why) != 0)
        return -1;
    if (h->k == 0 || d.y > h->y_highest) {
        h->highest = h->k;
        h->y_highest = d.y;
    }
    h->k++;
    return 0;
}

/* PunchLinkage._top: (crank angle, slider height) of the slider's highest point, after checking
   that the six-bar assembles over the whole turn; the crank angle where dY_D/dalpha changes sign
   + to -, bisected within a sample either side of the highest sample */
static int top_of(const double *p, double *alpha0, double *y_top, char *why)
{
    const char *names[N_PARAMS];
    Heights heights = {p, 0, 0, 0.0};
    double lo, hi, step = 2 * SEW_PI / ASSEMBLY_SAMPLES;
    SewMotion d;
    int i;
    for (i = 0; i < N_PARAMS; i++)
        names[i] = PARAMS[i].name;
    if (sew_check_assembly(height, &heights, "punch six-bar", names, p, N_PARAMS,
                           "crank angle alpha", ASSEMBLY_SAMPLES, why) != 0)
        return -1;
    lo = sew_crank_turn(heights.highest, ASSEMBLY_SAMPLES) - step;
    hi = sew_crank_turn(heights.highest, ASSEMBLY_SAMPLES) + step;
    for (i = 0; i < 60; i++) {       /* bisection on the slope: robust and exact enough */
        double mid = 0.5 * (lo + hi);
        /* dY_D/dalpha, analytic (crank rate 1); a failure here is Python's bare one */
        if (slider(p, mid, 1.0, 0.0, &d, why) != 0)
            return -1;
        if (d.vy > 0)
            lo = mid;
        else
            hi = mid;
    }
    *alpha0 = py_mod(0.5 * (lo + hi), 2 * SEW_PI);
    if (slider(p, *alpha0, 0.0, 0.0, &d, why) != 0)
        return -1;
    *y_top = d.y;
    return 0;
}

static int build(const double *p, double *derived, char *why)
{
    if (sew_validate(PARAMS, N_PARAMS, p, why) != 0)
        return -1;
    if ((int)p[MODE] == SIX_BAR)
        return top_of(p, &derived[ALPHA0], &derived[Y_TOP], why);
    if (p[PHI_DESCENT] + p[PHI_DWELL] + p[PHI_RETURN] > 2 * SEW_PI + 1e-12) {
        snprintf(why, SEW_WHY, "parameter phi_return: phi_descent + phi_dwell + phi_return "
                 "must not exceed one revolution (2\xcf\x80 rad)");
        return -1;
    }
    derived[ALPHA0] = 0.0;
    derived[Y_TOP] = 0.0;
    return 0;
}

/* PunchLinkage._required: psi and its first two derivatives with respect to phi: a cycloidal
   descent to psi_m, a dwell, a cycloidal return, rest at the top */
static int required(const double *p, double phi, double *psi, double *d1, double *d2,
                    char *why)
{
    double th = py_mod(phi, 2 * SEW_PI);
    double descent_end = p[PHI_DESCENT];
    double dwell_end = descent_end + p[PHI_DWELL];
    double return_end = dwell_end + p[PHI_RETURN];
    double start, width, sign, u, s, width2;
    if (th < descent_end) {
        start = 0.0;
        width = p[PHI_DESCENT];
        sign = +1.0;
    } else if (th < dwell_end) {
        *psi = p[PSI_M];
        *d1 = *d2 = 0.0;
        return 0;
    } else if (th < return_end) {
        start = dwell_end;
        width = p[PHI_RETURN];
        sign = -1.0;
    } else {
        *psi = *d1 = *d2 = 0.0;                            /* at rest at the top */
        return 0;
    }
    u = (th - start) / width;
    s = u - sin(2 * SEW_PI * u) / (2 * SEW_PI);           /* cycloidal law */
    *psi = p[PSI_M] * (sign > 0 ? s : 1.0 - s);
    *d1 = sign * p[PSI_M] * (1.0 - cos(2 * SEW_PI * u)) / width;
    if (py_square(width, &width2, why) != 0)
        return -1;
    return sew_divide(sign * p[PSI_M] * 2 * SEW_PI * sin(2 * SEW_PI * u), width2, d2, why);
}

/* PunchLinkage.motion at the shaft's (phi, omega, epsilon), as PunchLinkageSlave's row:
   xi, xi_dot, xi_ddot, psi */
static int outputs(const double *p, const double *derived, const double *state,
                   const double *u, double t, double *row, char *why)
{
    double phi = u[0], omega = u[1], epsilon = u[2], psi, d1, d2, omega2;
    (void)state;
    (void)t;
    if ((int)p[MODE] == SIX_BAR) {
        SewMotion d;
        if (slider(p, derived[ALPHA0] - phi, -omega, -epsilon, &d, why) != 0)
            return -1;
        psi = derived[Y_TOP] - d.y;
        row[0] = p[XI0] - psi;
        row[1] = d.vy;
        row[2] = d.ay;
        row[3] = psi;
        return 0;
    }
    if (required(p, phi, &psi, &d1, &d2, why) != 0 || py_square(omega, &omega2, why) != 0)
        return -1;
    /* xi = xi0 - psi(phi): chain rule with phi' = omega, phi'' = epsilon */
    row[0] = p[XI0] - psi;
    row[1] = -d1 * omega;
    row[2] = -(d2 * omega2 + d1 * epsilon);
    row[3] = psi;
    return 0;
}

const SewModel SEW_MODEL_PunchLinkage = {
    "PunchLinkage", N_DERIVED, 0, build, NULL, NULL, outputs, 0,
};
