/* A hostile FMI 2.0 host for tests/native/test_native_hostile.py, compiled with a native FMU's
   own sources under AddressSanitizer and UndefinedBehaviorSanitizer: it steps the FMU, then
   feeds it mutated serialized states (bytes flipped, truncated, lengthened, random), random
   value references, NaN and infinite values, negative steps, in a loop. Any memory error or
   undefined behaviour ends it with the sanitizer's report; otherwise it prints how many
   mutated states were accepted (only those equal to the original may be). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env, (void)name, (void)status, (void)category, (void)message;
}

int main(int argc, char **argv)
{
    if (argc < 3)
        return 2;
    fmi2CallbackFunctions cb = {logger, NULL, NULL, NULL, NULL};
    fmi2Component c = fmi2Instantiate("hostile", fmi2CoSimulation, argv[1], "", &cb, 0, 0);
    int rounds = atoi(argv[2]);
    if (!c)
        return 3;
    fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    double t = 0.0, h = 1e-5;
    for (int k = 0; k < 20; k++, t += h)
        fmi2DoStep(c, t, h, fmi2True);
    fmi2FMUstate state = NULL;
    size_t n = 0;
    if (fmi2GetFMUstate(c, &state) != fmi2OK
        || fmi2SerializedFMUstateSize(c, state, &n) != fmi2OK)
        return 4;
    unsigned char *good = malloc(n), *bad = malloc(n + 64);
    if (!good || !bad || fmi2SerializeFMUstate(c, state, (fmi2Byte *)good, n) != fmi2OK)
        return 5;
    srand(1);
    int foreign = 0;
    for (int i = 0; i < rounds; i++) {
        size_t m = n;
        memcpy(bad, good, n);
        switch (rand() % 4) {
        case 0: bad[rand() % n] ^= (unsigned char)(1 + rand() % 255); break;
        case 1: m = (size_t)rand() % (n + 64); break;
        case 2: for (int j = 0; j < 8; j++) bad[rand() % n] = (unsigned char)rand(); break;
        default: for (size_t j = 0; j < n; j++) bad[j] = (unsigned char)rand(); break;
        }
        fmi2FMUstate taken = NULL;
        if (fmi2DeSerializeFMUstate(c, (fmi2Byte *)bad, m, &taken) == fmi2OK) {
            foreign += m != n || memcmp(bad, good, n) != 0;
            fmi2SetFMUstate(c, taken);
            fmi2FreeFMUstate(c, &taken);
        }
        fmi2ValueReference vr[3] = {(unsigned)(rand() % 64), (unsigned)(rand() % 64),
                                    (unsigned)rand()};
        double x[3] = {rand() / 1e3, -rand() / 1e9, (rand() % 2) ? NAN : INFINITY};
        fmi2Integer ints[3];
        fmi2Boolean bools[3];
        fmi2SetReal(c, vr, (size_t)(rand() % 4), x);
        fmi2GetReal(c, vr, (size_t)(rand() % 4), x);
        fmi2GetInteger(c, vr, 3, ints);
        fmi2GetBoolean(c, vr, 3, bools);
        fmi2DoStep(c, t, (rand() % 3) ? h : -h, fmi2True);
        fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t);
    }
    fmi2SetFMUstate(c, state);
    fmi2FreeFMUstate(c, &state);
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    free(good);
    free(bad);
    printf("foreign states accepted: %d\n", foreign);
    return 0;
}
