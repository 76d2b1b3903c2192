/* twin-of: components/oscillator.py sha256:5a69ad02f361d266 */
/* The exact solution of a damped linear oscillator under polynomial forcing (oscillator.h).

   Python computes the roots and the homogeneous solution with cmath and complex numbers; here
   the complex arithmetic is written out in real arithmetic as CPython 3.11 does it, so that the
   numbers agree to the last bit on one platform:
     - a float mixed with a complex is first made the complex (x, 0.0), then the complex
       operation runs (CPython before 3.14 has no mixed-mode rules): kept, since it decides
       the signs of zeros;
     - products as _Py_c_prod, quotients as _Py_c_quot (Smith's algorithm), sums and
       differences part by part;
     - cmath.sqrt as Modules/cmathmodule.c's cmath_sqrt_impl, cmath.exp as cmath_exp_impl
       (finite arguments: the only ones a finite oscillator gives). */
#include "oscillator.h"

#include <float.h>
#include <math.h>

typedef struct {
    double re, im;
} Complex;

static Complex complex_of(double x)
{
    Complex r = {x, 0.0};
    return r;
}

static Complex c_sum(Complex a, Complex b)
{
    Complex r = {a.re + b.re, a.im + b.im};
    return r;
}

static Complex c_diff(Complex a, Complex b)
{
    Complex r = {a.re - b.re, a.im - b.im};
    return r;
}

static Complex c_prod(Complex a, Complex b)
{
    Complex r = {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
    return r;
}

/* _Py_c_quot; division by zero (Python's ZeroDivisionError) cannot happen here: 2·m > 0 and
   l2 - l1 = -root/m is 0 only in the critical case, which does not divide */
static Complex c_quot(Complex a, Complex b)
{
    Complex r;
    const double abs_breal = b.re < 0 ? -b.re : b.re;
    const double abs_bimag = b.im < 0 ? -b.im : b.im;
    if (abs_breal >= abs_bimag) {
        if (abs_breal == 0.0) {
            r.re = r.im = 0.0;
        } else {
            const double ratio = b.im / b.re;
            const double denom = b.re + b.im * ratio;
            r.re = (a.re + a.im * ratio) / denom;
            r.im = (a.im - a.re * ratio) / denom;
        }
    } else if (abs_bimag >= abs_breal) {
        const double ratio = b.re / b.im;
        const double denom = b.re * ratio + b.im;
        r.re = (a.re * ratio + a.im) / denom;
        r.im = (a.im * ratio - a.re) / denom;
    } else {                       /* a NaN among b's parts */
        r.re = r.im = NAN;
    }
    return r;
}

/* cmath_sqrt_impl for finite z */
static Complex c_sqrt(Complex z)
{
    /* CM_SCALE_UP, CM_SCALE_DOWN of cmathmodule.c for IEEE doubles */
    const int scale_up = 2 * (DBL_MANT_DIG / 2) + 1;
    const int scale_down = -(scale_up + 1) / 2;
    Complex r;
    double s, d, ax, ay;
    if (z.re == 0. && z.im == 0.) {
        r.re = 0.;
        r.im = z.im;
        return r;
    }
    ax = fabs(z.re);
    ay = fabs(z.im);
    if (ax < DBL_MIN && ay < DBL_MIN) {      /* hypot(ax, ay) would be subnormal */
        ax = ldexp(ax, scale_up);
        s = ldexp(sqrt(ax + hypot(ax, ldexp(ay, scale_up))), scale_down);
    } else {
        ax /= 8.;
        s = 2. * sqrt(ax + hypot(ax, ay / 8.));
    }
    d = ay / (2. * s);
    if (z.re >= 0.) {
        r.re = s;
        r.im = copysign(d, z.im);
    } else {
        r.re = d;
        r.im = copysign(s, z.im);
    }
    return r;
}

/* cmathmodule.c's CM_LOG_LARGE_DOUBLE, log(DBL_MAX / 4), and Py_MATH_E */
#define LOG_LARGE_DOUBLE 708.3964185322641
#define PY_MATH_E 2.7182818284590452354

/* cmath_exp_impl for finite z */
static Complex c_exp(Complex z)
{
    Complex r;
    double l;
    if (z.re > LOG_LARGE_DOUBLE) {
        l = exp(z.re - 1.);
        r.re = l * cos(z.im) * PY_MATH_E;
        r.im = l * sin(z.im) * PY_MATH_E;
    } else {
        l = exp(z.re);
        r.re = l * cos(z.im);
        r.im = l * sin(z.im);
    }
    return r;
}

static Complex complex_at(double re, double im)
{
    Complex r = {re, im};
    return r;
}

void sew_oscillator_init(SewOscillator *o, double m, double b, double c, double f0, double f1,
                         double f2, double y0, double v0)
{
    double e0, de0, disc;
    Complex root, l1, l2;
    o->m = m;
    o->b = b;
    o->c = c;
    o->f0 = f0;
    o->f1 = f1;
    o->f2 = f2;
    /* particular solution: a quadratic in τ */
    o->p2 = f2 / c;
    o->p1 = (f1 - 2.0 * b * o->p2) / c;
    o->p0 = (f0 - b * o->p1 - 2.0 * m * o->p2) / c;
    e0 = y0 - o->p0;
    de0 = v0 - o->p1;
    disc = b * b - 4.0 * m * c;
    root = c_sqrt(complex_of(disc));
    l1 = c_quot(c_sum(complex_of(-b), root), complex_of(2.0 * m));
    l2 = c_quot(c_diff(complex_of(-b), root), complex_of(2.0 * m));
    o->critical = fabs(disc) <= 1e-12 * (b * b + 4.0 * m * c);
    if (o->critical) {             /* repeated root: (k1 + k2·τ)·exp(l1·τ), all real */
        double l = -b / (2.0 * m);
        o->l1_re = o->l2_re = l;
        o->l1_im = o->l2_im = 0.0;
        o->k1_re = e0;
        o->k2_re = de0 - l * e0;
        o->k1_im = o->k2_im = 0.0;
    } else {
        Complex k2 = c_quot(c_diff(complex_of(de0), c_prod(l1, complex_of(e0))), c_diff(l2, l1));
        Complex k1 = c_diff(complex_of(e0), k2);
        o->l1_re = l1.re;
        o->l1_im = l1.im;
        o->l2_re = l2.re;
        o->l2_im = l2.im;
        o->k1_re = k1.re;
        o->k1_im = k1.im;
        o->k2_re = k2.re;
        o->k2_im = k2.im;
    }
}

void sew_oscillator_state(const SewOscillator *o, double tau, double *y, double *v)
{
    double py = o->p0 + tau * (o->p1 + tau * o->p2);
    double pv = o->p1 + 2.0 * tau * o->p2;
    if (o->critical) {
        double ex = exp(o->l1_re * tau);
        double e = (o->k1_re + o->k2_re * tau) * ex;
        double de = (o->k2_re + o->l1_re * (o->k1_re + o->k2_re * tau)) * ex;
        *y = py + e;
        *v = pv + de;
    } else {
        Complex l1 = complex_at(o->l1_re, o->l1_im), l2 = complex_at(o->l2_re, o->l2_im);
        Complex x1 = c_prod(complex_at(o->k1_re, o->k1_im), c_exp(c_prod(l1, complex_of(tau))));
        Complex x2 = c_prod(complex_at(o->k2_re, o->k2_im), c_exp(c_prod(l2, complex_of(tau))));
        *y = py + c_sum(x1, x2).re;
        *v = pv + c_sum(c_prod(l1, x1), c_prod(l2, x2)).re;
    }
}

double sew_oscillator_accel(const SewOscillator *o, double tau, double y, double v)
{
    return (o->f0 + tau * (o->f1 + tau * o->f2) - o->b * v - o->c * y) / o->m;
}
