/* What the FMI 3.0 glue's two files share (fmi3_glue.c: the calls a sewfmu FMU provides;
   fmi3_unsupported.c: those it refuses). */
#ifndef SEW_FMI3_GLUE_H
#define SEW_FMI3_GLUE_H

#include "fmi3Functions.h"
#include "sew_slave.h"

typedef struct {
    SewSlave *slave;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    int logging;
} Fmi3Instance;

#define SLAVE(c) (((Fmi3Instance *)(c))->slave)
#define CHECK(c)                                                                                  \
    do {                                                                                          \
        if (!(c))                                                                                 \
            return fmi3Error;                                                                     \
    } while (0)
#define REFUSE(c, call, why)                                                                      \
    do {                                                                                          \
        CHECK(c);                                                                                 \
        return (fmi3Status)sew_refuse(SLAVE(c), "%s: %s", call, why);                             \
    } while (0)

#endif
