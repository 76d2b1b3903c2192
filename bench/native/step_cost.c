/* A native FMU's own cost per step, with no host around it but this loop: instantiate one FMI
   2.0 co-simulation FMU from its unzipped folder, then N times set its inputs from a smooth
   series (the slider's motion, a sine of the shaft angle), doStep and get its Real outputs;
   prints the CPU nanoseconds per step. bench/native.py runs it, and under callgrind for the
   instructions per step (what a shared machine's load does not move).

       step_cost BINARY GUID N H VR_IN,VR_IN,... VR_OUT,VR_OUT,...                           */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void quiet(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                  fmi2String category, fmi2String message, ...)
{
    (void)env; (void)name; (void)category;
    if (status > fmi2Warning)
        fprintf(stderr, "%s\n", message);
}

static int parse_vrs(const char *text, fmi2ValueReference *vrs, int most)
{
    int n = 0;
    char *end;
    while (*text && n < most) {
        vrs[n++] = (fmi2ValueReference)strtoul(text, &end, 10);
        text = *end == ',' ? end + 1 : end;
    }
    return n;
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

#define LOAD(name) ((fmi2##name##TYPE *)dlsym(lib, "fmi2" #name))

int main(int argc, char **argv)
{
    fmi2ValueReference in[16], out[32];
    fmi2Real u[16], y[32];
    fmi2CallbackFunctions callbacks = {quiet, calloc, free, NULL, NULL};
    void *lib;
    long n, k;
    int n_in, n_out, i;
    double h, started, spent;
    fmi2Component c;
    if (argc != 7) {
        fprintf(stderr, "usage: step_cost BINARY GUID N H VR_IN,... VR_OUT,...\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 1;
    }
    n = atol(argv[3]);
    h = atof(argv[4]);
    n_in = parse_vrs(argv[5], in, 16);
    n_out = parse_vrs(argv[6], out, 32);
    c = LOAD(Instantiate)("bench", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False,
                          fmi2False);
    if (!c || LOAD(SetupExperiment)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning
        || LOAD(EnterInitializationMode)(c) > fmi2Warning
        || LOAD(ExitInitializationMode)(c) > fmi2Warning) {
        fprintf(stderr, "the FMU did not initialize\n");
        return 1;
    }
    fmi2SetRealTYPE *set_real = LOAD(SetReal);
    fmi2GetRealTYPE *get_real = LOAD(GetReal);
    fmi2DoStepTYPE *do_step = LOAD(DoStep);
    started = cpu_seconds();
    for (k = 0; k < n; k++) {
        double t = k * h, w = 100.0;
        /* a stroke of 4.5 mm at 100 rad/s: value, rate, acceleration (the punch's inputs; a
           linkage reads the first as the shaft angle) */
        for (i = 0; i < n_in; i++) {
            double s = 0.0045 * pow(w, i);
            u[i] = i % 4 == 0 ? s * cos(w * t) : i % 4 == 1 ? -s * sin(w * t)
                 : i % 4 == 2 ? -s * cos(w * t) : s * sin(w * t);
        }
        if (n_in && set_real(c, in, (size_t)n_in, u) > fmi2Warning)
            return 1;
        if (do_step(c, t, h, fmi2True) > fmi2Warning) {
            fprintf(stderr, "doStep failed at t = %g\n", t);
            return 1;
        }
        if (get_real(c, out, (size_t)n_out, y) > fmi2Warning)
            return 1;
    }
    spent = cpu_seconds() - started;
    printf("%.1f\n", 1e9 * spent / n);
    LOAD(Terminate)(c);
    LOAD(FreeInstance)(c);
    return 0;
}
