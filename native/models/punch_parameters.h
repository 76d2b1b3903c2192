/* twin-of: components/parameters.py sha256:b9d6335db0d8c591 */
/* twin-of: components/units.py sha256:c0938e7e938a7907 */
/* components/parameters.py's validate for a model's build: the same rules in the same order
   (finite, the allowed sign or choice, the machine's scale of the unit) and ParameterError's
   text, "parameter m: must be > 0 kg, got -1.0", with Python's repr of the value.
   Static functions in a header: each model file that includes it uses all of them. */
#ifndef SEW_PUNCH_PARAMETERS_H
#define SEW_PUNCH_PARAMETERS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sew_model.h"

typedef enum { SEW_POSITIVE, SEW_NONNEGATIVE, SEW_FRACTION, SEW_ANY, SEW_CHOICE } SewAllowed;

typedef struct {
    const char *name;
    const char *unit;
    SewAllowed allowed;
    double scale;          /* MACHINE_SCALE of the unit; 0 where it has none */
    const char *meant;     /* _MEANT: how a too large value is usually meant, or NULL */
    double factor;         /* DISPLAY_UNITS[unit][meant] */
    int n_choices;         /* SEW_CHOICE: its choices, ascending */
    int choices[4];
} SewParamInfo;

/* MACHINE_SCALE of the units the punch's parameters have, and _MEANT's hint for kg */
#define SEW_SCALE_KG 50.0
#define SEW_SCALE_N 1e4
#define SEW_SCALE_N_PER_M 1e9
#define SEW_SCALE_NS_PER_M 1e6
#define SEW_G_PER_KG 1e3

/* Python's repr of a float: the shortest digits that read back as x (as %.*e rounds them:
   David Gay's choice wherever the shortest is unique), fixed notation for a decimal point
   position -4 < decpt <= 16, else d.ddde±XX; a whole number ends in ".0". */
static void sew_py_repr(double x, char *out, size_t size)
{
    char buf[40], digits[24];
    const char *s;
    int p, n = 0, exponent, decpt, len;
    if (isnan(x)) {
        snprintf(out, size, "nan");
        return;
    }
    if (isinf(x)) {
        snprintf(out, size, x > 0 ? "inf" : "-inf");
        return;
    }
    for (p = 1; p < 17; p++) {
        snprintf(buf, sizeof buf, "%.*e", p - 1, x);
        if (strtod(buf, NULL) == x)
            break;
    }
    if (p == 17)
        snprintf(buf, sizeof buf, "%.16e", x);
    s = buf[0] == '-' ? buf + 1 : buf;
    for (; *s != 'e'; s++)
        if (*s != '.')
            digits[n++] = *s;
    exponent = atoi(s + 1);
    while (n > 1 && digits[n - 1] == '0')
        n--;
    digits[n] = '\0';
    decpt = exponent + 1;
    len = snprintf(out, size, "%s", signbit(x) ? "-" : "");
    out += len;
    size -= (size_t)len;
    if (decpt <= -4 || decpt > 16) {
        snprintf(out, size, "%c%s%se%c%02d", digits[0], n > 1 ? "." : "", digits + 1,
                 exponent < 0 ? '-' : '+', abs(exponent));
    } else if (decpt <= 0) {          /* 0.000ddd */
        snprintf(out, size, "0.%.*s%s", -decpt, "0000", digits);
    } else if (decpt >= n) {          /* ddd000.0 */
        snprintf(out, size, "%s%.*s.0", digits, decpt - n, "0000000000000000");
    } else {                          /* dd.ddd */
        snprintf(out, size, "%.*s.%s", decpt, digits, digits + decpt);
    }
}

/* check_value: 0, or -1 with ParameterError's text in why. A choice is an Integer parameter,
   made int as SewSlave.model does (truncated) before it is checked. */
static int sew_check_value(const SewParamInfo *info, double value, char *why)
{
    static const char *const range_text[] = {"> 0", ">= 0", "in (0, 1)"};
    char text[48];
    int ok, i;
    sew_py_repr(value, text, sizeof text);
    if (!isfinite(value)) {
        snprintf(why, SEW_WHY, "parameter %s: must be finite, got %s", info->name, text);
        return -1;
    }
    if (info->allowed == SEW_CHOICE) {
        char list[64] = "";
        double whole = trunc(value);
        for (i = 0; i < info->n_choices; i++)
            if (whole == info->choices[i])
                return 0;
        for (i = 0; i < info->n_choices; i++)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%d", i ? ", " : "",
                     info->choices[i]);
        snprintf(why, SEW_WHY, "parameter %s: must be one of [%s], got %.0f", info->name, list,
                 whole);
        return -1;
    }
    ok = info->allowed == SEW_POSITIVE ? value > 0 :
         info->allowed == SEW_NONNEGATIVE ? value >= 0 :
         info->allowed == SEW_FRACTION ? (0 < value && value < 1) : 1;
    if (!ok) {
        snprintf(why, SEW_WHY, "parameter %s: must be %s %s, got %s", info->name,
                 range_text[info->allowed], info->unit, text);
        return -1;
    }
    /* ParameterInfo.bounds: (0, 1) for a fraction (held already), else the unit's scale, from
       0 for a signed quantity and from -scale for any */
    if (info->allowed != SEW_FRACTION && info->scale > 0) {
        double low = info->allowed == SEW_ANY ? -info->scale : 0.0;
        if (!(low <= value && value <= info->scale)) {
            char hint[128] = "";
            double meant = info->meant != NULL ? value / info->factor : 0.0;
            if (info->meant != NULL && low <= meant && meant <= info->scale)
                snprintf(hint, sizeof hint, " (meant in %s? give the unit: \"%g %s\")",
                         info->meant, value, info->meant);
            snprintf(why, SEW_WHY, "parameter %s: must be within [%g, %g] %s in a sewing "
                     "machine's mechanism, got %g%s", info->name, low, info->scale, info->unit,
                     value, hint);
            return -1;
        }
    }
    return 0;
}

/* validate: the parameters p in their dataclass's order, the first refused one named */
static int sew_validate(const SewParamInfo *infos, int n, const double *p, char *why)
{
    int i;
    for (i = 0; i < n; i++)
        if (sew_check_value(&infos[i], p[i], why) != 0)
            return -1;
    return 0;
}

#endif
