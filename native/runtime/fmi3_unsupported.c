/* The FMI 3.0 calls a sewfmu co-simulation FMU does not provide (fmi3_glue.c has the others):
   each refused with fmi3Error and a log line saying why. */
#include "fmi3_glue.h"

static const char *const NO_EVENTS = "not provided: this FMU has no event mode and no clocks";
static const char *const NO_DERIVATIVES = "not provided (providesDirectionalDerivatives, "
                                          "providesAdjointDerivatives, "
                                          "maxOutputDerivativeOrder are not declared)";
static const char *const NO_ME = "not provided: this FMU is for co-simulation only";

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference, (void)nDependencies;
    REFUSE(c, "fmi3GetNumberOfVariableDependencies", "not provided (providesPerElementDependencies "
           "is not declared): the modelDescription's ModelStructure lists them");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    REFUSE(c, "fmi3GetVariableDependencies", "not provided (providesPerElementDependencies is "
           "not declared): the modelDescription's ModelStructure lists them");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    REFUSE(c, "fmi3GetDirectionalDerivative", NO_DERIVATIVES);
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    REFUSE(c, "fmi3GetAdjointDerivative", NO_DERIVATIVES);
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    REFUSE(c, "fmi3GetOutputDerivatives", NO_DERIVATIVES);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c)
{
    REFUSE(c, "fmi3EnterConfigurationMode", "not provided: this FMU has no structural "
           "parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance c)
{
    REFUSE(c, "fmi3ExitConfigurationMode", "not provided: this FMU has no structural "
           "parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)vr, (void)nvr, (void)intervals, (void)qualifiers;
    REFUSE(c, "fmi3GetIntervalDecimal", NO_EVENTS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions, (void)qualifiers;
    REFUSE(c, "fmi3GetIntervalFraction", NO_EVENTS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[])
{
    (void)vr, (void)nvr, (void)shifts;
    REFUSE(c, "fmi3GetShiftDecimal", NO_EVENTS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    REFUSE(c, "fmi3GetShiftFraction", NO_EVENTS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[])
{
    (void)vr, (void)nvr, (void)intervals;
    REFUSE(c, "fmi3SetIntervalDecimal", NO_EVENTS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    REFUSE(c, "fmi3SetIntervalFraction", NO_EVENTS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[])
{
    (void)vr, (void)nvr, (void)shifts;
    REFUSE(c, "fmi3SetShiftDecimal", NO_EVENTS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    REFUSE(c, "fmi3SetShiftFraction", NO_EVENTS);
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { REFUSE(c, "fmi3EnterEventMode", NO_EVENTS); }

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c)
{
    REFUSE(c, "fmi3EvaluateDiscreteStates", NO_EVENTS);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate, (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged, (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined, (void)nextEventTime;
    REFUSE(c, "fmi3UpdateDiscreteStates", NO_EVENTS);
}

fmi3Status fmi3EnterStepMode(fmi3Instance c) { REFUSE(c, "fmi3EnterStepMode", NO_EVENTS); }

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    REFUSE(c, "fmi3ActivateModelPartition", NO_EVENTS);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c)
{
    REFUSE(c, "fmi3EnterContinuousTimeMode", NO_ME);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    REFUSE(c, "fmi3CompletedIntegratorStep", NO_ME);
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time)
{
    (void)time;
    REFUSE(c, "fmi3SetTime", NO_ME);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    REFUSE(c, "fmi3SetContinuousStates", NO_ME);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives, (void)nContinuousStates;
    REFUSE(c, "fmi3GetContinuousStateDerivatives", NO_ME);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators, (void)nEventIndicators;
    REFUSE(c, "fmi3GetEventIndicators", NO_ME);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    REFUSE(c, "fmi3GetContinuousStates", NO_ME);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals, (void)nContinuousStates;
    REFUSE(c, "fmi3GetNominalsOfContinuousStates", NO_ME);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *nEventIndicators)
{
    (void)nEventIndicators;
    REFUSE(c, "fmi3GetNumberOfEventIndicators", NO_ME);
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *nContinuousStates)
{
    (void)nContinuousStates;
    REFUSE(c, "fmi3GetNumberOfContinuousStates", NO_ME);
}
