/* twin-of: components/kinematics.py sha256:6bb52530545eda75 */
/* Planar kinematics shared by every linkage (see kinematics.h): the same operations in the same
   order as components/kinematics.py, so that a linkage's numbers agree with Python's to the
   last bits. Velocities and accelerations from the differentiated loop-closure equations. */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1   /* printf's %g as C99 and Python write it: "1e-05" */
#endif
#include "kinematics.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sew_model.h"

SewMotion sew_at_rest(double x, double y)
{
    SewMotion m = {x, y, 0.0, 0.0, 0.0, 0.0};
    return m;
}

SewAngle sew_angle(double value, double rate, double accel)
{
    SewAngle a = {value, rate, accel};
    return a;
}

int sew_divide(double a, double b, double *quotient, char *why)
{
    if (b == 0.0) {
        snprintf(why, SEW_WHY, "float division by zero");
        return -1;
    }
    *quotient = a / b;
    return 0;
}

SewMotion sew_point_on_link(SewMotion pivot, double length, SewAngle ang, double offset)
{
    double c = cos(ang.value + offset), s = sin(ang.value + offset);
    double w = ang.rate, dw = ang.accel;
    double w2 = w * w;
    SewMotion m = {pivot.x + length * c, pivot.y + length * s,
                   pivot.vx - length * w * s, pivot.vy + length * w * c,
                   pivot.ax + length * (-dw * s - w2 * c), pivot.ay + length * (dw * c - w2 * s)};
    return m;
}

int sew_link_angle(SewMotion start, SewMotion end, SewAngle *out, char *why)
{
    double rx = end.x - start.x, ry = end.y - start.y;
    double vx = end.vx - start.vx, vy = end.vy - start.vy;
    double ax = end.ax - start.ax, ay = end.ay - start.ay;
    double r2 = rx * rx + ry * ry;
    double rate, accel;
    /* Python evaluates the tuple's items in order: atan2 cannot fail, the rate divides first */
    if (sew_divide(rx * vy - ry * vx, r2, &rate, why) != 0
        || sew_divide(rx * ay - ry * ax, r2, &accel, why) != 0)
        return -1;
    out->value = atan2(ry, rx);
    out->rate = rate;
    out->accel = accel;
    return 0;
}

int sew_dyad_rrr(SewMotion p, double r_p, SewMotion q, double r_q, int side, const char *name,
                 SewMotion *out, char *why)
{
    double dx = q.x - p.x, dy = q.y - p.y;
    double d2 = dx * dx + dy * dy;
    double d, along, h2, ex, ey, hh, x, y, ax_, ay_, bx_, by_, det;
    double ra, rb, vx, vy, dvpx, dvpy, dvqx, dvqy;
    if (!(d2 > 0.0)) {
        snprintf(why, SEW_WHY, "%s: the two pivots coincide", name);
        return -1;
    }
    d = sqrt(d2);
    /* distance from P, along P->Q, to the chord through the two intersection points */
    along = (d2 + r_p * r_p - r_q * r_q) / (2.0 * d);
    h2 = r_p * r_p - along * along;
    if (!(h2 >= 0.0)) {
        snprintf(why, SEW_WHY, "%s: links of %.6g m and %.6g m cannot meet", name, r_p, r_q);
        return -1;
    }
    ex = dx / d;
    ey = dy / d;
    hh = (double)side * sqrt(h2);
    x = p.x + along * ex - hh * ey;
    y = p.y + along * ey + hh * ex;

    /* velocity and acceleration loops; rows of the matrix are (X - P) and (X - Q) */
    ax_ = x - p.x;
    ay_ = y - p.y;
    bx_ = x - q.x;
    by_ = y - q.y;
    det = ax_ * by_ - ay_ * bx_;
    if (det == 0.0) {
        snprintf(why, SEW_WHY, "%s: links of %.6g m and %.6g m are stretched flat", name, r_p,
                 r_q);
        return -1;
    }
    /* each system by Cramer's rule, as Python writes it out */
    ra = ax_ * p.vx + ay_ * p.vy;
    rb = bx_ * q.vx + by_ * q.vy;
    vx = (ra * by_ - rb * ay_) / det;
    vy = (ax_ * rb - bx_ * ra) / det;
    dvpx = vx - p.vx;
    dvpy = vy - p.vy;
    dvqx = vx - q.vx;
    dvqy = vy - q.vy;
    ra = ax_ * p.ax + ay_ * p.ay - (dvpx * dvpx + dvpy * dvpy);
    rb = bx_ * q.ax + by_ * q.ay - (dvqx * dvqx + dvqy * dvqy);
    out->x = x;
    out->y = y;
    out->vx = vx;
    out->vy = vy;
    out->ax = (ra * by_ - rb * ay_) / det;
    out->ay = (ax_ * rb - bx_ * ra) / det;
    return 0;
}

int sew_dyad_rrp(SewMotion c, double r, double line_x, double line_y, double line_angle,
                 int side, const char *name, SewMotion *out, char *why)
{
    double ux = cos(line_angle), uy = sin(line_angle);
    double relx = c.x - line_x, rely = c.y - line_y;
    double along = relx * ux + rely * uy;
    double off = ux * rely - uy * relx;          /* signed distance of C from the line */
    double h2 = r * r - off * off;
    double s, x, y, rodx, rody, denom, s_dot, dvx, dvy, s_ddot;
    if (!(h2 >= 0.0)) {
        snprintf(why, SEW_WHY, "%s: rod of %.6g m cannot reach the slider line", name, r);
        return -1;
    }
    s = along + (double)side * sqrt(h2);
    x = line_x + s * ux;
    y = line_y + s * uy;
    rodx = x - c.x;
    rody = y - c.y;
    denom = rodx * ux + rody * uy;
    if (denom == 0.0) {
        snprintf(why, SEW_WHY, "%s: rod of %.6g m stands square to the slider line", name, r);
        return -1;
    }
    s_dot = (rodx * c.vx + rody * c.vy) / denom;
    dvx = s_dot * ux - c.vx;
    dvy = s_dot * uy - c.vy;
    s_ddot = (rodx * c.ax + rody * c.ay - (dvx * dvx + dvy * dvy)) / denom;
    out->x = x;
    out->y = y;
    out->vx = s_dot * ux;
    out->vy = s_dot * uy;
    out->ax = s_ddot * ux;
    out->ay = s_ddot * uy;
    return 0;
}

double sew_crank_turn(int k, int samples)
{
    double step = 2.0 * SEW_PI / samples;
    return k * step;
}

int sew_check_assembly(SewEvaluate evaluate, void *context, const char *mechanism,
                       const char *const *names, const double *p, int n, const char *angle_name,
                       int samples, char *why)
{
    char reason[SEW_WHY];
    int k, i;
    for (k = 0; k < samples; k++) {
        double crank = sew_crank_turn(k, samples);
        size_t len;
        if (evaluate(context, crank, reason) == 0)
            continue;
        /* math.degrees: x * (180 / pi); the degree sign in UTF-8, as Python writes it */
        len = (size_t)snprintf(why, SEW_WHY, "%s cannot be assembled at %s = %.1f\xc2\xb0 (%s); "
                               "parameters: ", mechanism, angle_name,
                               crank * (180.0 / SEW_PI), reason);
        for (i = 0; i < n && len < SEW_WHY; i++)
            len += (size_t)snprintf(why + len, SEW_WHY - len, "%s%s=%g", i ? ", " : "",
                                    names[i], p[i]);
        return -1;
    }
    return 0;
}
