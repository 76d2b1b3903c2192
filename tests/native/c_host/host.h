/* A small FMI host with no Python in it, for tests/native/test_hosts_without_python.py: it loads
   an unzipped FMU's binary (FMI 2.0 or 3.0 co-simulation; Linux .so or, under Wine, Windows .dll),
   runs an experiment and prints the outputs as CSV, or exercises one refusal and prints the
   status it got. host.c holds what both FMI versions share; host_fmi2.c and host_fmi3.c hold
   each version's calls behind HostOps. */
#ifndef SEW_HOST_H
#define SEW_HOST_H

#ifdef _WIN32
/* mingw's own printf and strtod: msvcrt's are not held to round-trip %.17g */
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <stddef.h>

#define HOST_MAX_VARS 256
#define HOST_TEXT 4096
#define HOST_NAME 256

/* the variable kinds sewfmu's FMUs declare (FMI 2.0 Real/Integer/Boolean, FMI 3.0
   Float64/Int32/Boolean) */
typedef enum { HOST_REAL = 0, HOST_INT = 1, HOST_BOOL = 2 } HostKind;

/* one variable named on the command line: "vr", "vr:i", "vr:b", with "=value" for a setting */
typedef struct {
    unsigned int vr;
    HostKind kind;
    double value;
} HostVar;

typedef struct Host Host;

/* One FMI version's calls. Each returns the FMI status (0 OK .. 4 Fatal) and leaves the name
   of the FMI function it called in host->call, for the one line a failure prints. */
typedef struct {
    int (*bind)(Host *h);            /* look the functions up in h->lib; 0 or -1 */
    int (*instantiate)(Host *h);
    int (*set)(Host *h, const HostVar *v);
    int (*get)(Host *h, const HostVar *v, double *value);
    int (*enter_initialization)(Host *h);
    int (*exit_initialization)(Host *h);
    int (*do_step)(Host *h, double t, double step);
    int (*get_state)(Host *h, void **state);
    int (*set_state)(Host *h, void *state);
    int (*free_state)(Host *h, void **state);
    /* size, then the bytes, into *bytes (malloc'd) */
    int (*serialize)(Host *h, void *state, unsigned char **bytes, size_t *size);
    int (*deserialize)(Host *h, const unsigned char *bytes, size_t size, void **state);
    int (*terminate)(Host *h);
    void (*free_instance)(Host *h);
} HostOps;

struct Host {
    /* from the command line and modelDescription.xml */
    const char *dir;                 /* the unzipped FMU */
    int fmi;                         /* 2 or 3 */
    char model_identifier[HOST_NAME];
    char token[HOST_TEXT];           /* guid / instantiationToken */
    /* FMI 2.0: a file URI (room for percent-encoding); FMI 3.0: a path ending in a separator */
    char resources[3 * HOST_TEXT + 64];
    double start, stop, step;
    HostVar sets[HOST_MAX_VARS];
    int n_sets;
    HostVar outs[HOST_MAX_VARS];
    int n_outs;

    /* at run time */
    void *lib;                       /* the binary (dlopen handle or HMODULE) */
    void *fns;                       /* the version's table of function pointers */
    void *instance;
    const char *call;                /* the FMI function called last */
    const HostOps *ops;
};

extern const HostOps HOST_FMI2;
extern const HostOps HOST_FMI3;

/* a function of the loaded binary, or NULL (dlsym / GetProcAddress); void (*)(void) is the
   type C lets one cast to any other function pointer type */
typedef void (*HostFunction)(void);
HostFunction host_symbol(Host *h, const char *name);
/* the status's name, for messages */
const char *host_status_name(int status);

#endif
