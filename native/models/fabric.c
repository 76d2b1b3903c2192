/* twin-of: components/punch_split.py sha256:cd6354e4e99d1d38 */
/* twin-of: components/punch_fmu.py sha256:bf257e4c55e423a8 */
/* The welded material: components/punch_split.py's Fabric (SEW_MODEL_Fabric), as punch_fmu.py's
   FabricSlave calls it. F2 from the punch's height and speed (unilateral, non-retaining); within
   a step the punch's extrapolated parabola, its contact switches and the largest F2 on it.
   The same operations in the same order as the Python, and Python's max(a, b) (b if b > a
   else a), so that the numbers agree to the last bit. */
#include <math.h>

#include "parameters.h"
#include "sew_model.h"

/* sub-intervals of the step's switch search; the bisection's resolution */
#define FABRIC_INTERVALS 8
#define TIME_RESOLUTION 1e-15

enum { P_C2, P_B2, N_PARAMS };                    /* FabricParams' fields */
enum { S_F2_MAX, S_T_SWITCH, N_STATE };          /* FabricSlave's _F2_max, _t_switch */
enum { U_Y, U_Y_DOT, U_Y_DDOT };                 /* the punch's y, y', y'' */

static const SewParamInfo FABRIC_PARAMS[N_PARAMS] = {
    SEW_PARAM("c2", "N/m", SEW_POSITIVE), SEW_PARAM("b2", "N.s/m", SEW_NONNEGATIVE),
};

/* Python's max(a, b): a unless b is larger */
static double py_max(double a, double b)
{
    return b > a ? b : a;
}

static int in_contact(const double *p, double y, double v)
{
    return y < 0.0 && p[P_C2] * y + p[P_B2] * v < 0.0;
}

/* F2 >= 0: the fabric pushes the punch up while the punch presses into it */
static double fabric_force(const double *p, double y, double v)
{
    return in_contact(p, y, v) ? -(p[P_C2] * y + p[P_B2] * v) : 0.0;
}

/* dF2/dt for the punch's acceleration a (0 out of contact) */
static double force_rate(const double *p, double y, double v, double a)
{
    return in_contact(p, y, v) ? -(p[P_C2] * v + p[P_B2] * a) : 0.0;
}

/* the step's extrapolated motion y0 + v0·τ + a0·τ²/2 */
typedef struct {
    const double *p;
    double y0, v0, a0;
} Motion;

/* < 0 inside the contact set */
static double contact_g(const Motion *mo, double t)
{
    double y = mo->y0 + t * (mo->v0 + 0.5 * mo->a0 * t), v = mo->v0 + mo->a0 * t;
    return py_max(y, mo->p[P_C2] * y + mo->p[P_B2] * v);
}

/* _bisect with flipped(t) = (g(t) < 0) != contact: the first time in (lo, hi] it holds */
static double bisect(const Motion *mo, int contact, double lo, double hi)
{
    while (hi - lo > TIME_RESOLUTION * py_max(1.0, fabs(hi))) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi)
            break;
        if ((contact_g(mo, mid) < 0.0) != contact)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* _largest_force: the largest F2 on the contact pieces of the step, F2(τ) a parabola */
static double largest_force(const double *p, double y0, double v0, double a0, double h,
                            int n_switches, const double *times, const int *after)
{
    double c2 = p[P_C2], b2 = p[P_B2];
    double q0 = -(c2 * y0 + b2 * v0);
    double q1 = -(c2 * v0 + b2 * a0);
    double q2 = -0.5 * c2 * a0;
    double best = 0.0;
    int piece;
    for (piece = 0; piece <= n_switches; piece++) {
        double lo = piece == 0 ? 0.0 : times[piece - 1];
        double hi = piece == n_switches ? h : times[piece];
        int contact = piece == 0 ? in_contact(p, y0, v0) : after[piece - 1];
        double candidates[3];
        int n = 2, i;
        if (!contact)
            continue;
        candidates[0] = lo;
        candidates[1] = hi;
        if (q2 < 0.0) {
            double vertex = -q1 / (2.0 * q2);
            if (lo < vertex && vertex < hi)
                candidates[n++] = vertex;
        }
        for (i = 0; i < n; i++) {
            double t = candidates[i];
            best = py_max(best, q0 + t * (q1 + t * q2));
        }
    }
    return py_max(best, 0.0);
}

/* Fabric.step: F2_max, and the time of the last switch; returns the number of switches */
static int fabric_step(const double *p, double y0, double v0, double a0, double h,
                       double *f2_max, double *last_switch)
{
    Motion mo;
    double times[FABRIC_INTERVALS], t_prev = 0.0;
    int after[FABRIC_INTERVALS], n = 0, k, contact;
    mo.p = p;
    mo.y0 = y0;
    mo.v0 = v0;
    mo.a0 = a0;
    contact = contact_g(&mo, 0.0) < 0.0;
    for (k = 1; k <= FABRIC_INTERVALS; k++) {
        double t = h * k / FABRIC_INTERVALS;
        if ((contact_g(&mo, t) < 0.0) != contact) {
            times[n] = bisect(&mo, contact, t_prev, t);
            contact = !contact;
            after[n++] = contact;
        }
        t_prev = t;
    }
    *f2_max = largest_force(p, y0, v0, a0, h, n, times, after);
    *last_switch = n > 0 ? times[n - 1] : 0.0;
    return n;
}

static int fabric_build(const double *p, double *derived, char *why)
{
    (void)derived;
    return sew_validate(FABRIC_PARAMS, N_PARAMS, p, why);
}

static void fabric_initialize(const double *p, const double *derived, const double *u,
                              double *state)
{
    (void)p;
    (void)derived;
    (void)u;
    state[S_F2_MAX] = 0.0;
    state[S_T_SWITCH] = -1.0;
}

static int fabric_advance(const double *p, const double *derived, double *state, const double *u,
                          double t, double h, char *why)
{
    double f2_max, last;
    int switches;
    (void)derived;
    (void)why;
    switches = fabric_step(p, u[U_Y], u[U_Y_DOT], u[U_Y_DDOT], h, &f2_max, &last);
    state[S_F2_MAX] = f2_max;
    state[S_T_SWITCH] = switches ? t + last : -1.0;
    return 0;
}

/* the row: F2, F2_dot, contact, F2_max, t_switch */
static int fabric_outputs(const double *p, const double *derived, const double *state,
                          const double *u, double t, double *row, char *why)
{
    double f2 = fabric_force(p, u[U_Y], u[U_Y_DOT]);
    (void)derived;
    (void)t;
    (void)why;
    row[0] = f2;
    row[1] = force_rate(p, u[U_Y], u[U_Y_DOT], u[U_Y_DDOT]);
    row[2] = f2 > 0.0;
    row[3] = py_max(state[S_F2_MAX], f2);
    row[4] = state[S_T_SWITCH];
    return 0;
}

const SewModel SEW_MODEL_Fabric = {
    "Fabric", 0, N_STATE,
    fabric_build, fabric_initialize, fabric_advance, fabric_outputs, 0,
};
