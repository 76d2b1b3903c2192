/* The exact solution of a damped linear oscillator under polynomial forcing: the C twin of
   components/oscillator.py's DampedOscillator (the punch between switches, each carriage mode).

       m·y'' + b·y' + c·y = f0 + f1·τ + f2·τ²,   y(0) = y0, y'(0) = v0                        */
#ifndef SEW_OSCILLATOR_H
#define SEW_OSCILLATOR_H

typedef struct {
    double m, b, c, f0, f1, f2;
    double p0, p1, p2;                 /* particular solution, a quadratic in τ */
    double l1_re, l1_im, l2_re, l2_im; /* the roots */
    double k1_re, k1_im, k2_re, k2_im; /* the homogeneous solution's coefficients */
    int critical;                      /* repeated root: (k1 + k2·τ)·exp(l1·τ) */
} SewOscillator;

void sew_oscillator_init(SewOscillator *o, double m, double b, double c, double f0, double f1,
                         double f2, double y0, double v0);
/* (y, y') at τ */
void sew_oscillator_state(const SewOscillator *o, double tau, double *y, double *v);
double sew_oscillator_accel(const SewOscillator *o, double tau, double y, double v);

#endif
