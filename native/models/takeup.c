/* twin-of: components/takeup.py sha256:653fa0ffd62ca8c7 */
/* twin-of: components/takeup_fmu.py sha256:33658ab2908f7439 */
/* The thread take-up four-bar (SEW_MODEL_TakeupLinkage): crank AB, coupler BC with the take-up
   eye E on it, rocker CD; frame A = (0, 0), coordinates (Z, X). The C twin of
   components/takeup.py's TakeupLinkage; its row is TakeupLinkageSlave's outputs
   (components/takeup_fmu.py). Stateless, and nothing to work out once: build only checks. */
#include <stddef.h>

#include "kinematics.h"
#include "parameters.h"
#include "sew_model.h"

/* TakeupParams' fields, in order */
enum { L_AB, L_BC, L_CD, L_BE, ANGLE_CBE, Z_D, X_D, N_PARAMS };

#define LENGTH(name, allowed) SEW_PARAM(name, "m", allowed)
#define ANGLE(name, allowed) SEW_PARAM(name, "rad", allowed)

static const SewParamInfo PARAMS[N_PARAMS] = {
    LENGTH("L_AB", SEW_POSITIVE), LENGTH("L_BC", SEW_POSITIVE), LENGTH("L_CD", SEW_POSITIVE),
    LENGTH("L_BE", SEW_POSITIVE), ANGLE("angle_CBE", SEW_ANY), LENGTH("z_D", SEW_ANY),
    LENGTH("x_D", SEW_ANY),
};

/* TakeupMotion: the joints B, C, E and the link angles */
typedef struct {
    SewMotion b, c, e;
    SewAngle phi_bc, phi_cd;
} TakeupMotion;

/* TakeupLinkage.motion at crank angle theta (rad, from +Z), speed omega, acceleration epsilon */
static int motion(const double *p, double theta, double omega, double epsilon, TakeupMotion *m,
                  char *why)
{
    SewMotion d = sew_at_rest(p[Z_D], p[X_D]);
    m->b = sew_point_on_link(sew_at_rest(0.0, 0.0), p[L_AB], sew_angle(theta, omega, epsilon),
                             0.0);
    /* the "+" root of the paper's closed form: C on the left of B -> D (larger Z) */
    if (sew_dyad_rrr(m->b, p[L_BC], d, p[L_CD], SEW_LEFT, "coupler BC / rocker CD", &m->c, why)
        != 0 || sew_link_angle(m->b, m->c, &m->phi_bc, why) != 0)
        return -1;
    m->e = sew_point_on_link(m->b, p[L_BE], m->phi_bc, p[ANGLE_CBE]);
    return sew_link_angle(d, m->c, &m->phi_cd, why);
}

static int at_rest(void *context, double theta, char *why)
{
    TakeupMotion m;
    return motion(context, theta, 0.0, 0.0, &m, why);
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
    return sew_check_assembly(at_rest, (void *)p, "thread take-up four-bar", names, p, N_PARAMS,
                              "crank angle theta", 3600, why);
}

/* TakeupLinkageSlave's row: E_z, E_x, E_vz, E_vx, E_az, E_ax, phi_BC, phi_CD */
static int outputs(const double *p, const double *derived, const double *state,
                   const double *u, double t, double *row, char *why)
{
    TakeupMotion m;
    (void)derived;
    (void)state;
    (void)t;
    if (motion(p, u[0], u[1], u[2], &m, why) != 0)
        return -1;
    row[0] = m.e.x;
    row[1] = m.e.y;
    row[2] = m.e.vx;
    row[3] = m.e.vy;
    row[4] = m.e.ax;
    row[5] = m.e.ay;
    row[6] = m.phi_bc.value;
    row[7] = m.phi_cd.value;
    return 0;
}

const SewModel SEW_MODEL_TakeupLinkage = {
    "TakeupLinkage", 0, 0, build, NULL, NULL, outputs, 0,
};
