/* twin-of: components/punch_contact.py sha256:a60a3e32840b55a4 */
/* twin-of: components/punch_split.py sha256:cd6354e4e99d1d38 */
/* twin-of: components/punch_fmu.py sha256:bf257e4c55e423a8 */
/* The punch body between springs and the fabric: components/punch_contact.py's PunchContact
   (SEW_MODEL_PunchContact) and punch_split.py's PunchBody, the same without the fabric and with
   its force an input (SEW_MODEL_PunchBody), as punch_fmu.py's slaves call them. Exact pieces
   (oscillator.c) between switches of contact and of spring 11, located by bisection; held on
   the stop of a preloaded compression-only spring 11. Every expression keeps the Python's
   operations and their order, and Python's max(a, b) (b if b > a else a), so that the numbers
   agree to the last bit where libm is the same. */
#ifndef __USE_MINGW_ANSI_STDIO
#define __USE_MINGW_ANSI_STDIO 1     /* C99 printf (%g's two-digit exponent) on Windows */
#endif
#include <math.h>
#include <stdio.h>

#include "oscillator.h"
#include "parameters.h"
#include "sew_model.h"

#define GRAVITY 9.81
#define PI 3.141592653589793         /* math.pi (M_PI is not C99) */
#define SAMPLES_PER_PERIOD 16
#define MAX_SWITCHES_PER_STEP 64
#define MAX_SEARCH_INTERVALS 4000
#define TIME_RESOLUTION 1e-15

/* PunchContactParams' fields; PunchBody's are the same without c2 and b2 */
enum { P_M, P_F10, P_C1, P_B1, P_C2, P_B2, P_C3, P_B3, P_F30, P_COMPRESSION_ONLY, N_PARAMS };
/* derived: PunchContactParams as the model runs with them (PunchBody: c2 = b2 = 0), then the
   constants of _set_up */
enum { D_PERIOD = N_PARAMS, D_HAS_STOP, N_DERIVED };
/* PunchState's fields, in its order */
enum { S_Y, S_Y_DOT, S_CONTACT, S_SPRING_ON, S_LANDINGS, S_F2_MAX, S_HELD, N_STATE };
/* the inputs: xi, xi_dot, xi_ddot, then PunchBody's F2, F2_dot */
enum { U_XI, U_XI_DOT, U_XI_DDOT, U_F2, U_F2_DOT };

static const SewParamInfo PUNCH_PARAMS[N_PARAMS] = {
    SEW_PARAM("m", "kg", SEW_POSITIVE), SEW_PARAM("F10", "N", SEW_NONNEGATIVE),
    SEW_PARAM("c1", "N/m", SEW_POSITIVE), SEW_PARAM("b1", "N.s/m", SEW_NONNEGATIVE),
    SEW_PARAM("c2", "N/m", SEW_POSITIVE), SEW_PARAM("b2", "N.s/m", SEW_NONNEGATIVE),
    SEW_PARAM("c3", "N/m", SEW_POSITIVE), SEW_PARAM("b3", "N.s/m", SEW_NONNEGATIVE),
    SEW_PARAM("F30", "N", SEW_NONNEGATIVE), {"compression_only", "1", SEW_CHOICE, 2, {0, 1, 0, 0}},
};

typedef struct {
    double m, F10, c1, b1, c2, b2, c3, b3, F30;
    int compression_only, has_stop;
    double shortest_period;
} Punch;

/* a piece of motion from the piece's start: held on the stop (the slider's parabola
   a0 + a1·u + a2·u², punch_contact.py's _Held) or an exact oscillator */
typedef struct {
    int held;
    double a0, a1, a2;
    SewOscillator o;
} Piece;

/* Python's max(a, b): a unless b is larger */
static double py_max(double a, double b)
{
    return b > a ? b : a;
}

static void punch_of(const double *d, Punch *P)
{
    P->m = d[P_M];
    P->F10 = d[P_F10];
    P->c1 = d[P_C1];
    P->b1 = d[P_B1];
    P->c2 = d[P_C2];
    P->b2 = d[P_B2];
    P->c3 = d[P_C3];
    P->b3 = d[P_B3];
    P->F30 = d[P_F30];
    P->compression_only = d[P_COMPRESSION_ONLY] != 0.0;
    P->shortest_period = d[D_PERIOD];
    P->has_stop = d[D_HAS_STOP] != 0.0;
}

/* PunchContact._set_up, into derived (the parameters already checked) */
static void set_up(double *d)
{
    double stiffest = d[P_C1] + d[P_C2] + d[P_C3];
    d[D_PERIOD] = 2.0 * PI * sqrt(d[P_M] / stiffest);
    d[D_HAS_STOP] = d[P_COMPRESSION_ONLY] != 0.0 && d[P_F30] > 0.0;
}

static void piece_state(const Piece *pc, double tau, double *y, double *v)
{
    if (pc->held) {
        *y = pc->a0 + tau * (pc->a1 + tau * pc->a2);
        *v = pc->a1 + 2.0 * tau * pc->a2;
    } else {
        sew_oscillator_state(&pc->o, tau, y, v);
    }
}

static double piece_accel(const Piece *pc, double tau, double y, double v)
{
    return pc->held ? 2.0 * pc->a2 : sew_oscillator_accel(&pc->o, tau, y, v);
}

/* --- forces ----------------------------------------------------------------------------- */

/* (F1, F2): the closing spring's force and the fabric's (>= 0, only in contact) */
static void spring6_and_fabric(const Punch *P, double y, double v, int contact, double *f1,
                               double *f2)
{
    *f2 = contact ? py_max(0.0, -(P->c2 * y + P->b2 * v)) : 0.0;
    *f1 = P->F10 + P->c1 * y + P->b1 * v;
}

/* force of spring 11's stop that makes the punch move with the slider (y'' = xi'') */
static double stop_force(const Punch *P, double y, double v, double xi_ddot, int contact,
                         double ext)
{
    double f1, f2;
    spring6_and_fabric(P, y, v, contact, &f1, &f2);
    return P->m * (xi_ddot + GRAVITY) + f1 - f2 - ext;
}

static int compresses_on_release(const Punch *P, double y, double v, double xi_ddot, int contact,
                                 double ext)
{
    return stop_force(P, y, v, xi_ddot, contact, ext) > P->F30;
}

/* --- switching functions: negative while the current flag is consistent ------------------ */

static double contact_g(const Punch *P, double y, double v)
{
    return py_max(y, P->c2 * y + P->b2 * v);
}

static double spring_g(const Punch *P, double y, double v, double xi, double xi_dot)
{
    double delta = xi - y;
    return py_max(-delta, -(P->F30 + P->c3 * delta + P->b3 * (xi_dot - v)));
}

static double release_g(const Punch *P, double y, double v, double xi_ddot, int contact,
                        double ext)
{
    double f = stop_force(P, y, v, xi_ddot, contact, ext);
    return py_max(f - P->F30, -f);
}

/* _sticks: the punch, at the stop of spring 11, comes to rest on it */
static int sticks(const Punch *P, double y, double v, double xi, double xi_dot, double xi_ddot,
                  int contact, int spring_on, double ext)
{
    double f3_star, f, f1, f2, a, excursion_speed;
    if (!P->has_stop)
        return 0;
    f3_star = P->F30 + P->c3 * (xi - y) + P->b3 * (xi_dot - v);
    if (f3_star < 0.5 * P->F30)
        return 0;
    f = stop_force(P, xi, xi_dot, xi_ddot, contact, ext);
    if (!(0.0 <= f && f <= P->F30))
        return 0;
    spring6_and_fabric(P, y, v, contact, &f1, &f2);
    a = (-f1 + f2 + (spring_on ? f3_star : 0.0) + ext) / P->m - GRAVITY;
    excursion_speed = fabs(xi_dot - v);
    return 2.0 * excursion_speed
           <= fabs(xi_ddot - a) * P->shortest_period / SAMPLES_PER_PERIOD;
}

/* initial_state: at rest on the excitation, the switches consistent with that */
static void initial_state(const Punch *P, double xi, double xi_dot, double xi_ddot, double ext,
                          double *s)
{
    int contact = contact_g(P, xi, 0.0) < 0.0;
    int spring_on = P->compression_only ? spring_g(P, xi, 0.0, xi, xi_dot) < 0.0 : 1;
    int held = sticks(P, xi, 0.0, xi, xi_dot, xi_ddot, contact, spring_on, ext);
    s[S_Y] = xi;
    s[S_Y_DOT] = held ? xi_dot : 0.0;
    s[S_CONTACT] = contact;
    s[S_SPRING_ON] = spring_on || held;
    s[S_LANDINGS] = 0.0;
    s[S_F2_MAX] = 0.0;
    s[S_HELD] = held;
}

/* PunchOutputs: y, y_dot, y_ddot, F1, F2, F3, Delta, contact, F2_max */
static void punch_outputs(const Punch *P, const double *s, double xi, double xi_dot,
                          double xi_ddot, double ext, double *o)
{
    double f1, f2, f3, delta = xi - s[S_Y];
    int contact = s[S_CONTACT] != 0.0;
    spring6_and_fabric(P, s[S_Y], s[S_Y_DOT], contact, &f1, &f2);
    o[0] = s[S_Y];
    o[1] = s[S_Y_DOT];
    o[3] = f1;
    o[4] = f2;
    o[6] = delta;
    o[7] = contact;
    o[8] = py_max(s[S_F2_MAX], f2);
    if (s[S_HELD] != 0.0) {        /* the stop carries whatever keeps the punch on the slider */
        o[2] = xi_ddot;
        o[5] = stop_force(P, s[S_Y], s[S_Y_DOT], xi_ddot, contact, ext);
        return;
    }
    f3 = P->F30 + P->c3 * delta + P->b3 * (xi_dot - s[S_Y_DOT]);
    if (s[S_SPRING_ON] == 0.0)
        f3 = 0.0;
    else if (P->compression_only)
        f3 = py_max(0.0, f3);
    o[2] = (-f1 + f2 + f3 + ext) / P->m - GRAVITY;
    o[5] = f3;
}

/* --- one communication step --------------------------------------------------------------- */

/* _piece: the exact solution from time t0 of the step, in the current mode */
static void make_piece(const Punch *P, double y, double v, int contact, int spring_on, int held,
                       double x0, double x1, double x2, double t0, double e0, double e1,
                       Piece *pc)
{
    double b = P->b1, c = P->c1, f0, f1, f2;
    /* excitation re-centred at t0: xi(t0 + u) = a0 + a1·u + a2·u² */
    double a0 = x0 + t0 * (x1 + t0 * x2);
    double a1 = x1 + 2.0 * t0 * x2;
    double a2 = x2;
    pc->held = held;
    pc->a0 = a0;
    pc->a1 = a1;
    pc->a2 = a2;
    if (held)
        return;
    f0 = -P->F10 - P->m * GRAVITY + e0 + e1 * t0;
    f1 = e1;
    f2 = 0.0;
    if (contact) {
        b += P->b2;
        c += P->c2;
    }
    if (spring_on) {
        b += P->b3;
        c += P->c3;
        f0 += P->F30 + P->c3 * a0 + P->b3 * a1;
        f1 += P->c3 * a1 + 2.0 * P->b3 * a2;
        f2 += P->c3 * a2;
    }
    sew_oscillator_init(&pc->o, P->m, b, c, f0, f1, f2, y, v);
}

/* the flags of the current mode and the step's excitation, as _first_switch's funcs see them */
typedef struct {
    const Punch *P;
    const Piece *pc;
    int contact, spring_on, held;
    double x0, x1, x2, t0, e0, e1;
} Mode;

enum { SWITCH_CONTACT, SWITCH_SPRING };

/* _switch_functions' value of one flag at the step's time t: > 0 means 'flip this flag' */
static double switch_value(const Mode *md, int which, double t)
{
    const Punch *P = md->P;
    double y, v, g;
    piece_state(md->pc, t - md->t0, &y, &v);
    if (which == SWITCH_CONTACT) {
        g = contact_g(P, y, v);
        return md->contact ? g : -g;
    }
    if (md->held)
        return release_g(P, y, v, 2.0 * md->x2, md->contact, md->e0 + md->e1 * t);
    {
        double xi = md->x0 + t * (md->x1 + t * md->x2);
        double xi_dot = md->x1 + 2.0 * t * md->x2;
        g = spring_g(P, y, v, xi, xi_dot);
        return md->spring_on ? g : -g;
    }
}

/* _bisect: the smallest bracket end where the flag's function is > 0 */
static double bisect(const Mode *md, int which, double lo, double hi)
{
    while (hi - lo > TIME_RESOLUTION * py_max(1.0, fabs(hi))) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi)
            break;
        if (switch_value(md, which, mid) > 0.0)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* _first_switch: 1 with (time in the step, which flag) of the first switch in (t0, h], or 0 */
static int first_switch(const Mode *md, double h, double *t_switch, int *which)
{
    const Punch *P = md->P;
    int n_flags = md->held || P->compression_only ? 2 : 1;
    double n_sub = ceil((h - md->t0) / (P->shortest_period / SAMPLES_PER_PERIOD));
    double t_prev = md->t0, k;
    if (!(n_sub > 1))
        n_sub = 1;
    for (k = 1; k <= n_sub; k++) {
        double t = md->t0 + (h - md->t0) * k / n_sub;
        int w, found = 0;
        for (w = 0; w < n_flags; w++) {
            if (switch_value(md, w, t) > 0.0) {
                double t_hit = bisect(md, w, t_prev, t);
                if (!found || t_hit < *t_switch) {
                    *t_switch = t_hit;
                    *which = w;
                    found = 1;
                }
            }
        }
        if (found)
            return 1;
        t_prev = t;
    }
    return 0;
}

static double fabric_force_on(const Punch *P, const Piece *pc, double tau)
{
    double y, v;
    piece_state(pc, tau, &y, &v);
    return -(P->c2 * y + P->b2 * v);
}

static double fabric_slope_on(const Punch *P, const Piece *pc, double tau)
{
    double y, v;
    piece_state(pc, tau, &y, &v);
    return -(P->c2 * v + P->b2 * piece_accel(pc, tau, y, v));
}

/* _largest_F2: the largest fabric force -(c2·y + b2·y') on a contact piece of this length */
static double largest_F2(const Punch *P, const Piece *pc, double length)
{
    double best = py_max(fabric_force_on(P, pc, 0.0), fabric_force_on(P, pc, length));
    double lo = 0.0, hi = length;
    if (fabric_slope_on(P, pc, lo) > 0.0 && 0.0 > fabric_slope_on(P, pc, hi)) {
        while (hi - lo > TIME_RESOLUTION * 1e3) {
            double mid = 0.5 * (lo + hi);
            if (fabric_slope_on(P, pc, mid) > 0.0)
                lo = mid;
            else
                hi = mid;
        }
        best = py_max(best, fabric_force_on(P, pc, 0.5 * (lo + hi)));
    }
    return py_max(best, 0.0);
}

/* PunchContact.step: advance s by h under xi(τ) = x0 + x1·τ + x2·τ² and the external force
   e0 + e1·τ. 0, or -1 with StepTooLong's or ZenoError's text in why (s then unchanged). */
static int punch_step(const Punch *P, double *s, double x0, double x1, double x2, double h,
                      double e0, double e1, char *why)
{
    double y = s[S_Y], v = s[S_Y_DOT], landings = s[S_LANDINGS];
    int contact = s[S_CONTACT] != 0.0, spring_on = s[S_SPRING_ON] != 0.0;
    int held = s[S_HELD] != 0.0;
    double t0 = 0.0, f2_max = 0.0, search, intervals, budget, i;
    if (held) {
        /* the punch rides on the slider: it starts where the new inputs put it, and leaves the
           stop at once if the stop cannot hold it under them */
        y = x0;
        v = x1;
        if (release_g(P, y, v, 2.0 * x2, contact, e0) > 0.0) {
            held = 0;
            spring_on = compresses_on_release(P, y, v, 2.0 * x2, contact, e0);
        }
    } else if (P->compression_only) {
        spring_on = spring_g(P, y, v, x0, x1) < 0.0;
    }
    search = P->shortest_period / SAMPLES_PER_PERIOD;
    intervals = ceil(h / search);
    if (isnan(intervals) || isinf(intervals)) {      /* math.ceil's own refusal */
        snprintf(why, SEW_WHY, isnan(intervals) ? "ValueError: cannot convert float NaN to "
                 "integer" : "OverflowError: cannot convert float infinity to integer");
        return -1;
    }
    if (intervals > MAX_SEARCH_INTERVALS) {
        snprintf(why, SEW_WHY, "a step of %g s needs %.3g switch-search intervals of %.3g s "
                 "(1/%d of the punch's shortest natural period); at most %d per step: take "
                 "steps of at most %.3g s", h, intervals, search, SAMPLES_PER_PERIOD,
                 MAX_SEARCH_INTERVALS, MAX_SEARCH_INTERVALS * search);
        return -1;
    }
    /* a guard against an endless loop, scaled with the search sub-intervals */
    budget = MAX_SWITCHES_PER_STEP + 4 * intervals;
    for (i = 0; i < budget; i++) {
        Piece pc;
        Mode md;
        double t_switch = 0.0, xi_ddot;
        int which = SWITCH_CONTACT, event;
        make_piece(P, y, v, contact, spring_on, held, x0, x1, x2, t0, e0, e1, &pc);
        md.P = P;
        md.pc = &pc;
        md.contact = contact;
        md.spring_on = spring_on;
        md.held = held;
        md.x0 = x0;
        md.x1 = x1;
        md.x2 = x2;
        md.t0 = t0;
        md.e0 = e0;
        md.e1 = e1;
        event = first_switch(&md, h, &t_switch, &which);
        if (contact)
            f2_max = py_max(f2_max, largest_F2(P, &pc, (event ? t_switch : h) - t0));
        if (!event) {
            piece_state(&pc, h - t0, &y, &v);
            s[S_Y] = y;
            s[S_Y_DOT] = v;
            s[S_CONTACT] = contact;
            s[S_SPRING_ON] = spring_on;
            s[S_LANDINGS] = landings;
            s[S_F2_MAX] = f2_max;
            s[S_HELD] = held;
            return 0;
        }
        piece_state(&pc, t_switch - t0, &y, &v);
        t0 = t_switch;
        xi_ddot = 2.0 * x2;
        if (which == SWITCH_CONTACT) {
            contact = !contact;
            landings += contact;
        } else if (held) {
            held = 0;
            spring_on = compresses_on_release(P, y, v, xi_ddot, contact, e0 + e1 * t0);
        } else {
            double xi = x0 + t0 * (x1 + t0 * x2), xi_dot = x1 + 2.0 * t0 * x2;
            spring_on = !spring_on;
            if (sticks(P, y, v, xi, xi_dot, xi_ddot, contact, spring_on, e0 + e1 * t0)) {
                held = 1;
                spring_on = 1;
                y = xi;
                v = xi_dot;
            }
        }
    }
    snprintf(why, SEW_WHY, "more than %.0f contact switches within one step of %g s "
             "(y = %.6g m): the contact chatters; check c2, b2, c3, b3", budget, h, y);
    return -1;
}

/* === SEW_MODEL_PunchContact =============================================================== */

static int contact_build(const double *p, double *derived, char *why)
{
    int i;
    if (sew_validate(PUNCH_PARAMS, N_PARAMS, p, why) != 0)
        return -1;
    for (i = 0; i < N_PARAMS; i++)
        derived[i] = p[i];
    derived[P_COMPRESSION_ONLY] = trunc(p[P_COMPRESSION_ONLY]);    /* SewSlave.model's int() */
    set_up(derived);
    return 0;
}

static void contact_initialize(const double *p, const double *derived, const double *u,
                               double *state)
{
    Punch P;
    (void)p;
    punch_of(derived, &P);
    initial_state(&P, u[U_XI], u[U_XI_DOT], u[U_XI_DDOT], 0.0, state);
}

static int contact_advance(const double *p, const double *derived, double *state,
                           const double *u, double t, double h, char *why)
{
    Punch P;
    (void)p;
    (void)t;
    punch_of(derived, &P);
    return punch_step(&P, state, u[U_XI], u[U_XI_DOT], 0.5 * u[U_XI_DDOT], h, 0.0, 0.0, why);
}

static int contact_outputs(const double *p, const double *derived, const double *state,
                           const double *u, double t, double *row, char *why)
{
    Punch P;
    (void)p;
    (void)t;
    (void)why;
    punch_of(derived, &P);
    punch_outputs(&P, state, u[U_XI], u[U_XI_DOT], u[U_XI_DDOT], 0.0, row);
    return 0;
}

const SewModel SEW_MODEL_PunchContact = {
    "PunchContact", N_DERIVED, N_STATE,
    contact_build, contact_initialize, contact_advance, contact_outputs, 0,
};

/* === SEW_MODEL_PunchBody: the fabric's force F2 (+ F2_dot·τ) is the external force ========== */

/* PunchBodyParams: PunchContactParams without c2 and b2 */
static const int BODY_FIELDS[] = {P_M, P_F10, P_C1, P_B1, P_C3, P_B3, P_F30, P_COMPRESSION_ONLY};
#define N_BODY_PARAMS ((int)(sizeof BODY_FIELDS / sizeof BODY_FIELDS[0]))

static int body_build(const double *p, double *derived, char *why)
{
    SewParamInfo infos[N_BODY_PARAMS];
    int i;
    for (i = 0; i < N_BODY_PARAMS; i++)
        infos[i] = PUNCH_PARAMS[BODY_FIELDS[i]];
    if (sew_validate(infos, N_BODY_PARAMS, p, why) != 0)
        return -1;
    /* no fabric inside: with c2 = b2 = 0 the contact set is empty */
    derived[P_C2] = derived[P_B2] = 0.0;
    for (i = 0; i < N_BODY_PARAMS; i++)
        derived[BODY_FIELDS[i]] = p[i];
    derived[P_COMPRESSION_ONLY] = trunc(derived[P_COMPRESSION_ONLY]);
    set_up(derived);
    return 0;
}

static void body_initialize(const double *p, const double *derived, const double *u,
                            double *state)
{
    Punch P;
    (void)p;
    punch_of(derived, &P);
    initial_state(&P, u[U_XI], u[U_XI_DOT], u[U_XI_DDOT], u[U_F2], state);
}

static int body_advance(const double *p, const double *derived, double *state, const double *u,
                        double t, double h, char *why)
{
    Punch P;
    (void)p;
    (void)t;
    punch_of(derived, &P);
    return punch_step(&P, state, u[U_XI], u[U_XI_DOT], 0.5 * u[U_XI_DDOT], h, u[U_F2],
                      u[U_F2_DOT], why);
}

/* the row: y, y_dot, y_ddot, F1, F3, Delta (PunchContact's without F2, contact, F2_max) */
static int body_outputs(const double *p, const double *derived, const double *state,
                        const double *u, double t, double *row, char *why)
{
    Punch P;
    double o[9];
    (void)p;
    (void)t;
    (void)why;
    punch_of(derived, &P);
    punch_outputs(&P, state, u[U_XI], u[U_XI_DOT], u[U_XI_DDOT], u[U_F2], o);
    row[0] = o[0];
    row[1] = o[1];
    row[2] = o[2];
    row[3] = o[3];
    row[4] = o[5];
    row[5] = o[6];
    return 0;
}

const SewModel SEW_MODEL_PunchBody = {
    "PunchBody", N_DERIVED, N_STATE,
    body_build, body_initialize, body_advance, body_outputs, 0,
};
