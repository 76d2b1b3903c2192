/* components/parameters.py's checks for every model's build (parameters.c): a parameter as its
   dataclass field declares it (name, SI unit, allowed range, choices), validate with
   ParameterError's words, and Python's repr of a float for them. */
#ifndef SEW_PARAMETERS_H
#define SEW_PARAMETERS_H

#include <stddef.h>

/* parameters.py's allowed ranges */
typedef enum { SEW_POSITIVE, SEW_NONNEGATIVE, SEW_FRACTION, SEW_ANY, SEW_CHOICE } SewAllowed;

#define SEW_MAX_CHOICES 4

/* ParameterInfo: what check_value reads of a field. The machine's scale of the unit and how a
   too large value is usually meant are looked up by unit, as parameters.py does. */
typedef struct {
    const char *name;
    const char *unit;
    SewAllowed allowed;
    int n_choices;                     /* SEW_CHOICE: its choices, as declared */
    int choices[SEW_MAX_CHOICES];
} SewParamInfo;

/* a field with no choices */
#define SEW_PARAM(name, unit, allowed) {name, unit, allowed, 0, {0, 0, 0, 0}}

/* Python's repr(x) into out (size bytes; 32 hold every double's) */
void sew_py_repr(double x, char *out, size_t size);

/* check_value: 0, or -1 with ParameterError's text in why (SEW_WHY bytes). A choice's value
   is made int as SewSlave.model does (truncated) before it is checked. */
int sew_check_value(const SewParamInfo *info, double value, char *why);

/* validate: the n parameters p in their dataclass's order; the first refused one named */
int sew_validate(const SewParamInfo *infos, int n, const double *p, char *why);

#endif
