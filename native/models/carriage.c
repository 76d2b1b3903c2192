/* The coordinate device's carriage: the start-stop table drive (CarriageDrive) and the carriage
   on its guide cantilever, a 2-DOF Ritz model stepped mode by mode (CarriageModal).
   The C twins of components/carriage.py's models as components/carriage_fmu.py's slaves call
   them, their parameters checked by parameters.c (components/parameters.py's twin).
   Every expression keeps the Python's operations and their order (x ** n is pow, as CPython's
   float power), so that the numbers agree to the last bit where libm is the same. */
/* twin-of: components/carriage.py sha256:314624d9c448430f */
/* twin-of: components/carriage_fmu.py sha256:aa68cca395bba5b0 */
#include <math.h>
#include <stdio.h>

#include "oscillator.h"
#include "parameters.h"
#include "sew_model.h"

#define PI 3.141592653589793            /* math.pi (M_PI is not C99) */
#define TWO_PI (2 * PI)                 /* 2 * math.pi: a doubling, exact */

/* --- Python's float arithmetic where it differs from C's -------------------------------- */

/* Where Python raises, the twin refuses with the line the Python FMU logs (pythonfmu_quirks'
   describe: "ZeroDivisionError: float division by zero") */
static int zero_division(double divisor, char *why)
{
    if (divisor != 0.0) return 0;
    snprintf(why, SEW_WHY, "ZeroDivisionError: float division by zero");
    return -1;
}

/* CPython's float ** n: libm's pow (through a volatile exponent, because GCC turns pow(x, 2)
   into x * x, and glibc's pow is not correctly rounded: 1554.7281482805886 ** 2 differs in the
   last bit); a finite x whose power overflows raises OverflowError */
static int py_pow(double x, double n, double *power, char *why)
{
    volatile double exponent = n;
    *power = pow(x, exponent);
    if (isinf(*power) && isfinite(x)) {
        snprintf(why, SEW_WHY, "OverflowError: (34, 'Numerical result out of range')");
        return -1;
    }
    return 0;
}

/* math.sqrt: a negative argument raises ValueError */
static int py_sqrt(double x, double *root, char *why)
{
    if (x < 0) {
        snprintf(why, SEW_WHY, "ValueError: math domain error");
        return -1;
    }
    *root = sqrt(x);
    return 0;
}

/* === CarriageDrive ============================================================================ */

enum { D_STITCH, D_WINDOW, D_PHI_START };              /* CarriageDriveParams' fields */

static const SewParamInfo DRIVE_PARAMS[] = {
    SEW_PARAM("stitch_length", "m", SEW_POSITIVE), SEW_PARAM("window", "1", SEW_FRACTION),
    SEW_PARAM("phi_start", "rad", SEW_NONNEGATIVE),
};

/* CarriageDrive._law: position and its first three derivatives with respect to phi; -1 where
   Python raises (math.floor of a phi that is not finite, or a window so short that its powers
   underflow to 0) */
static int drive_law(const double *p, double phi, double law[4], char *why)
{
    double span = TWO_PI * p[D_WINDOW];
    double rel = phi - p[D_PHI_START];
    double turns = rel / TWO_PI;
    double stitch, u, s, c, span2, span3, two_pi2;
    if (!isfinite(turns)) {              /* what math.floor says of it */
        snprintf(why, SEW_WHY, isnan(turns) ? "ValueError: cannot convert float NaN to integer"
                 : "OverflowError: cannot convert float infinity to integer");
        return -1;
    }
    stitch = floor(turns);
    if (zero_division(span, why) != 0) return -1;
    u = (rel - TWO_PI * stitch) / span;
    s = p[D_STITCH];
    if (u >= 1.0) {                      /* at rest after this stitch's transport window */
        law[0] = s * (stitch + 1.0);
        law[1] = law[2] = law[3] = 0.0;
        return 0;
    }
    c = TWO_PI * u;
    if (isinf(c)) {                      /* math.sin of it */
        snprintf(why, SEW_WHY, "ValueError: math domain error");
        return -1;
    }
    law[0] = s * (stitch + u - sin(c) / TWO_PI);
    law[1] = s * (1 - cos(c)) / span;
    if (py_pow(span, 2, &span2, why) != 0 || zero_division(span2, why) != 0) return -1;
    law[2] = s * 2 * PI * sin(c) / span2;
    if (py_pow(TWO_PI, 2, &two_pi2, why) != 0 || py_pow(span, 3, &span3, why) != 0
            || zero_division(span3, why) != 0) return -1;
    law[3] = s * two_pi2 * cos(c) / span3;
    return 0;
}

static int drive_build(const double *p, double *derived, char *why)
{
    double law[4];
    if (sew_validate(DRIVE_PARAMS, 3, p, why) != 0) return -1;
    if (drive_law(p, 0.0, law, why) != 0) return -1;
    derived[0] = law[0];                 /* x0: x = 0 at phi = 0 */
    return 0;
}

/* CarriageDrive.motion at u = (phi, omega, epsilon): x, v, a, jerk */
static int drive_outputs(const double *p, const double *derived, const double *state,
                         const double *u, double t, double *row, char *why)
{
    double law[4], omega = u[1], epsilon = u[2], omega2, omega3;
    (void)state; (void)t;
    if (drive_law(p, u[0], law, why) != 0) return -1;
    row[0] = law[0] - derived[0];
    row[1] = law[1] * omega;
    if (py_pow(omega, 2, &omega2, why) != 0) return -1;
    row[2] = law[2] * omega2 + law[1] * epsilon;
    if (py_pow(omega, 3, &omega3, why) != 0) return -1;
    row[3] = law[3] * omega3 + 3 * law[2] * omega * epsilon;
    return 0;
}

const SewModel SEW_MODEL_CarriageDrive = {
    "CarriageDrive", 1, 0, drive_build, NULL, NULL, drive_outputs, 0,
};

/* === CarriageModal ============================================================================ */

enum { C_L, C_A, C_EJ, C_M_N, C_M_K, C_J_C, C_ZETA };  /* CarriageParams' fields */

static const SewParamInfo CARRIAGE_PARAMS[] = {
    SEW_PARAM("l", "m", SEW_POSITIVE), SEW_PARAM("a", "m", SEW_POSITIVE),
    SEW_PARAM("EJ", "N.m2", SEW_POSITIVE), SEW_PARAM("m_n", "kg", SEW_POSITIVE),
    SEW_PARAM("m_k", "kg", SEW_POSITIVE), SEW_PARAM("J_c", "kg.m2", SEW_POSITIVE),
    SEW_PARAM("zeta", "1", SEW_NONNEGATIVE),
};

/* derived: 2x2 matrices as rows (m[2*i + j]), vectors as pairs */
enum {
    FLEX = 0,          /* F: the cantilever's flexibility at a and l */
    STIFF = 4,         /* K = F^-1 */
    MASS = 8,          /* M */
    LOAD = 12,         /* p: the load of a unit base acceleration */
    MODES = 14,        /* Phi: columns the mass-normalized modes */
    OMEGA = 18,        /* the natural frequencies */
    MODAL_LOAD = 20,   /* gamma_i = phi_i^T p */
    N_DERIVED = 22
};

/* state: q1, q2, dq1, dq2 (the modal coordinates and their rates) */
enum { Q = 0, DQ = 2, N_STATE = 4 };

static void times(const double *A, const double *x, double *y)
{
    double y0 = A[0] * x[0] + A[1] * x[1];
    double y1 = A[2] * x[0] + A[3] * x[1];
    y[0] = y0;
    y[1] = y1;
}

/* deflection at z of the cantilever under a unit force at s (the curvature is not needed) */
static double unit_deflection(double z, double s, double EJ)
{
    if (z <= s) return z * z * (3 * s - z) / (6 * EJ);
    return s * s * (3 * z - s) / (6 * EJ);
}

/* M and the load vector p: the Ritz shapes integrated by 4-point Gauss on [0, a] and [a, l] */
static int mass_and_load(const double *p, double *d, char *why)
{
    const double *K = d + STIFF;
    double gauss_x[4], gauss_w[4], beam[4] = {0.0, 0.0, 0.0, 0.0}, integral[2] = {0.0, 0.0};
    double rho, gap2, tilt;
    int k, sign, g, part, i, j;
    for (g = 0, k = -1; k <= 1; k += 2)            /* _GAUSS_4, in its order */
        for (sign = -1; sign <= 1; sign += 2, g++) {
            gauss_x[g] = sign * sqrt(3.0 / 7 + k * 2 / 7.0 * sqrt(6.0 / 5));
            gauss_w[g] = (18 - k * sqrt(30)) / 36;
        }
    for (part = 0; part < 2; part++) {
        double lo = part == 0 ? 0.0 : p[C_A], hi = part == 0 ? p[C_A] : p[C_L];
        double half = 0.5 * (hi - lo), mid = 0.5 * (hi + lo);
        for (g = 0; g < 4; g++) {
            double z = mid + half * gauss_x[g], w = half * gauss_w[g], n[2];
            double wa = unit_deflection(z, p[C_A], p[C_EJ]);
            double wl = unit_deflection(z, p[C_L], p[C_EJ]);
            n[0] = K[0] * wa + K[2] * wl;           /* N = K^T (w_a, w_l) */
            n[1] = K[1] * wa + K[3] * wl;
            for (i = 0; i < 2; i++) {
                integral[i] += w * n[i];
                for (j = 0; j < 2; j++) beam[2 * i + j] += w * n[i] * n[j];
            }
        }
    }
    rho = p[C_M_N] / p[C_L];
    if (py_pow(p[C_L] - p[C_A], 2, &gap2, why) != 0 || zero_division(gap2, why) != 0) return -1;
    tilt = p[C_J_C] / gap2;                          /* the carriage's tilt */
    d[MASS + 0] = rho * beam[0] + tilt;
    d[MASS + 1] = rho * beam[1] - tilt;
    d[MASS + 2] = rho * beam[2] - tilt;
    d[MASS + 3] = rho * beam[3] + tilt + p[C_M_K];
    d[LOAD + 0] = rho * integral[0];
    d[LOAD + 1] = rho * integral[1] + p[C_M_K];
    return 0;
}

/* _generalized_eigen: K phi = lambda M phi in closed form, lambda ascending, phi
   mass-normalized with its largest component positive; then omega = sqrt(lambda) */
static int generalized_eigen(double *d, char *why)
{
    const double *K = d + STIFF, *M = d + MASS;
    double m01_2, k01_2, a, b, c, disc, root, big, lams[2];
    int i;
    if (py_pow(M[1], 2, &m01_2, why) != 0) return -1;
    a = M[0] * M[3] - m01_2;
    b = -(K[0] * M[3] + K[3] * M[0] - 2.0 * K[1] * M[1]);
    if (py_pow(K[1], 2, &k01_2, why) != 0) return -1;
    c = K[0] * K[3] - k01_2;
    disc = b * b - 4.0 * a * c;
    if (0.0 > disc) disc = 0.0;                     /* max(disc, 0.0), NaN kept as Python's */
    root = sqrt(disc);
    if (zero_division(2.0 * a, why) != 0) return -1;
    big = (-b + root) / (2.0 * a);                  /* the larger root without cancellation */
    if (zero_division(a * big, why) != 0) return -1;
    lams[0] = c / (a * big);
    lams[1] = big;
    for (i = 0; i < 2; i++) {
        double lam = lams[i];
        double r0[2], r1[2], v[2], norm, sign, largest;
        const double *row;
        r0[0] = K[0] - lam * M[0];
        r0[1] = K[1] - lam * M[1];
        r1[0] = K[2] - lam * M[2];
        r1[1] = K[3] - lam * M[3];
        row = hypot(r0[0], r0[1]) >= hypot(r1[0], r1[1]) ? r0 : r1;
        v[0] = -row[1];                             /* orthogonal to the better row */
        v[1] = row[0];
        if (py_sqrt(v[0] * (M[0] * v[0] + M[1] * v[1]) + v[1] * (M[2] * v[0] + M[3] * v[1]),
                    &norm, why) != 0) return -1;
        largest = fabs(v[1]) > fabs(v[0]) ? v[1] : v[0];   /* max(v, key=abs): first of ties */
        sign = largest > 0 ? 1.0 : -1.0;
        if (zero_division(norm, why) != 0) return -1;
        d[MODES + i] = sign * v[0] / norm;          /* column i */
        d[MODES + 2 + i] = sign * v[1] / norm;
    }
    for (i = 0; i < 2; i++)
        if (py_sqrt(lams[i], &d[OMEGA + i], why) != 0) return -1;
    return 0;
}

static int carriage_build(const double *p, double *d, char *why)
{
    double det;
    char l_text[40], a_text[40];
    int i;
    if (sew_validate(CARRIAGE_PARAMS, 7, p, why) != 0) return -1;
    if (!(p[C_A] < p[C_L])) {
        sew_py_repr(p[C_L], l_text, sizeof l_text);
        sew_py_repr(p[C_A], a_text, sizeof a_text);
        snprintf(why, SEW_WHY, "parameter a: must lie on the cantilever, 0 < a < l = %s m, "
                 "got %s", l_text, a_text);
        return -1;
    }
    {   /* flexibility */
        double a = p[C_A], l = p[C_L], EJ = p[C_EJ], a3, l3;
        double f_al = a * a * (3 * l - a) / (6 * EJ);
        if (py_pow(a, 3, &a3, why) != 0 || py_pow(l, 3, &l3, why) != 0) return -1;
        d[FLEX + 0] = a3 / (3 * EJ);
        d[FLEX + 1] = f_al;
        d[FLEX + 2] = f_al;
        d[FLEX + 3] = l3 / (3 * EJ);
    }
    det = d[FLEX + 0] * d[FLEX + 3] - d[FLEX + 1] * d[FLEX + 2];   /* _inverse */
    if (zero_division(det, why) != 0) return -1;
    d[STIFF + 0] = d[FLEX + 3] / det;
    d[STIFF + 1] = -d[FLEX + 1] / det;
    d[STIFF + 2] = -d[FLEX + 2] / det;
    d[STIFF + 3] = d[FLEX + 0] / det;
    if (mass_and_load(p, d, why) != 0 || generalized_eigen(d, why) != 0) return -1;
    for (i = 0; i < 2; i++)
        d[MODAL_LOAD + i] = d[MODES + i] * d[LOAD + 0] + d[MODES + 2 + i] * d[LOAD + 1];
    return 0;
}

/* U under a constant base acceleration: U = -F p a */
static void static_deflection(const double *d, double a_base, double *U)
{
    double u[2];
    times(d + FLEX, d + LOAD, u);
    U[0] = -u[0] * a_base;
    U[1] = -u[1] * a_base;
}

/* CarriageModalSlave.initialize: at rest in the static deflection under the held a_base,
   in modal coordinates q = Phi^T M U */
static void carriage_initialize(const double *p, const double *d, const double *u,
                                double *state)
{
    double U[2], mu[2];
    int i;
    (void)p;
    static_deflection(d, u[0], U);
    times(d + MASS, U, mu);
    for (i = 0; i < 2; i++) state[Q + i] = d[MODES + i] * mu[0] + d[MODES + 2 + i] * mu[1];
    state[DQ + 0] = 0.0;
    state[DQ + 1] = 0.0;
}

/* CarriageModal.step under a(tau) = a_base + a_base_dot tau: each mode exactly */
static int carriage_advance(const double *p, const double *d, double *state, const double *u,
                            double t, double h, char *why)
{
    double y[2], v[2];
    int i;
    (void)t; (void)why;
    for (i = 0; i < 2; i++) {
        SewOscillator mode;
        double w = d[OMEGA + i], g = -d[MODAL_LOAD + i];
        sew_oscillator_init(&mode, 1.0, 2.0 * p[C_ZETA] * w, w * w, g * u[0], g * u[1], 0.0,
                            state[Q + i], state[DQ + i]);
        sew_oscillator_state(&mode, h, &y[i], &v[i]);
    }
    state[Q + 0] = y[0];
    state[Q + 1] = y[1];
    state[DQ + 0] = v[0];
    state[DQ + 1] = v[1];
    return 0;
}

/* U1, U2, U1_dot, U2_dot from the modal state (physical), then omega1, omega2 */
static int carriage_outputs(const double *p, const double *d, const double *state,
                            const double *u, double t, double *row, char *why)
{
    (void)p; (void)u; (void)t; (void)why;
    times(d + MODES, state + Q, row);
    times(d + MODES, state + DQ, row + 2);
    row[4] = d[OMEGA + 0];
    row[5] = d[OMEGA + 1];
    return 0;
}

const SewModel SEW_MODEL_CarriageModal = {
    "CarriageModal", N_DERIVED, N_STATE, carriage_build, carriage_initialize, carriage_advance,
    carriage_outputs, 0,
};
