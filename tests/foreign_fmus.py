"""FMUs sewfmu did not make, built by the tests: a first-order motor written with pythonfmu in
its own style (not sewfmu's slave base), a gain compiled from C against the FMI 2.0 headers
fmpy ships, whose modelDescription declares its units (mm) with their FMI unit definitions, and
an FMI 3.0 gain written with pythonfmu3."""
import shutil
import subprocess
import uuid
import zipfile
from pathlib import Path

import fmpy

MOTOR_PY = '''
import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Motor(Fmi2Slave):
    """A motor whose speed follows a first-order lag from omega0 to omega_ref (time constant T),
    stepped in closed form: phi, omega and epsilon are exact at every step's end."""

    author = "a designer"
    description = "first-order motor"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.omega0, self.omega_ref, self.T = 100.0, 150.0, 0.02
        self.phi, self.omega, self.epsilon = 0.0, 100.0, 2500.0
        for name in ("omega0", "omega_ref", "T"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        for name in ("phi", "omega", "epsilon"):
            self.register_variable(Real(name, causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        self._at(0.0)

    def do_step(self, current_time, step_size):
        self._at(current_time + step_size)
        return True

    def _at(self, t):
        d, e = self.omega0 - self.omega_ref, math.exp(-t / self.T)
        self.phi = self.omega_ref * t + d * self.T * (1.0 - e)
        self.omega = self.omega_ref + d * e
        self.epsilon = -d / self.T * e
'''

GAIN3_PY = '''
from pythonfmu3 import Fmi3Causality, Fmi3Slave, Fmi3Variability, Float64


class Gain3(Fmi3Slave):
    """y = k*u, computed at each step's end (no direct feedthrough)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k, self.u, self.y, self.time = 2.0, 0.0, 0.0, 0.0
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous))
        self.register_variable(Float64("k", causality=Fmi3Causality.parameter,
                                       variability=Fmi3Variability.tunable))
        self.register_variable(Float64("u", causality=Fmi3Causality.input))
        self.register_variable(Float64("y", causality=Fmi3Causality.output))

    def do_step(self, current_time, step_size):
        self.time = current_time + step_size
        self.y = self.k * self.u
        return True
'''

GAIN_C = r'''
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"

/* y = k*u, computed when y is read (direct feedthrough); u and y in mm */
typedef struct { double k, u, t; } Gain;

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String x[])
{ return fmi2OK; }
fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *f,
                              fmi2Boolean visible, fmi2Boolean logging)
{
    Gain *g;
    if (type != fmi2CoSimulation) return NULL;
    g = calloc(1, sizeof(Gain));
    if (g) g->k = 1.0;
    return g;
}
void fmi2FreeInstance(fmi2Component c) { free(c); }
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real start,
                               fmi2Boolean sd, fmi2Real stop)
{ ((Gain *)c)->t = start; return fmi2OK; }
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { Gain *g = c; g->k = 1.0; g->u = 0.0; return fmi2OK; }
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    Gain *g = c; size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] == 0) v[i] = g->k;
        else if (vr[i] == 1) v[i] = g->u;
        else if (vr[i] == 2) v[i] = g->k * g->u;
        else return fmi2Error;
    }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[])
{
    Gain *g = c; size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] == 0) g->k = v[i];
        else if (vr[i] == 1) g->u = v[i];
        else return fmi2Error;
    }
    return fmi2OK;
}
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSet)
{ ((Gain *)c)->t = t + h; return fmi2OK; }
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{
    Gain *copy = *s ? (Gain *)*s : malloc(sizeof(Gain));
    if (!copy) return fmi2Error;
    memcpy(copy, c, sizeof(Gain)); *s = copy; return fmi2OK;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{ memcpy(c, s, sizeof(Gain)); return fmi2OK; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { free(*s); *s = NULL; return fmi2OK; }

/* the rest of the interface: not used by a gain */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) { return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{ return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n,
                                   fmi2FMUstate *s) { return fmi2Error; }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) { return fmi2Error; }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[])
{ return fmi2Error; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer o[], fmi2Real v[])
{ return fmi2Error; }
fmi2Status fmi2CancelStep(fmi2Component c) { return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
{ return fmi2Error; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v)
{ return fmi2Error; }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
{ return fmi2Error; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v)
{ return fmi2Error; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v)
{ return fmi2Error; }
'''

GAIN_XML = '''<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Gain" guid="{guid}"
    generationTool="gcc, by hand" variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="Gain" canHandleVariableCommunicationStepSize="true"
      canGetAndSetFMUstate="true"/>
  <UnitDefinitions>
    <Unit name="mm"><BaseUnit m="1" factor="0.001"/></Unit>
  </UnitDefinitions>
  <DefaultExperiment startTime="0" stopTime="1" stepSize="0.1"/>
  <ModelVariables>
    <ScalarVariable name="k" valueReference="0" causality="parameter" variability="tunable">
      <Real start="1" min="-1000" max="1000"/>
    </ScalarVariable>
    <ScalarVariable name="u" valueReference="1" causality="input" variability="continuous">
      <Real start="0" unit="mm"/>
    </ScalarVariable>
    <ScalarVariable name="y" valueReference="2" causality="output" variability="continuous"
        initial="calculated">
      <Real unit="mm"/>
    </ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs><Unknown index="3" dependencies="2"/></Outputs>
    <InitialUnknowns><Unknown index="3" dependencies="2"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
'''


def fmi2_headers() -> Path:
    """The FMI 2.0 headers fmpy ships (fmpy/c-code)."""
    return Path(fmpy.__file__).parent / "c-code"


def build_motor(folder: Path) -> Path:
    """Motor.fmu built with pythonfmu's FmuBuilder from the script above."""
    from pythonfmu import FmuBuilder  # pythonfmu: only the test that builds the motor needs it

    script = folder / "motor.py"
    script.write_text(MOTOR_PY)
    return Path(FmuBuilder.build_FMU(script, dest=folder))


def build_gain(folder: Path) -> Path | None:
    """Gain.fmu compiled with gcc (None without gcc)."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    source = folder / "gain.c"
    source.write_text(GAIN_C)
    library = folder / "Gain.so"
    subprocess.run([gcc, "-shared", "-fPIC", "-O1", "-I", str(fmi2_headers()), "-o",
                    str(library), str(source)], check=True, capture_output=True)
    fmu = folder / "Gain.fmu"
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("modelDescription.xml", GAIN_XML.format(guid="{" + str(uuid.uuid4()) + "}"))
        z.write(library, "binaries/linux64/Gain.so")
        z.write(source, "sources/gain.c")
    return fmu


def build_gain3(folder: Path) -> Path:
    """Gain3.fmu (FMI 3.0) built with pythonfmu3's FmuBuilder."""
    from pythonfmu3 import FmuBuilder  # pythonfmu3: only the test that builds it needs it

    script = folder / "gain3.py"
    script.write_text(GAIN3_PY)
    return Path(FmuBuilder.build_FMU(script, dest=folder))


def rewritten(fmu: Path, folder: Path, name: str = "Rewritten.fmu", **attributes: str) -> Path:
    """A copy of the FMU whose modelDescription.xml gives other values to the attributes (what a
    hostile or careless exporter could write, or capabilities it claims; the binary finds its code
    by modelIdentifier), as the file `name` in `folder`."""
    copy = folder / name
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(copy, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                for attribute, value in attributes.items():
                    start = text.index(f' {attribute}="') + len(f' {attribute}="')
                    text = text[:start] + value + text[text.index('"', start):]
                data = text.encode()
            target.writestr(item, data)
    return copy
