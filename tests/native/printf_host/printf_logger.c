/* An FMI 2.0 host whose logger is printf-like, as fmusim's, FMIL's and the standard's examples
   are: the message is passed as the format with the varargs after it. It instantiates the FMU
   of argv[1] (binary) with guid argv[2] under the instance name argv[3], makes calls that are
   each refused or discarded with a log line (an unknown value reference, an unknown log
   category naming argv[3], a garbled state, a step before initialization, a negative start
   time) and prints every line. A '%' left in a line makes vsnprintf read arguments that are not
   there (a crash, or a %n write); the test checks the lines instead. */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

typedef void (*Logger)(void *, const char *, int, const char *, const char *, ...);
typedef struct {
    Logger logger;
    void *(*allocate)(size_t, size_t);
    void (*release)(void *);
    void *step_finished;
    void *env;
} Callbacks;

static void printf_logger(void *env, const char *name, int status, const char *category,
                          const char *message, ...)
{
    char line[4096];
    va_list args;
    (void)env, (void)name, (void)category;
    va_start(args, message);
    vsnprintf(line, sizeof line, message, args);     /* the message is the format */
    va_end(args);
    printf("%d|%s\n", status, line);
}

typedef void *(*Instantiate)(const char *, int, const char *, const char *, const Callbacks *,
                             int, int);
typedef int (*SetReal)(void *, const unsigned *, size_t, const double *);
typedef int (*SetDebugLogging)(void *, int, size_t, const char *const *);
typedef int (*DeSerialize)(void *, const char *, size_t, void **);
typedef int (*DoStep)(void *, double, double, int);
typedef int (*Setup)(void *, int, double, double, int, double);
typedef void (*FreeInstance)(void *);

int main(int argc, char **argv)
{
    if (argc != 4)
        return 2;
    void *lib = dlopen(argv[1], RTLD_NOW);
    if (!lib)
        return 3;
    Callbacks cb = {printf_logger, calloc, free, NULL, NULL};
    void *c = ((Instantiate)dlsym(lib, "fmi2Instantiate"))(argv[3], 1, argv[2], NULL, &cb, 0, 1);
    if (!c)
        return 4;
    unsigned unknown = 99999;
    double x = 1.0;
    const char *categories[] = {argv[3]};
    char garbage[64] = "%s%n%s%n not a state";
    void *state = NULL;
    ((SetReal)dlsym(lib, "fmi2SetReal"))(c, &unknown, 1, &x);
    ((SetDebugLogging)dlsym(lib, "fmi2SetDebugLogging"))(c, 1, 1, categories);
    ((DeSerialize)dlsym(lib, "fmi2DeSerializeFMUstate"))(c, garbage, sizeof garbage, &state);
    ((DoStep)dlsym(lib, "fmi2DoStep"))(c, 0.0, 0.1, 1);
    ((Setup)dlsym(lib, "fmi2SetupExperiment"))(c, 0, 0.0, -1.0, 0, 0.0);
    ((FreeInstance)dlsym(lib, "fmi2FreeInstance"))(c);
    printf("done\n");
    return 0;
}
