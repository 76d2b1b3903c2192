/* The fixed-step Jacobi master's step loop, compiled: the C twin of master.py's
 * Master._fixed_steps with algorithms/fixed_step.py's Jacobi.advance and exchange,
 * instances.py's Instance.exchange and recorder.py's Recorder._record_at_once, for runs whose
 * every instance is a native sewfmu FMU (plain C function pointers; no Python inside a call).
 *
 * It lives here, beside its Python twins, not under native/: it is the host's code, never part
 * of an FMU, and native/'s sources make the native FMUs' version (native_current.py).
 * scenarios/cosim/stepper.py compiles it on first use into sewfmu's cache folder, decides which
 * runs it may take, fills the tables below and calls it in chunks; between two chunks the
 * Python loop does what a user notices (Ctrl-C, close() from another thread, progress).
 *
 * The same FMI calls in the same order with the same arguments as the Python loop, the same
 * arithmetic (t = k * h; a * x + b of a converted input; no fused multiply-add), the guardian's
 * board written as the Python loop writes it (a beat and the time per step, the instance and
 * call before each call), and the rows the Python recorder would write. It stops at the first
 * status worse than Warning or output not finite, saying which instance and call, so that
 * Python raises the error it raises today; and before a row the recorder has no room for. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#if defined(_WIN32)
#define SEW_EXPORT __declspec(dllexport)
#else
#define SEW_EXPORT __attribute__((visibility("default")))
#endif

/* the call under way, as guardian.CODE numbers it (WHERE = slot * 32 + code) */
enum { CALL_DO_STEP = 1, CALL_SET_INPUTS = 2, CALL_GET_OUTPUTS = 3, CALL_GET_BOOLEANS = 13 };
/* why a chunk ended (stepper.py's names) */
enum { STEPS_DONE = 0, CALL_FAILED = 1, NOT_FINITE = 2, ROW_NEEDS_PYTHON = 3 };
#define WARNING_LEVEL 1     /* fmi2Warning, fmi3Warning: the worst status a run goes on after */

typedef void (*sew_function)(void);      /* any of the FMU's functions, as passed in */
typedef int (*do_step2)(void *, double, double, int);
typedef int (*do_step3)(void *, double, double, bool, bool *, bool *, bool *, double *);
typedef int (*values2)(void *, const uint32_t *, size_t, void *);
typedef int (*values3)(void *, const uint32_t *, size_t, void *, size_t);

/* One instance, as stepper.py's SewInstance lays it out (every field 8 bytes wide). */
typedef struct {
    int64_t fmi;                /* 2 or 3 */
    int64_t no_set_prior;       /* doStep's noSetFMUStatePriorToCurrentCommunicationPoint */
    int64_t where;              /* slot * 32: this instance's share of the board's WHERE */
    void *component;
    sew_function do_step, set_real, get_real, get_boolean;
    /* FMI 3.0 doStep's results: event handling needed, terminate, early return, last time */
    bool *event, *terminate, *early;
    double *last_time;
    int64_t n_in;
    const uint32_t *in_vr;
    double *in_buf;
    const double *const *in_src;     /* the source output each input takes */
    const double *in_a, *in_b;       /* a * x + b per input (instances.py's in_scales), or NULL */
    int64_t n_out;
    const uint32_t *out_vr;
    double *out_buf;
    int64_t n_bool;
    const uint32_t *bool_vr;
    void *bool_buf;
} SewInstance;

/* The run, as stepper.py's SewRun lays it out. */
typedef struct {
    int64_t n_inst;
    SewInstance *inst;
    double h, stop;
    int64_t n, every, dense_k;
    int64_t *beat;              /* the board's BEAT, T and the instances' WHERE */
    double *now;
    int64_t *where;
    /* the recorder: times[rows_cap], reals[rows_cap][n_reals] from outputs, and per flagged
     * instance its rows of flag_bytes bytes from its Boolean buffer */
    double *times, *reals;
    const double *outputs;
    int64_t n_reals, rows_cap, n_flags;
    char *const *flag_rows;
    const char *const *flag_now;
    const int64_t *flag_bytes;
    /* in and out: the steps done, the rows recorded; out: the failed instance, call, status */
    int64_t k, length;
    int64_t failed_inst, failed_call, failed_status;
} SewRun;

static int failed(SewRun *r, int64_t i, int64_t call, int status)
{
    r->failed_inst = i;
    r->failed_call = call;
    r->failed_status = status;
    return CALL_FAILED;
}

static int do_step(SewInstance *s, double t, double h)
{
    if (s->fmi == 3)
        return ((do_step3)s->do_step)(s->component, t, h, s->no_set_prior != 0, s->event,
                                      s->terminate, s->early, s->last_time);
    return ((do_step2)s->do_step)(s->component, t, h, (int)s->no_set_prior);
}

static int values(const SewInstance *s, sew_function call, const uint32_t *vr, int64_t n, void *buf)
{
    if (s->fmi == 3)
        return ((values3)call)(s->component, vr, (size_t)n, buf, (size_t)n);
    return ((values2)call)(s->component, vr, (size_t)n, buf);
}

/* Instance.exchange: inputs from their sources, set; outputs got and checked; flags got. */
static int exchange(SewRun *r, int64_t i)
{
    SewInstance *s = &r->inst[i];
    int status;
    if (s->n_in) {
        for (int64_t j = 0; j < s->n_in; j++)
            s->in_buf[j] = s->in_a ? s->in_a[j] * *s->in_src[j] + s->in_b[j] : *s->in_src[j];
        *r->where = s->where + CALL_SET_INPUTS;
        status = values(s, s->set_real, s->in_vr, s->n_in, s->in_buf);
        if (status > WARNING_LEVEL)
            return failed(r, i, CALL_SET_INPUTS, status);
    }
    if (s->n_out) {
        *r->where = s->where + CALL_GET_OUTPUTS;
        status = values(s, s->get_real, s->out_vr, s->n_out, s->out_buf);
        if (status > WARNING_LEVEL)
            return failed(r, i, CALL_GET_OUTPUTS, status);
        /* a NaN or infinite output stops the run (Python: a sum not finite, then the output
         * that is not: a sum that overflows from finite outputs goes on, as here) */
        for (int64_t j = 0; j < s->n_out; j++) {
            if (!isfinite(s->out_buf[j])) {
                r->failed_inst = i;
                return NOT_FINITE;
            }
        }
    }
    if (s->n_bool) {
        status = values(s, s->get_boolean, s->bool_vr, s->n_bool, s->bool_buf);
        if (status > WARNING_LEVEL)
            return failed(r, i, CALL_GET_BOOLEANS, status);
    }
    return STEPS_DONE;
}

static void record(SewRun *r, double t)
{
    int64_t row = r->length;
    r->times[row] = t;
    memcpy(r->reals + row * r->n_reals, r->outputs, (size_t)r->n_reals * sizeof(double));
    for (int64_t f = 0; f < r->n_flags; f++)
        memcpy(r->flag_rows[f] + row * r->flag_bytes[f], r->flag_now[f],
               (size_t)r->flag_bytes[f]);
    r->length = row + 1;
}

/* Steps from r->k up to `end` (at most r->n). Returns STEPS_DONE; CALL_FAILED or NOT_FINITE
 * with r->k the step that failed (failed_inst, failed_call, failed_status say where); or
 * ROW_NEEDS_PYTHON with r->k the step just taken, whose row the recorder has no room for. */
SEW_EXPORT int sew_jacobi_steps(SewRun *r, int64_t end)
{
    const double h = r->h;
    int64_t k = r->k;
    while (k < end) {
        double t = (double)k * h;
        *r->beat += 1;
        *r->now = t;
        for (int64_t i = 0; i < r->n_inst; i++) {
            SewInstance *s = &r->inst[i];
            *r->where = s->where + CALL_DO_STEP;
            int status = do_step(s, t, h);
            if (status > WARNING_LEVEL)
                return failed(r, i, CALL_DO_STEP, status);
        }
        for (int64_t i = 0; i < r->n_inst; i++) {
            int why = exchange(r, i);
            if (why != STEPS_DONE)
                return why;
        }
        k += 1;
        r->k = k;
        /* n even steps of h end exactly at the stop time */
        t = k == r->n ? r->stop : (double)k * h;
        if (k % r->every == 0 || k >= r->dense_k || k == r->n) {
            if (r->length >= r->rows_cap)
                return ROW_NEEDS_PYTHON;
            record(r, t);
        }
    }
    return STEPS_DONE;
}
