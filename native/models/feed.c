/* twin-of: components/feed.py sha256:cca55492e83ab8e6 */
/* twin-of: components/feed_fmu.py sha256:b1a9a9ef28ea6a5a */
/* The closed lever-hinge feed mechanism (SEW_MODEL_FeedLinkage): one crank at A drives the lift
   branch (rod 2, lever 3 about D) and the feed branch (rod 8, rocker 7 about G), closed by rod 4
   and the feed-bar lever 5 that carries the feed-dog point M. The C twin of components/feed.py's
   FeedLinkage; its row is FeedLinkageSlave's outputs (components/feed_fmu.py). Stateless, and
   nothing to work out once: build only checks. */
#include <math.h>
#include <stddef.h>

#include "kinematics.h"
#include "parameters.h"
#include "sew_model.h"

/* FeedParams' fields, in order */
enum {
    R_L, R_F, ALPHA1, L2, L8, X_D, Y_D, X_G, Y_G, L3, L3P, ALPHA3, L7, L7P, ALPHA7, L4, L5, L_HM,
    N_PARAMS
};

#define LENGTH(name, allowed) SEW_PARAM(name, "m", allowed)
#define ANGLE(name, allowed) SEW_PARAM(name, "rad", allowed)

static const SewParamInfo PARAMS[N_PARAMS] = {
    LENGTH("r_l", SEW_POSITIVE), LENGTH("r_f", SEW_POSITIVE), ANGLE("alpha1", SEW_ANY),
    LENGTH("l2", SEW_POSITIVE), LENGTH("l8", SEW_POSITIVE), LENGTH("x_D", SEW_ANY),
    LENGTH("y_D", SEW_ANY), LENGTH("x_G", SEW_ANY), LENGTH("y_G", SEW_ANY),
    LENGTH("l3", SEW_POSITIVE), LENGTH("l3p", SEW_POSITIVE), ANGLE("alpha3", SEW_ANY),
    LENGTH("l7", SEW_POSITIVE), LENGTH("l7p", SEW_POSITIVE), ANGLE("alpha7", SEW_ANY),
    LENGTH("l4", SEW_POSITIVE), LENGTH("l5", SEW_POSITIVE), LENGTH("l_HM", SEW_POSITIVE),
};

/* what the FMU reads of FeedMotion: the point M, the link angles, the transmission angles */
typedef struct {
    SewMotion m;
    SewAngle phi3, phi4, phi5, phi7;
    double mu_c, mu_n, mu_f;
} FeedMotion;

/* transmission_angle: the angle between the links from P and from Q that meet at `joint`,
   folded to [0, π/2] */
static int transmission_angle(SewMotion joint, SewMotion p, SewMotion q, double *mu_out,
                              char *why)
{
    double ax = p.x - joint.x, ay = p.y - joint.y;
    double bx = q.x - joint.x, by = q.y - joint.y;
    double c, mu;
    if (sew_divide(ax * bx + ay * by, sqrt((ax * ax + ay * ay) * (bx * bx + by * by)), &c, why)
        != 0)
        return -1;
    /* min(1.0, max(-1.0, c)) as Python's min and max choose (a NaN gives -1) */
    c = c > -1.0 ? c : -1.0;
    c = c < 1.0 ? c : 1.0;
    mu = acos(c);
    *mu_out = SEW_PI - mu < mu ? SEW_PI - mu : mu;
    return 0;
}

/* FeedLinkage.motion at crank angle phi1, speed omega, acceleration epsilon */
static int motion(const double *p, double phi1, double omega, double epsilon, FeedMotion *out,
                  char *why)
{
    SewMotion a = sew_at_rest(0.0, 0.0), d = sew_at_rest(p[X_D], p[Y_D]);
    SewMotion g = sew_at_rest(p[X_G], p[Y_G]), b, k, c, n, e, h, f;
    SewAngle crank = sew_angle(phi1, omega, epsilon);
    b = sew_point_on_link(a, p[R_L], crank, 0.0);
    k = sew_point_on_link(a, p[R_F], crank, p[ALPHA1]);
    if (sew_dyad_rrr(b, p[L2], d, p[L3], SEW_RIGHT, "rod 2 / lever 3", &c, why) != 0
        || sew_dyad_rrr(k, p[L8], g, p[L7], SEW_LEFT, "rod 8 / rocker 7", &n, why) != 0
        || sew_link_angle(d, c, &out->phi3, why) != 0
        || sew_link_angle(g, n, &out->phi7, why) != 0)
        return -1;
    e = sew_point_on_link(d, p[L3P], out->phi3, p[ALPHA3]);
    h = sew_point_on_link(g, p[L7P], out->phi7, SEW_PI / 2 + p[ALPHA7]);
    if (sew_dyad_rrr(e, p[L4], h, p[L5], SEW_LEFT, "rod 4 / feed-bar lever 5", &f, why) != 0
        || sew_link_angle(e, f, &out->phi4, why) != 0
        || sew_link_angle(h, f, &out->phi5, why) != 0)
        return -1;
    out->m = sew_point_on_link(h, p[L_HM], out->phi5, 0.0);
    if (transmission_angle(c, b, d, &out->mu_c, why) != 0
        || transmission_angle(n, k, g, &out->mu_n, why) != 0
        || transmission_angle(f, e, h, &out->mu_f, why) != 0)
        return -1;
    return 0;
}

static int at_rest(void *context, double phi1, char *why)
{
    FeedMotion m;
    return motion(context, phi1, 0.0, 0.0, &m, why);
}

static int build(const double *p, double *derived, char *why)
{
    const char *names[N_PARAMS];
    int i;
    (void)derived;
    if (sew_validate(PARAMS, N_PARAMS, p, why) != 0)
        return -1;
    for (i = 0; i < N_PARAMS; i++)
        names[i] = PARAMS[i].name;
    return sew_check_assembly(at_rest, (void *)p, "feed mechanism", names, p, N_PARAMS,
                              "crank angle phi1", 3600, why);
}

/* FeedLinkageSlave's row: phi3, phi4, phi5, phi7, M_x, M_y, M_vx, M_vy, M_ax, M_ay, mu_C, mu_N,
   mu_F */
static int outputs(const double *p, const double *derived, const double *state,
                   const double *u, double t, double *row, char *why)
{
    FeedMotion m;
    (void)derived;
    (void)state;
    (void)t;
    if (motion(p, u[0], u[1], u[2], &m, why) != 0)
        return -1;
    row[0] = m.phi3.value;
    row[1] = m.phi4.value;
    row[2] = m.phi5.value;
    row[3] = m.phi7.value;
    row[4] = m.m.x;
    row[5] = m.m.y;
    row[6] = m.m.vx;
    row[7] = m.m.vy;
    row[8] = m.m.ax;
    row[9] = m.m.ay;
    row[10] = m.mu_c;
    row[11] = m.mu_n;
    row[12] = m.mu_f;
    return 0;
}

const SewModel SEW_MODEL_FeedLinkage = {
    "FeedLinkage", 0, 0, build, NULL, NULL, outputs, 0,
};
