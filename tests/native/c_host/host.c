/* A small FMI 2.0 / 3.0 co-simulation host in C with no Python in it (see host.h).

   host DIR [--start T] [--stop T] [--step H] [--set VR[:k]=V]... [--out VR[:k],...]
            [--probe NAME [ARG]] [--phase instantiated|initializing|stepping]

   DIR is an unzipped FMU; k is r (Real/Float64, the default), i (Integer/Int32) or b (Boolean).
   Start, stop and step default to the DefaultExperiment. Without --probe it runs the experiment
   with fmpy's own communication points (so that its rows line up with fmpy's simulate_fmu) and
   prints "time,<vr>..." then one row per communication point, %.17g. The FMU's log goes to
   stderr; any status but OK ends the run with one line on stderr and exit status 1.

   --probe runs one refusal and prints "<probe> <FMI call> <status>" per call to stdout:
     unknown-vr VR     set and get a value reference the FMU does not have
     out-of-range VR=V set a value outside the declared range
     nan VR, inf VR    set NaN, +infinity
     set-output VR     set an output
     garbled-state V   serialize the state halfway, garble it, deserialize it; V: all (every
                       byte inverted), header, middle, last (one byte inverted), truncated
     state-roundtrip   halfway get and serialize the state, run to the end (printed as the
                       plain run), set the state back and run again, deserialize and run again:
                       the three ends must be equal to the bit (exit 1 if not)
   The probe's call happens in --phase (stepping: after initialization, the default). */
#ifndef _WIN32
#define _XOPEN_SOURCE 700  /* realpath; before any system header */
#endif

#include "host.h"

#ifndef _WIN32
#include <dlfcn.h>
#else
#include <fcntl.h>
#include <io.h>
#include <windows.h>
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#define SEP "\\"
#else
#define SEP "/"
#endif

const char *host_status_name(int status)
{
    static const char *const names[] = {"OK", "Warning", "Discard", "Error", "Fatal", "Pending"};
    return status >= 0 && status <= 5 ? names[status] : "?";
}

static int fail_usage(const char *what, const char *detail)
{
    fprintf(stderr, "host: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    return 2;
}

/* the one line a non-OK status prints; exit status 1 */
static int fail_call(const Host *h, int status, double t)
{
    fprintf(stderr, "host: %s returned %d (%s) at t=%.17g\n", h->call ? h->call : "?", status,
            host_status_name(status), t);
    return 1;
}

/* ---- modelDescription.xml: the few attributes the host needs, found by their names ---- */

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *text;
    long n;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = malloc((size_t)n + 1);
    if (text && fread(text, 1, (size_t)n, f) != (size_t)n) {
        free(text);
        text = NULL;
    }
    if (text) text[n] = '\0';
    fclose(f);
    return text;
}

/* the value of attribute `name` inside the element starting at `element` (up to its '>') */
static int attribute(const char *element, const char *name, char *out, size_t size)
{
    const char *end = strchr(element, '>');
    char pattern[64];
    const char *at = element, *q;
    snprintf(pattern, sizeof pattern, " %s=\"", name);
    while ((at = strstr(at, pattern)) != NULL && (!end || at < end)) {
        at += strlen(pattern);
        q = strchr(at, '"');
        if (!q || (size_t)(q - at) >= size) return -1;
        memcpy(out, at, (size_t)(q - at));
        out[q - at] = '\0';
        /* a prefix match of another attribute ("xstartTime") cannot occur: the pattern
           starts with a space */
        return 0;
    }
    return -1;
}

static int read_description(Host *h)
{
    char path[HOST_TEXT], value[HOST_TEXT];
    char *xml, *root, *cs, *experiment;
    snprintf(path, sizeof path, "%s" SEP "modelDescription.xml", h->dir);
    xml = read_text(path);
    if (!xml) return fail_usage("cannot read", path);
    root = strstr(xml, "<fmiModelDescription");
    cs = strstr(xml, "<CoSimulation");
    if (!root || !cs || attribute(root, "fmiVersion", value, sizeof value) != 0) {
        free(xml);
        return fail_usage("not a co-simulation FMU", path);
    }
    h->fmi = value[0] == '3' ? 3 : 2;
    if (attribute(root, h->fmi == 3 ? "instantiationToken" : "guid", h->token,
                  sizeof h->token) != 0
        || attribute(cs, "modelIdentifier", h->model_identifier,
                     sizeof h->model_identifier) != 0) {
        free(xml);
        return fail_usage("no token or modelIdentifier in", path);
    }
    experiment = strstr(xml, "<DefaultExperiment");
    if (experiment) {
        if (isnan(h->start) && attribute(experiment, "startTime", value, sizeof value) == 0)
            h->start = strtod(value, NULL);
        if (isnan(h->stop) && attribute(experiment, "stopTime", value, sizeof value) == 0)
            h->stop = strtod(value, NULL);
        if (isnan(h->step) && attribute(experiment, "stepSize", value, sizeof value) == 0)
            h->step = strtod(value, NULL);
    }
    free(xml);
    if (isnan(h->start)) h->start = 0.0;
    if (isnan(h->stop) || isnan(h->step) || !(h->step > 0.0))
        return fail_usage("no stop time or step size", "give --stop and --step");
    return 0;
}

/* ---- the binary and its resources ---- */

HostFunction host_symbol(Host *h, const char *name)
{
#ifdef _WIN32
    return (HostFunction)GetProcAddress((HMODULE)h->lib, name);
#else
    /* dlsym gives an object pointer; POSIX guarantees it converts to a function pointer */
    void *p = dlsym(h->lib, name);
    HostFunction f;
    memcpy(&f, &p, sizeof f);
    return f;
#endif
}

/* `uri` as a file URI of the absolute path `path`, percent-encoding what a URI may not hold */
static void file_uri(const char *path, char *uri, size_t size)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t n = (size_t)snprintf(uri, size, "file://%s", path[0] == '/' ? "" : "/");
    for (; *path && n + 4 < size; ++path) {
        unsigned char c = (unsigned char)*path;
        if (c == '\\') c = '/';
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')
            || strchr("/:-._~", c)) {
            uri[n++] = (char)c;
        } else {
            uri[n++] = '%';
            uri[n++] = hex[c >> 4];
            uri[n++] = hex[c & 15];
        }
    }
    uri[n] = '\0';
}

static int load(Host *h)
{
    /* room for the folder, absolute, and what is appended to it */
    char absolute[HOST_TEXT], path[HOST_TEXT + HOST_NAME + 64], resources[HOST_TEXT + 16];
    const char *platform;
#ifdef _WIN32
    platform = h->fmi == 3 ? "x86_64-windows" : "win64";
    if (!_fullpath(absolute, h->dir, sizeof absolute)) return fail_usage("no such FMU", h->dir);
    snprintf(path, sizeof path, "%s\\binaries\\%s\\%s.dll", absolute, platform,
             h->model_identifier);
    /* the DLL's own folder first when it looks for what it imports */
    h->lib = LoadLibraryExA(path, NULL, LOAD_WITH_ALTERED_SEARCH_PATH);
    if (!h->lib) {
        char code[32];
        snprintf(code, sizeof code, "%s (error %lu)", path, (unsigned long)GetLastError());
        return fail_usage("cannot load", code);
    }
#else
    platform = h->fmi == 3 ? "x86_64-linux" : "linux64";
    if (!realpath(h->dir, absolute)) return fail_usage("no such FMU", h->dir);
    snprintf(path, sizeof path, "%s/binaries/%s/%s.so", absolute, platform, h->model_identifier);
    h->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h->lib) return fail_usage("cannot load", dlerror());
#endif
    snprintf(resources, sizeof resources, "%s" SEP "resources", absolute);
    if (h->fmi == 3)
        snprintf(h->resources, sizeof h->resources, "%s" SEP, resources);
    else
        file_uri(resources, h->resources, sizeof h->resources);
    h->ops = h->fmi == 3 ? &HOST_FMI3 : &HOST_FMI2;
    if (h->ops->bind(h) != 0) return fail_usage("an FMI function is missing from", path);
    return 0;
}

/* ---- the command line ---- */

/* "vr", "vr:k", with "=value" where `with_value` */
static int parse_var(const char *text, int with_value, HostVar *v)
{
    char *end;
    unsigned long vr = strtoul(text, &end, 10);
    if (end == text) return -1;
    v->vr = (unsigned int)vr;
    v->kind = HOST_REAL;
    v->value = 0.0;
    if (*end == ':') {
        if (end[1] == 'i') v->kind = HOST_INT;
        else if (end[1] == 'b') v->kind = HOST_BOOL;
        else if (end[1] != 'r') return -1;
        end += 2;
    }
    if (with_value) {
        if (*end != '=') return -1;
        text = end + 1;
        v->value = strtod(text, &end);
        if (end == text) return -1;
    }
    return *end == '\0' ? 0 : -1;
}

static int parse_outs(Host *h, const char *list)
{
    char item[64];
    while (*list) {
        size_t n = strcspn(list, ",");
        if (n >= sizeof item || h->n_outs >= HOST_MAX_VARS) return -1;
        memcpy(item, list, n);
        item[n] = '\0';
        if (parse_var(item, 0, &h->outs[h->n_outs++]) != 0) return -1;
        list += n + (list[n] == ',');
    }
    return 0;
}

/* ---- the run ---- */

typedef enum { PHASE_INSTANTIATED, PHASE_INITIALIZING, PHASE_STEPPING } Phase;

/* math.isclose's default, as fmpy's loop decides its points with it */
static int isclose(double a, double b)
{
    return fabs(a - b) <= 1e-9 * fmax(fabs(a), fabs(b));
}

/* the outputs now: into row (if not NULL) and as a CSV line to out (if not NULL) */
static int sample(Host *h, double t, double *row, FILE *out)
{
    int i, status;
    double value;
    if (out) fprintf(out, "%.17g", t);
    for (i = 0; i < h->n_outs; ++i) {
        status = h->ops->get(h, &h->outs[i], &value);
        if (status != 0) return status;
        if (row) row[i] = value;
        if (out) fprintf(out, ",%.17g", value);
    }
    if (out) fputc('\n', out);
    return 0;
}

/* Step from communication point n (time *t) to the stop time, or `limit` steps if limit >= 0,
   as fmpy's simulateCS does: the points are start + k * step, the last one the stop time.
   The rows go to rows (n_outs doubles each, room for all) and out. */
static int run(Host *h, long *n, double *t, long limit, double *rows, FILE *out)
{
    long taken = 0;
    int status;
    while (!(*t > h->stop || isclose(*t, h->stop)) && (limit < 0 || taken < limit)) {
        double next = h->start + (double)(*n + 1) * h->step;
        if (next > h->stop && !isclose(next, h->stop)) next = h->stop;
        status = h->ops->do_step(h, *t, next - *t);
        if (status != 0) return fail_call(h, status, *t);
        *t = next;
        if (isclose(*t, h->start + (double)(*n + 1) * h->step)) ++*n;
        status = sample(h, *t, rows ? rows + taken * h->n_outs : NULL, out);
        if (status != 0) return fail_call(h, status, *t);
        ++taken;
    }
    return 0;
}

static long points(const Host *h)
{
    return (long)ceil((h->stop - h->start) / h->step * (1.0 - 1e-12)) + 1;
}

static void header(const Host *h)
{
    int i;
    printf("time");
    for (i = 0; i < h->n_outs; ++i) printf(",%u", h->outs[i].vr);
    printf("\n");
}

/* the state halfway (get, serialize), then three runs from it that must end alike */
static int state_roundtrip(Host *h, long n, double t)
{
    const long rest = points(h);
    const size_t row_bytes = (size_t)h->n_outs * sizeof(double);
    double *ends[3];
    unsigned char *bytes = NULL;
    size_t size = 0;
    void *state = NULL;
    long n_run, counts[3];
    double t_run;
    int k, status;
    if ((status = h->ops->get_state(h, &state)) != 0
        || (status = h->ops->serialize(h, state, &bytes, &size)) != 0)
        return fail_call(h, status, t);
    for (k = 0; k < 3; ++k) {
        ends[k] = calloc((size_t)rest + 1, row_bytes + 1);
        if (!ends[k]) return fail_usage("out of memory", NULL);
        if (k == 1 && (status = h->ops->set_state(h, state)) != 0) return fail_call(h, status, t);
        if (k == 2) {
            if ((status = h->ops->free_state(h, &state)) != 0
                || (status = h->ops->deserialize(h, bytes, size, &state)) != 0
                || (status = h->ops->set_state(h, state)) != 0)
                return fail_call(h, status, t);
        }
        n_run = n;
        t_run = t;
        /* the first run is the plain run's second half, printed */
        if ((status = run(h, &n_run, &t_run, -1, ends[k], k == 0 ? stdout : NULL)) != 0)
            return status;
        counts[k] = n_run - n;
    }
    free(bytes);
    if ((status = h->ops->free_state(h, &state)) != 0) return fail_call(h, status, t);
    for (k = 1; k < 3; ++k) {
        if (counts[k] != counts[0]
            || memcmp(ends[k], ends[0], (size_t)counts[0] * row_bytes) != 0) {
            fprintf(stderr, "host: the run after %s differs from the first one\n",
                    k == 1 ? "setting the state back" : "deserializing the state");
            return 1;
        }
    }
    fprintf(stderr, "host: state round trip: %ld rows after t=%.17g equal to the bit, twice\n",
            counts[0], t);
    return 0;
}

/* serialize the state, garble it as `how` says, deserialize it: the status */
static int garbled_state(Host *h, const char *how, double t)
{
    unsigned char *bytes = NULL;
    size_t size = 0, i;
    void *state = NULL, *back = NULL;
    int status;
    if ((status = h->ops->get_state(h, &state)) != 0
        || (status = h->ops->serialize(h, state, &bytes, &size)) != 0)
        return fail_call(h, status, t);
    if (size == 0) return fail_usage("the serialized state is empty", NULL);
    if (strcmp(how, "all") == 0) {
        for (i = 0; i < size; ++i) bytes[i] ^= 0xFF;
    } else if (strcmp(how, "header") == 0) {
        bytes[0] ^= 0xFF;
    } else if (strcmp(how, "middle") == 0) {
        bytes[size / 2] ^= 0xFF;
    } else if (strcmp(how, "last") == 0) {
        bytes[size - 1] ^= 0xFF;
    } else if (strcmp(how, "truncated") == 0) {
        size -= 1;
    } else {
        return fail_usage("garbled-state takes all, header, middle, last or truncated", how);
    }
    status = h->ops->deserialize(h, bytes, size, &back);
    printf("garbled-state %s %s %d\n", how, h->call, status);
    if (status == 0 && back) h->ops->free_state(h, &back);
    h->ops->free_state(h, &state);
    free(bytes);
    return 0;
}

/* one refusal: the call's status on stdout */
static int probe(Host *h, const char *name, const char *arg, double t)
{
    HostVar v;
    double value;
    int status;
    if (strcmp(name, "garbled-state") == 0) return garbled_state(h, arg ? arg : "all", t);
    if (!arg || parse_var(arg, strcmp(name, "out-of-range") == 0, &v) != 0)
        return fail_usage("this probe needs a variable VR[:k] (VR[:k]=V for out-of-range)", name);
    if (strcmp(name, "unknown-vr") == 0) {
        v.value = 1.0;
        status = h->ops->set(h, &v);
        printf("%s %s %d\n", name, h->call, status);
        status = h->ops->get(h, &v, &value);
        printf("%s %s %d\n", name, h->call, status);
        return 0;
    }
    if (strcmp(name, "nan") == 0) v.value = NAN;
    else if (strcmp(name, "inf") == 0) v.value = HUGE_VAL;
    else if (strcmp(name, "set-output") == 0) v.value = 1.0;
    else if (strcmp(name, "out-of-range") != 0) return fail_usage("no such probe", name);
    status = h->ops->set(h, &v);
    printf("%s %s %d\n", name, h->call, status);
    return 0;
}

static int probe_and_free(Host *h, const char *name, const char *arg, double t)
{
    int result = probe(h, name, arg, t);
    h->ops->free_instance(h);
    return result;
}

int main(int argc, char **argv)
{
    static Host host;
    Host *h = &host;
    const char *probe_name = NULL, *probe_arg = NULL;
    Phase phase = PHASE_STEPPING;
    long n = 0;
    double t;
    int i, status, result, stateful;
#ifdef _WIN32
    /* "\n", not "\r\n": the CSV is the same bytes on both platforms */
    _setmode(_fileno(stdout), _O_BINARY);
#endif
    h->start = h->stop = h->step = NAN;
    if (argc < 2) return fail_usage("usage: host DIR [options] (see host.c)", NULL);
    h->dir = argv[1];
    for (i = 2; i < argc; ++i) {
        const char *opt = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(opt, "--probe") == 0 && val) {
            probe_name = argv[++i];
            if (i + 1 < argc && strncmp(argv[i + 1], "--", 2) != 0) probe_arg = argv[++i];
            continue;
        }
        if (!val) return fail_usage("an option without its value", opt);
        ++i;
        if (strcmp(opt, "--start") == 0) h->start = strtod(val, NULL);
        else if (strcmp(opt, "--stop") == 0) h->stop = strtod(val, NULL);
        else if (strcmp(opt, "--step") == 0) h->step = strtod(val, NULL);
        else if (strcmp(opt, "--out") == 0) {
            if (parse_outs(h, val) != 0) return fail_usage("bad --out", val);
        } else if (strcmp(opt, "--set") == 0) {
            if (h->n_sets >= HOST_MAX_VARS || parse_var(val, 1, &h->sets[h->n_sets++]) != 0)
                return fail_usage("bad --set", val);
        } else if (strcmp(opt, "--phase") == 0) {
            if (strcmp(val, "instantiated") == 0) phase = PHASE_INSTANTIATED;
            else if (strcmp(val, "initializing") == 0) phase = PHASE_INITIALIZING;
            else if (strcmp(val, "stepping") == 0) phase = PHASE_STEPPING;
            else return fail_usage("bad --phase", val);
        } else {
            return fail_usage("unknown option", opt);
        }
    }
    if ((status = read_description(h)) != 0 || (status = load(h)) != 0) return status;
    t = h->start;

    if ((status = h->ops->instantiate(h)) != 0) return fail_call(h, status, t);
    for (i = 0; i < h->n_sets; ++i)
        if ((status = h->ops->set(h, &h->sets[i])) != 0) return fail_call(h, status, t);
    /* the state probes need a state that has stepped: they run while stepping */
    stateful = probe_name && (strcmp(probe_name, "state-roundtrip") == 0
                              || strcmp(probe_name, "garbled-state") == 0);
    if (probe_name && !stateful && phase == PHASE_INSTANTIATED)
        return probe_and_free(h, probe_name, probe_arg, t);
    if ((status = h->ops->enter_initialization(h)) != 0) return fail_call(h, status, t);
    if (probe_name && !stateful && phase == PHASE_INITIALIZING)
        return probe_and_free(h, probe_name, probe_arg, t);
    if ((status = h->ops->exit_initialization(h)) != 0) return fail_call(h, status, t);

    if (!probe_name || strcmp(probe_name, "state-roundtrip") == 0) {
        header(h);
        if ((status = sample(h, t, NULL, stdout)) != 0) return fail_call(h, status, t);
        if (!probe_name) {
            result = run(h, &n, &t, -1, NULL, stdout);
        } else {
            result = run(h, &n, &t, points(h) / 2, NULL, stdout);
            if (result == 0) result = state_roundtrip(h, n, t);
        }
    } else {
        /* a state from halfway, so that it holds more than its start */
        if (stateful && (result = run(h, &n, &t, points(h) / 2, NULL, NULL)) != 0) return result;
        return probe_and_free(h, probe_name, probe_arg, t);
    }
    if (result != 0) return result;
    if ((status = h->ops->terminate(h)) != 0) return fail_call(h, status, t);
    h->ops->free_instance(h);
    fflush(stdout);
    return 0;
}
