/* The runtime of a native sewfmu FMU: components/slave.py's SewSlave in C (sew_slave.h says
   what it adds to the Python FMUs). The same operations in the same order as the Python slave
   where numbers are made (the held rates, the Taylor extrapolation of inputs), so that a native
   FMU repeats the Python FMU's numbers to the last bit. */
#include "sew_slave.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* a step must start where the last one ended, to within this fraction of max(1 s, |t|, h):
   slave.py's _TIME_TOLERANCE */
#define SEW_TIME_TOLERANCE 1e-9

static const char *model_name(const SewSlave *s) { return s->d->model_name; }

/* text appended to line[*n..size), every '%' written out in words: FMI 2.0's logger is
   printf-like (hosts and containers pass a line on as the format), so no part of a line, the
   instance name a host gave included, may carry one (as the Python FMUs' error_line) */
static void append_words(char *line, size_t *n, size_t size, const char *text)
{
    for (const char *c = text; *c && *n + 9 < size; c++) {
        if (*c == '%') {
            memcpy(line + *n, " percent", 8);
            *n += 8;
        } else {
            line[(*n)++] = *c;
        }
    }
    line[*n] = '\0';
}

static void emit(SewSlave *s, SewStatus status, const char *message)
{
    char line[3 * SEW_WHY];
    size_t n = 0;
    line[0] = '\0';
    append_words(line, &n, sizeof line, s->instance);
    append_words(line, &n, sizeof line, " (");
    append_words(line, &n, sizeof line, model_name(s));
    append_words(line, &n, sizeof line, "): ");
    append_words(line, &n, sizeof line, message);
    if (s->log)
        s->log(s->env, status, line);
}

void sew_log(SewSlave *s, SewStatus status, const char *fmt, ...)
{
    char message[2 * SEW_WHY];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    emit(s, status, message);
}

SewStatus sew_refuse(SewSlave *s, const char *fmt, ...)
{
    char message[2 * SEW_WHY];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    emit(s, SEW_ERROR, message);
    return SEW_ERROR;
}

/* an Error line, but not the same one again at every getter call of a host's loop */
static void error_once(SewSlave *s, const char *key, const char *message)
{
    size_t n = strlen(key);
    if (n >= sizeof s->last_error)
        n = sizeof s->last_error - 1;     /* a key that long is told apart by its beginning */
    if (strncmp(key, s->last_error, n) == 0 && s->last_error[n] == '\0')
        return;
    memcpy(s->last_error, key, n);
    s->last_error[n] = '\0';
    emit(s, SEW_ERROR, message);
}

static void *zeroed(size_t n, size_t size) { return calloc(n > 0 ? n : 1, size); }

SewSlave *sew_new(const SewDescription *d, const char *instance, SewLogger log, void *env)
{
    SewSlave *s = zeroed(1, sizeof *s);
    if (!s)
        return NULL;
    const SewModel *m = d->model;
    s->d = d;
    s->model = m;
    s->log = log;
    s->env = env;
    s->instance = malloc(strlen(instance ? instance : "?") + 1);
    if (s->instance)
        strcpy(s->instance, instance ? instance : "?");
    s->p = zeroed((size_t)d->n_params, sizeof(double));
    s->u = zeroed((size_t)d->n_inputs, sizeof(double));
    s->u_now = zeroed((size_t)d->n_inputs, sizeof(double));
    s->derived = zeroed((size_t)m->n_derived, sizeof(double));
    s->state = zeroed((size_t)m->n_state, sizeof(double));
    s->saved_state = zeroed((size_t)m->n_state, sizeof(double));
    s->scratch_state = zeroed((size_t)m->n_state, sizeof(double));
    s->row = zeroed((size_t)d->n_row, sizeof(double));
    s->fresh = zeroed((size_t)d->n_inputs, 1);
    s->held = zeroed((size_t)d->n_inputs, 1);
    for (int i = 0; i < d->n_variables; i++)
        if (d->variables[i].vr + 1 > s->n_vr)
            s->n_vr = d->variables[i].vr + 1;
    s->by_vr = malloc((s->n_vr > 0 ? s->n_vr : 1) * sizeof(int));
    if (!s->instance || !s->p || !s->u || !s->u_now || !s->derived || !s->state
        || !s->saved_state || !s->scratch_state || !s->row || !s->fresh || !s->held || !s->by_vr) {
        sew_free(s);
        return NULL;
    }
    for (unsigned int vr = 0; vr < s->n_vr; vr++)
        s->by_vr[vr] = -1;
    for (int i = 0; i < d->n_variables; i++)
        s->by_vr[d->variables[i].vr] = i;
    sew_reset(s);
    return s;
}

void sew_free(SewSlave *s)
{
    if (!s)
        return;
    free(s->instance);
    free(s->p);
    free(s->u);
    free(s->u_now);
    free(s->derived);
    free(s->state);
    free(s->saved_state);
    free(s->scratch_state);
    free(s->row);
    free(s->fresh);
    free(s->held);
    free(s->by_vr);
    free(s);
}

void sew_reset(SewSlave *s)
{
    const SewDescription *d = s->d;
    for (int i = 0; i < d->n_variables; i++) {
        const SewVariable *v = &d->variables[i];
        if (v->causality == SEW_PARAMETER)
            s->p[v->index] = v->start;
        else if (v->causality == SEW_INPUT)
            s->u[v->index] = v->start;
    }
    memset(s->fresh, 0, (size_t)d->n_inputs);
    memset(s->held, 0, (size_t)d->n_inputs);
    memset(s->state, 0, (size_t)s->model->n_state * sizeof(double));
    s->held_stale = 1;
    s->any_fresh = 0;
    s->built = 0;
    s->cached = 0;
    s->cache_failed = 0;
    s->initialized = 0;
    s->phase = SEW_INSTANTIATED;
    s->time = 0.0;
    s->elapsed = 0.0;
    s->broken[0] = '\0';
    s->last_error[0] = '\0';
}

const SewVariable *sew_variable(const SewSlave *s, unsigned int vr)
{
    if (vr >= s->n_vr || s->by_vr[vr] < 0)
        return NULL;
    return &s->d->variables[s->by_vr[vr]];
}

/* --- the inputs as the model takes them ------------------------------------------------------ */

/* Which rates act as zero, from what the host set since the last step: slave.py's
   _note_held_rates (a rate not set since its value was set, or the value's own rate was held) */
static void note_held_rates(SewSlave *s)
{
    const SewDescription *d = s->d;
    for (int c = 0; c < d->n_chains; c++) {
        const int *chain = d->chains[c];
        for (int k = 0; k < 2 && chain[k + 1] >= 0; k++) {
            int value = chain[k], rate = chain[k + 1];
            if (s->fresh[rate])
                s->held[rate] = 0;
            else if (s->fresh[value] || s->held[value])
                s->held[rate] = 1;
        }
    }
    s->held_stale = 0;
}

/* slave.py's held_inputs, into u_now */
static void held_inputs(SewSlave *s)
{
    int n = s->d->n_inputs;
    if (s->held_stale)
        note_held_rates(s);
    for (int i = 0; i < n; i++)
        s->u_now[i] = s->held[i] ? 0.0 : s->u[i];
}

const double *sew_extrapolated_inputs(SewSlave *s, double dt)
{
    double *u = s->u_now;
    held_inputs(s);
    if (dt == 0.0)
        return u;
    /* slave.extrapolated_inputs: the terms dt^j / j! as (((1 * dt/1) * dt/2) ...), each sum
       from 0.0 in the order of the chain; a chain of two as slave._taylor's loop */
    double t1 = 1.0 * (dt / 1);
    double t2 = t1 * (dt / 2);
    for (int c = 0; c < s->d->n_chains; c++) {
        const int *chain = s->d->chains[c];
        if (chain[2] >= 0) {
            double x0 = u[chain[0]], x1 = u[chain[1]], x2 = u[chain[2]];
            u[chain[0]] = 0.0 + x0 * 1.0 + x1 * t1 + x2 * t2;
            u[chain[1]] = 0.0 + x1 * 1.0 + x2 * t1;
        } else {
            double x0 = u[chain[0]], x1 = u[chain[1]];
            double total = 0.0, term = 1.0;
            total += x0 * term;
            term *= dt / 1;
            total += x1 * term;
            u[chain[0]] = total;
        }
    }
    return u;
}

/* --- the model --------------------------------------------------------------------------------- */

/* The constants of the current parameters (built once); 0, or -1 with the reason in s->why. */
static int ensure_built(SewSlave *s)
{
    if (s->built)
        return 0;
    s->why[0] = '\0';
    if (s->model->build(s->p, s->derived, s->why) != 0) {
        if (!s->why[0])
            snprintf(s->why, sizeof s->why, "the parameters do not make a model");
        return -1;
    }
    s->built = 1;
    return 0;
}

/* The outputs now into s->row (kept until an input, a parameter, the time or the state
   changes); -1 where the model cannot give them: NaN, with an Error line saying why. */
static int fill_row(SewSlave *s)
{
    if (s->cached)
        return s->cache_failed ? -1 : 0;
    const SewDescription *d = s->d;
    const SewModel *m = s->model;
    char message[2 * SEW_WHY];
    int failed = ensure_built(s) != 0;
    if (!failed) {
        const double *state = s->state;
        if (!s->initialized && m->n_state > 0) {
            /* before initialization ends: the state initialization would give now */
            held_inputs(s);
            m->initialize(s->p, s->derived, s->u_now, s->scratch_state);
            state = s->scratch_state;
        }
        const double *u = sew_extrapolated_inputs(s, s->elapsed);
        s->why[0] = '\0';
        failed = m->outputs(s->p, s->derived, state, u, s->time, s->row, s->why) != 0;
    }
    if (failed) {
        snprintf(message, sizeof message, "outputs unavailable: %s", s->why);
        error_once(s, message, message);
        for (int i = 0; i < d->n_row; i++)
            s->row[i] = NAN;
    } else {
        for (int i = 0; i < d->n_variables; i++) {
            const SewVariable *v = &d->variables[i];
            if ((v->causality == SEW_OUTPUT || v->causality == SEW_CALCULATED)
                && !isfinite(s->row[v->index])) {
                char key[SEW_WHY];
                snprintf(key, sizeof key, "output %s is %g", v->name, s->row[v->index]);
                snprintf(message, sizeof message, "output %s is %g at t = %g s: the model has "
                         "left the range where it computes (inputs or parameters too large?)",
                         v->name, s->row[v->index], s->time);
                error_once(s, key, message);
                failed = 1;
                break;
            }
        }
    }
    s->cached = 1;
    s->cache_failed = failed;
    return failed ? -1 : 0;
}

/* --- get and set ------------------------------------------------------------------------------ */

static const char *kind_name(SewKind kind)
{
    return kind == SEW_INTEGER ? "Integer" : kind == SEW_BOOLEAN ? "Boolean" : "Real";
}

SewStatus sew_no_such_kind(SewSlave *s, const char *call, const unsigned int *vr, size_t n)
{
    if (n == 0)
        return SEW_OK;
    if (!vr)
        return sew_refuse(s, "%s: no value references given", call);
    return sew_refuse(s, "%s: no such variable (value reference %u): this FMU has no variable "
                      "of that type", call, vr[0]);
}

SewStatus sew_get(SewSlave *s, const char *call, SewKind kind, const unsigned int *vr, size_t n,
                  double *values)
{
    int needs_row = 0;
    if (n > 0 && (!vr || !values))
        return sew_refuse(s, "%s: no array given for %lu values", call, (unsigned long)n);
    for (size_t i = 0; i < n; i++) {
        const SewVariable *v = sew_variable(s, vr[i]);
        if (!v || v->kind != kind)
            return sew_refuse(s, "%s: no such variable (value reference %u)%s", call, vr[i],
                              v ? "; it is not of this type" : "");
        needs_row |= v->causality == SEW_OUTPUT || v->causality == SEW_CALCULATED;
    }
    int row_failed = needs_row ? fill_row(s) != 0 : 0;
    for (size_t i = 0; i < n; i++) {
        const SewVariable *v = sew_variable(s, vr[i]);
        switch (v->causality) {
        case SEW_PARAMETER: values[i] = s->p[v->index]; break;
        case SEW_INPUT: values[i] = s->u[v->index]; break;
        case SEW_INDEPENDENT: values[i] = s->time; break;
        default: values[i] = s->row[v->index]; break;
        }
    }
    return row_failed ? SEW_ERROR : SEW_OK;
}

/* why the value x cannot be set to the variable v, into why; 0 if it can */
static int refusal_of_set(const SewSlave *s, const SewVariable *v, double x, char *why)
{
    if (v->causality == SEW_OUTPUT || v->causality == SEW_CALCULATED
        || v->causality == SEW_INDEPENDENT) {
        snprintf(why, SEW_WHY, "%s is %s: it cannot be set (value %.17g ignored)", v->name,
                 v->causality == SEW_OUTPUT ? "an output"
                 : v->causality == SEW_CALCULATED ? "a calculated parameter"
                                                  : "the independent variable",
                 x);
        return -1;
    }
    if (v->causality == SEW_PARAMETER && s->phase >= SEW_STEPPING) {
        /* variability "fixed": FMI forbids it after initialization */
        snprintf(why, SEW_WHY, "parameter %s is fixed: it cannot change after "
                 "exitInitializationMode (value %.17g ignored)", v->name, x);
        return -1;
    }
    if (!isfinite(x)) {
        snprintf(why, SEW_WHY, "%s %s = %g refused: not a finite number",
                 v->causality == SEW_PARAMETER ? "parameter" : "input", v->name, x);
        return -1;
    }
    if (v->kind == SEW_INTEGER && x != floor(x)) {
        snprintf(why, SEW_WHY, "%s = %.17g refused: not a whole number", v->name, x);
        return -1;
    }
    if (!(x >= v->min && x <= v->max)) {
        const char *gap = v->unit[0] ? " " : "";
        int n = snprintf(why, SEW_WHY, "%s %s = %.6g%s%s is outside its range [%g, %g]%s%s: "
                         "refused", v->causality == SEW_PARAMETER ? "parameter" : "input",
                         v->name, x, gap, v->unit, v->min, v->max, gap, v->unit);
        /* an input beyond its range in a run is what the Python FMU's refusal says it is */
        if (v->causality == SEW_INPUT && n > 0 && n < SEW_WHY)
            snprintf(why + n, (size_t)(SEW_WHY - n), " (set at t = %g s: a co-simulation that "
                     "diverges, or a value in another unit)", s->time);
        return -1;
    }
    return 0;
}

SewStatus sew_set(SewSlave *s, const char *call, SewKind kind, const unsigned int *vr, size_t n,
                  const double *values)
{
    char why[SEW_WHY];
    if (n > 0 && (!vr || !values))
        return sew_refuse(s, "%s: no array given for %lu values", call, (unsigned long)n);
    if (n > 0 && s->phase == SEW_TERMINATED)
        return sew_refuse(s, "%s: the instance is terminated: nothing can be set", call);
    /* all or nothing: every value is checked before any is taken */
    for (size_t i = 0; i < n; i++) {
        const SewVariable *v = sew_variable(s, vr[i]);
        if (!v)
            return sew_refuse(s, "%s: no such variable (value reference %u, value %.17g "
                              "ignored)", call, vr[i], values[i]);
        if (v->kind != kind)
            return sew_refuse(s, "%s: %s is not a%s %s variable (value %.17g ignored)", call,
                              v->name, kind == SEW_INTEGER ? "n" : "", kind_name(kind),
                              values[i]);
        if (refusal_of_set(s, v, values[i], why) != 0)
            return sew_refuse(s, "%s: %s", call, why);
    }
    for (size_t i = 0; i < n; i++) {
        const SewVariable *v = sew_variable(s, vr[i]);
        if (v->causality == SEW_PARAMETER) {
            if (s->p[v->index] != values[i])
                s->built = 0;     /* rebuilt (and checked) with the new value when next needed */
            s->p[v->index] = values[i];
        } else {
            s->u[v->index] = values[i];
            s->fresh[v->index] = 1;
            s->any_fresh = 1;
            s->held_stale = 1;
            s->elapsed = 0.0;
        }
    }
    if (n > 0)
        s->cached = 0;
    return SEW_OK;
}

/* --- the life of an instance ------------------------------------------------------------------ */

const char *const SEW_LOG_CATEGORIES[] = {
    "logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal", "logAll", NULL,
};

SewStatus sew_check_categories(SewSlave *s, const char *call, size_t n,
                               const char *const categories[])
{
    char names[256] = "";
    if (n > 0 && !categories)
        return sew_refuse(s, "%s: no categories given", call);
    for (size_t i = 0; i < n; i++) {
        int known = 0;
        for (int k = 0; categories[i] && SEW_LOG_CATEGORIES[k]; k++)
            known |= strcmp(categories[i], SEW_LOG_CATEGORIES[k]) == 0;
        if (known)
            continue;
        for (int k = 0; SEW_LOG_CATEGORIES[k]; k++) {
            if (k > 0)
                strncat(names, ", ", sizeof names - strlen(names) - 1);
            strncat(names, SEW_LOG_CATEGORIES[k], sizeof names - strlen(names) - 1);
        }
        /* the category, the host's text, goes through emit like every line: '%' in words */
        return sew_refuse(s, "%s: unknown log category %s%.200s%s (known: %s); logging left as "
                          "it was", call, categories[i] ? "'" : "",
                          categories[i] ? categories[i] : "NULL", categories[i] ? "'" : "", names);
    }
    return SEW_OK;
}

SewStatus sew_check_start_time(SewSlave *s, const char *call, double start_time)
{
    if (!isfinite(start_time))
        return sew_refuse(s, "%s: the start time must be finite, got %g", call, start_time);
    if (s->model->from_time_zero && start_time < 0.0)
        return sew_refuse(s, "%s: start time %g s refused: %s's model is a function of the "
                          "time since its start at t = 0, defined for t >= 0 only (start at 0 "
                          "or later)", call, start_time,
                          model_name(s));
    return SEW_OK;
}

SewStatus sew_enter_initialization(SewSlave *s, const char *call, double start_time)
{
    if (s->phase != SEW_INSTANTIATED)
        return sew_refuse(s, "%s: only once, after instantiation (or a reset)", call);
    if (sew_check_start_time(s, call, start_time) != SEW_OK)
        return SEW_ERROR;
    s->time = start_time;
    s->phase = SEW_INITIALIZING;
    s->cached = 0;
    return SEW_OK;
}

SewStatus sew_exit_initialization(SewSlave *s, const char *call)
{
    if (s->phase != SEW_INITIALIZING)
        return sew_refuse(s, "%s: called outside initialization mode", call);
    s->phase = SEW_STEPPING;
    s->initialized = 1;
    s->cached = 0;
    if (ensure_built(s) != 0) {
        snprintf(s->broken, sizeof s->broken, "%s", s->why);
        return sew_refuse(s, "%s; every doStep of this instance will be refused", s->broken);
    }
    if (s->model->n_state > 0) {
        held_inputs(s);
        s->model->initialize(s->p, s->derived, s->u_now, s->state);
    }
    return SEW_OK;
}

SewStatus sew_terminate(SewSlave *s, const char *call)
{
    if (s->phase != SEW_STEPPING)
        return sew_refuse(s, "%s: called outside step mode", call);
    s->phase = SEW_TERMINATED;
    return SEW_OK;
}

/* why a doStep(t, h) cannot be taken at all (into s->why), or 0 */
static int refusal_of_step(SewSlave *s, double t, double h)
{
    if (s->phase == SEW_TERMINATED)
        snprintf(s->why, sizeof s->why, "the instance is terminated");
    else if (!s->initialized || s->phase != SEW_STEPPING)
        snprintf(s->why, sizeof s->why, "called before exitInitializationMode");
    else if (s->broken[0])
        snprintf(s->why, sizeof s->why, "%s", s->broken);
    else if (!(isfinite(h) && h > 0.0))
        snprintf(s->why, sizeof s->why, "the step size must be positive and finite, got %.17g",
                 h);
    else if (!(isfinite(t) && fabs(t - s->time)
               <= SEW_TIME_TOLERANCE * fmax(fmax(1.0, fabs(t)), h)))
        snprintf(s->why, sizeof s->why, "the step starts at t = %.17g s, but the last one ended "
                 "at t = %.17g s", t, s->time);
    else
        return 0;
    return -1;
}

SewStatus sew_do_step(SewSlave *s, const char *call, double t, double h)
{
    const SewModel *m = s->model;
    int n_state = m->n_state;
    if (refusal_of_step(s, t, h) != 0)
        return sew_refuse(s, "%s(%g, %g) refused: %s", call, t, h, s->why);
    double saved_elapsed = s->elapsed, saved_time = s->time;
    if (n_state > 0)
        memcpy(s->saved_state, s->state, (size_t)n_state * sizeof(double));
    if (s->held_stale)
        note_held_rates(s);      /* which rates act as zero, from what was set */
    /* the model of parameters a restored state brought: built (and checked) now */
    int failed = ensure_built(s) != 0;
    if (!failed && m->advance) {
        const double *u = sew_extrapolated_inputs(s, s->elapsed);
        s->why[0] = '\0';
        failed = m->advance(s->p, s->derived, s->state, u, t, h, s->why) != 0;
        if (failed && !s->why[0])
            snprintf(s->why, sizeof s->why, "the model could not take the step");
    }
    if (!failed) {
        s->time = t + h;
        s->elapsed += h;
        /* a state that is no longer finite is not a state: the step is not taken */
        for (int i = 0; i < n_state; i++)
            if (!isfinite(s->state[i])) {
                snprintf(s->why, sizeof s->why, "the internal state's element %d would be %g "
                         "at t = %g s: the model has left the range where it computes (inputs "
                         "or parameters too large?)", i, s->state[i], t + h);
                failed = 1;
                break;
            }
    }
    s->cached = 0;
    if (failed) {
        s->elapsed = saved_elapsed;
        s->time = saved_time;
        if (n_state > 0)
            memcpy(s->state, s->saved_state, (size_t)n_state * sizeof(double));
        sew_log(s, SEW_DISCARD, "%s(%g, %g) discarded: %s", call, t, h, s->why);
        return SEW_DISCARD;
    }
    if (s->any_fresh) {
        int any_held = 0;
        memset(s->fresh, 0, (size_t)s->d->n_inputs);
        s->any_fresh = 0;
        for (int i = 0; i < s->d->n_inputs; i++)
            any_held |= s->held[i];
        s->held_stale = any_held;     /* (a rate set alone may now be held) */
    }
    return SEW_OK;
}
