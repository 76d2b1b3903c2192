/* Planar kinematics shared by every linkage: the C twin of components/kinematics.py.

   A point in motion is a SewMotion (position, velocity, acceleration); an angle with its rate and
   acceleration a SewAngle. What raises in Python (AssemblyError, and ZeroDivisionError where
   Python divides by a float zero and C would give inf) returns -1 here with Python's message in
   why (SEW_WHY bytes). */
#ifndef SEW_KINEMATICS_H
#define SEW_KINEMATICS_H

#include <stddef.h>

#define SEW_PI 3.141592653589793          /* math.pi */
#define SEW_LEFT (+1)   /* X on the left of the directed line P -> Q */
#define SEW_RIGHT (-1)

typedef struct { double x, y, vx, vy, ax, ay; } SewMotion;
typedef struct { double value, rate, accel; } SewAngle;

/* Motion(x, y): a point at rest */
SewMotion sew_at_rest(double x, double y);
SewAngle sew_angle(double value, double rate, double accel);

/* a point at `length` from pivot on a link whose direction is ang + offset (rad) */
SewMotion sew_point_on_link(SewMotion pivot, double length, SewAngle ang, double offset);

/* the direction of start -> end with rate and acceleration; -1 where |end - start|² is 0
   (Python: ZeroDivisionError "float division by zero") */
int sew_link_angle(SewMotion start, SewMotion end, SewAngle *out, char *why);

/* joint X of links r_p from P and r_q from Q, on `side` of P -> Q (dyad_rrr) */
int sew_dyad_rrr(SewMotion p, double r_p, SewMotion q, double r_q, int side, const char *name,
                 SewMotion *out, char *why);

/* slider X on the fixed line through (line_x, line_y) at line_angle, joined to C by a rod of
   length r; side +1 along the line direction, -1 behind (dyad_rrp) */
int sew_dyad_rrp(SewMotion c, double r, double line_x, double line_y, double line_angle,
                 int side, const char *name, SewMotion *out, char *why);

/* crank_turn(samples)[k] */
double sew_crank_turn(int k, int samples);

/* What check_assembly evaluates at one crank angle: 0, or -1 with the reason in why. */
typedef int (*SewEvaluate)(void *context, double crank, char *why);

/* check_assembly: evaluate at every crank angle of crank_turn(samples), in order; at the first
   that fails, -1 with "<mechanism> cannot be assembled at <angle_name> = 12.3° (<reason>);
   parameters: k=v, ..." (names[0..n), p[0..n) listed as f"{v:g}"). */
int sew_check_assembly(SewEvaluate evaluate, void *context, const char *mechanism,
                       const char *const *names, const double *p, int n, const char *angle_name,
                       int samples, char *why);

/* Python's float division a / b: -1 with ZeroDivisionError's text where b is 0 */
int sew_divide(double a, double b, double *quotient, char *why);

#endif
