/* twin-of: components/parameters.py sha256:b9d6335db0d8c591 */
/* twin-of: components/units.py sha256:c0938e7e938a7907 */
/* components/parameters.py's check_value and validate for every model's build: the same rules
   in the same order (finite, the choice or the allowed sign, the machine's scale of the unit
   with the "meant in" hint of units.py's display units) and ParameterError's words,
   "parameter m: must be > 0 kg, got -1.0", with Python's repr and format(:g) of the value. */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1   /* printf's %e and %g as C99 and Python write them: "1e-05" */
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "parameters.h"
#include "sew_model.h"

#define PI 3.141592653589793            /* math.pi (M_PI is not C99) */

/* MACHINE_SCALE, _MEANT and the factor DISPLAY_UNITS[unit][meant] (units.py), by unit */
static const struct {
    const char *unit;
    double scale;
    const char *meant;                  /* NULL: no hint for this unit */
    double factor;
} UNIT_SCALES[] = {
    {"m", 1.0, "mm", 1e3},
    {"kg", 50.0, "g", 1e3},
    {"rad", 2 * PI, "deg", 180.0 / PI},
    {"rad/s", 2000.0, "rpm", 60.0 / (2.0 * PI)},
    {"s", 60.0, NULL, 0.0},
    {"N", 1e4, NULL, 0.0},
    {"N/m", 1e9, NULL, 0.0},
    {"N.s/m", 1e6, NULL, 0.0},
    {"N.m2", 1e7, NULL, 0.0},
    {"kg.m2", 10.0, NULL, 0.0},
};
#define N_UNIT_SCALES ((int)(sizeof UNIT_SCALES / sizeof UNIT_SCALES[0]))

/* --- reading a decimal back exactly ---------------------------------------------------------
   Whether M·10^E reads back as a double is decided here in whole numbers, not with strtod:
   mingw-w64's strtod reads some decimals just below a large power of two as the power itself
   (3.839223843572815e-239 as 2**-791), which would shorten repr there on Windows. */

#define BIG_LIMBS 64                    /* 2048 bits; a comparison needs at most ~1200 */

typedef struct {
    int n;                              /* limbs in use, least significant first */
    unsigned int limb[BIG_LIMBS];       /* 32 bits each */
} Big;

static void big_set(Big *b, unsigned long long v)
{
    b->n = 0;
    for (; v != 0; v >>= 32) b->limb[b->n++] = (unsigned int)(v & 0xffffffffu);
}

static void big_mul_small(Big *b, unsigned int k)
{
    unsigned long long carry = 0;
    int i;
    for (i = 0; i < b->n; i++) {
        carry += (unsigned long long)b->limb[i] * k;
        b->limb[i] = (unsigned int)(carry & 0xffffffffu);
        carry >>= 32;
    }
    if (carry != 0 && b->n < BIG_LIMBS) b->limb[b->n++] = (unsigned int)carry;
}

static void big_mul_pow10(Big *b, int n)
{
    static const unsigned int small[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000,
                                         100000000};
    for (; n >= 9; n -= 9) big_mul_small(b, 1000000000u);
    big_mul_small(b, small[n]);
}

static void big_shift_left(Big *b, int n)
{
    int whole = n / 32, bits = n % 32, i;
    if (b->n == 0) return;
    if (bits != 0) {
        unsigned int carry = 0;
        for (i = 0; i < b->n; i++) {
            unsigned int next = b->limb[i] >> (32 - bits);
            b->limb[i] = (b->limb[i] << bits) | carry;
            carry = next;
        }
        if (carry != 0 && b->n < BIG_LIMBS) b->limb[b->n++] = carry;
    }
    if (whole > 0 && b->n + whole <= BIG_LIMBS) {
        for (i = b->n - 1; i >= 0; i--) b->limb[i + whole] = b->limb[i];
        for (i = 0; i < whole; i++) b->limb[i] = 0;
        b->n += whole;
    }
}

static int big_cmp(const Big *a, const Big *b)
{
    int i;
    if (a->n != b->n) return a->n < b->n ? -1 : 1;
    for (i = a->n - 1; i >= 0; i--)
        if (a->limb[i] != b->limb[i]) return a->limb[i] < b->limb[i] ? -1 : 1;
    return 0;
}

/* sign of M·10^E - k·2^(e-2), as whole numbers (each side times what the other lacks) */
static int compare_scaled(unsigned long long M, int E, unsigned long long k, int e)
{
    Big a, b;
    big_set(&a, M);
    big_set(&b, k);
    if (E >= 0) big_mul_pow10(&a, E); else big_mul_pow10(&b, -E);
    if (e - 2 >= 0) big_shift_left(&b, e - 2); else big_shift_left(&a, 2 - e);
    return big_cmp(&a, &b);
}

/* whether the decimal M·10^E (M > 0) reads back as x (finite, > 0): within half the gap to
   x's neighbours (half the gap below only, where x is a power of two above the smallest
   normal), the ends included where x's significand is even (round half to even) */
static int reads_back(unsigned long long M, int E, double x)
{
    unsigned long long bits, f;
    int biased, e, inclusive, below, above;
    memcpy(&bits, &x, sizeof bits);
    biased = (int)((bits >> 52) & 0x7ff);
    f = bits & ((1ull << 52) - 1);
    e = biased == 0 ? -1074 : biased - 1075;      /* x = f·2^e */
    if (biased != 0) f |= 1ull << 52;
    inclusive = (f & 1) == 0;
    /* in quarters of the gap above, 2^(e-2): x is 4f, its neighbours' midpoints 4f ± 2 (4f - 1
       below a power of two, whose gap below is half) */
    below = compare_scaled(M, E, 4 * f - (f == 1ull << 52 && biased > 1 ? 1 : 2), e);
    above = compare_scaled(M, E, 4 * f + 2, e);
    return inclusive ? (below >= 0 && above <= 0) : (below > 0 && above < 0);
}

/* the digits of a p-digit mantissa m (10^(p-1) <= m < 10^p, or m = 0) */
static void mantissa_digits(unsigned long long m, int p, char *digits)
{
    int i;
    for (i = p - 1; i >= 0; i--, m /= 10) digits[i] = (char)('0' + (int)(m % 10));
    digits[p] = '\0';
}

/* Python's repr of a float: the shortest digits that read back as x (of as many digits, the
   closest to x: printf's rounding, or its neighbour on x's other side where x is a power of two,
   whose gap below is half the gap above: -2**-24 is -5.960464477539063e-08, not ...062e-08,
   which reads back as the double below), in fixed notation for a decimal point at
   -4 < decpt <= 16, else d.ddde+XX; a whole number ends in ".0" */
void sew_py_repr(double x, char *out, size_t size)
{
    char buf[48], digits[20], text[48];
    double ax = fabs(x);
    unsigned long long m = 0, low = 1, high;
    int p, n, e = 0, decpt, k = 0, i;
    if (isnan(x)) { snprintf(out, size, "nan"); return; }
    if (isinf(x)) { snprintf(out, size, x > 0 ? "inf" : "-inf"); return; }
    for (p = 1; p <= 17; p++, low *= 10) {
        const char *s;
        unsigned long long nearest;
        high = low * 10;                               /* m lies in [10^(p-1), 10^p) */
        snprintf(buf, sizeof buf, "%.*e", p - 1, ax);
        for (m = 0, s = buf; *s != 'e'; s++)
            if (*s != '.') m = 10 * m + (unsigned long long)(*s - '0');
        e = atoi(s + 1);
        if (ax == 0.0 || reads_back(m, e - p + 1, ax)) break;
        /* else only the neighbour on x's other side can read back (the one on the same side
           is farther still); trying both needs no comparison with x */
        nearest = m;
        if (nearest + 1 == high ? reads_back(low, e - p + 2, ax)
                                : reads_back(nearest + 1, e - p + 1, ax)) {
            if (++m == high) { m = low; e++; }
            break;
        }
        if (nearest == low ? reads_back(high - 1, e - p, ax)
                           : reads_back(nearest - 1, e - p + 1, ax)) {
            if (m == low) { m = high - 1; e--; } else { m--; }
            break;
        }
    }
    if (p > 17) p = 17;                                /* (never: 17 digits always read back) */
    mantissa_digits(m, p, digits);
    n = p;
    while (n > 1 && digits[n - 1] == '0') n--;
    decpt = e + 1;
    if (signbit(x)) text[k++] = '-';
    if (decpt <= -4 || decpt > 16) {
        text[k++] = digits[0];
        if (n > 1) text[k++] = '.';
        for (i = 1; i < n; i++) text[k++] = digits[i];
        snprintf(text + k, sizeof text - (size_t)k, "e%c%02d", e < 0 ? '-' : '+', abs(e));
    } else {
        if (decpt <= 0) {
            text[k++] = '0';
            text[k++] = '.';
            for (i = decpt; i < 0; i++) text[k++] = '0';
        }
        for (i = 0; i < n || i < decpt; i++) {
            if (i == decpt && decpt > 0) text[k++] = '.';
            text[k++] = i < n ? digits[i] : '0';
        }
        if (decpt >= n) {
            text[k++] = '.';
            text[k++] = '0';
        }
        text[k] = '\0';
    }
    snprintf(out, size, "%s", text);
}

/* check_value's CHOICE branch on int(value): "must be one of [0, 1], got 2" */
static int check_choice(const SewParamInfo *info, double value, char *why)
{
    char list[64] = "";
    double whole = trunc(value) + 0.0;        /* int() truncates; + 0.0: int(-0.5) is 0 */
    int i;
    for (i = 0; i < info->n_choices; i++)
        if (whole == info->choices[i]) return 0;
    for (i = 0; i < info->n_choices; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%d", i ? ", " : "",
                 info->choices[i]);
    snprintf(why, SEW_WHY, "parameter %s: must be one of [%s], got %.0f", info->name, list,
             whole);
    return -1;
}

int sew_check_value(const SewParamInfo *info, double value, char *why)
{
    static const char *const range_text[] = {"> 0", ">= 0", "in (0, 1)"};
    char text[48];
    double low, high;
    int ok, u;
    if (!isfinite(value)) {
        sew_py_repr(value, text, sizeof text);
        snprintf(why, SEW_WHY, "parameter %s: must be finite, got %s", info->name, text);
        return -1;
    }
    if (info->allowed == SEW_CHOICE) return check_choice(info, value, why);
    ok = info->allowed == SEW_POSITIVE ? value > 0 :
         info->allowed == SEW_NONNEGATIVE ? value >= 0 :
         info->allowed == SEW_FRACTION ? (0 < value && value < 1) : 1;
    if (!ok) {
        sew_py_repr(value, text, sizeof text);
        snprintf(why, SEW_WHY, "parameter %s: must be %s %s, got %s", info->name,
                 range_text[info->allowed], info->unit, text);
        return -1;
    }
    /* ParameterInfo.bounds: (0, 1) for a fraction, else up to the unit's scale (none: no
       bound), from -scale for ANY and from 0 for a signed quantity */
    if (info->allowed == SEW_FRACTION) {
        low = 0.0;
        high = 1.0;
        u = -1;
    } else {
        for (u = 0; u < N_UNIT_SCALES && strcmp(UNIT_SCALES[u].unit, info->unit) != 0; u++) {}
        if (u == N_UNIT_SCALES) return 0;
        high = UNIT_SCALES[u].scale;
        low = info->allowed == SEW_ANY ? -high : 0.0;
    }
    if (!(low <= value && value <= high)) {
        /* the hint only where the number, read in that unit, is within the range */
        char hint[128] = "";
        if (u >= 0 && UNIT_SCALES[u].meant != NULL) {
            double meant = value / UNIT_SCALES[u].factor;
            if (low <= meant && meant <= high)
                snprintf(hint, sizeof hint, " (meant in %s? give the unit: \"%g %s\")",
                         UNIT_SCALES[u].meant, value, UNIT_SCALES[u].meant);
        }
        snprintf(why, SEW_WHY, "parameter %s: must be within [%g, %g] %s in a sewing machine's "
                 "mechanism, got %g%s", info->name, low, high, info->unit, value, hint);
        return -1;
    }
    return 0;
}

int sew_validate(const SewParamInfo *infos, int n, const double *p, char *why)
{
    int i;
    for (i = 0; i < n; i++)
        if (sew_check_value(&infos[i], p[i], why) != 0) return -1;
    return 0;
}
