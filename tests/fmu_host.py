"""A minimal FMI host for the tests: one FMU instance (FMI 2.0 or 3.0) through fmpy, with its log
kept. An FMI 3.0 FMU is driven through the FMI 2.0 names the tests use (`As2`), so that every
test of an FMU runs unchanged against both versions.

Every Host is freed at the end of the test session (conftest.py), unless a call on it failed:
pythonfmu releases a failed instance's Python objects at once, so freeing it again would crash
the process, and a healthy instance left unfreed can corrupt the heap at interpreter exit.
"""
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from sewfmu.scenarios.cosim.fmi_calls import LogCollector, kind_of
from sewfmu.scenarios.cosim.instances import extracted_fmu
from sewfmu.scenarios.cosim.pythonfmu_host import release_at_exit

OPEN_HOSTS: list["Host"] = []


class Host:
    def __init__(self, path, name="inst"):
        unzip_dir, self.md = extracted_fmu(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: kind_of(v) for v in self.md.modelVariables}   # FMI 2.0's words
        self.log = LogCollector()
        self.failed = False
        fmi3 = self.md.fmiVersion.startswith("3")
        fmu = (FMU3Slave if fmi3 else FMU2Slave)(
            guid=self.md.guid, unzipDirectory=unzip_dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        release_at_exit(fmu)
        self._watch_calls(fmu)
        if fmi3:
            fmu.instantiate(loggingOn=True, logMessage=self.log.for_fmi3(name))
            self.fmu = As2(fmu)
        else:
            fmu.instantiate(callbacks=self.log.callbacks, loggingOn=True)
            self.fmu = fmu
        free = fmu.fmi3FreeInstance if fmi3 else fmu.fmi2FreeInstance
        self._free = lambda: free(fmu.component)
        OPEN_HOSTS.append(self)
        if fmi3:
            fmu.enterInitializationMode(startTime=0.0)
        else:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()

    def _watch_calls(self, fmu):
        """Mark the host failed when any FMI call on it fails (fmpy routes them all via _call)."""
        call = fmu._call

        def watched(name, *args):
            try:
                return call(name, *args)
            except FMICallException as err:
                # after fmi2Fatal no call is allowed; after Discard or Error terminate/free are
                self.failed = self.failed or "fatal" in str(err)
                raise
        fmu._call = watched

    def set(self, **values):
        for name, value in values.items():
            if self.types[name] == "Integer":
                self.fmu.setInteger([self.vr[name]], [int(value)])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        values = []
        for name in names:
            if self.types[name] == "Boolean":
                values.append(bool(self.fmu.getBoolean([self.vr[name]])[0]))
            else:
                values.append(self.fmu.getReal([self.vr[name]])[0])
        return values if len(values) > 1 else values[0]

    def log_text(self):
        return "\n".join(self.log.lines)

    def close(self):
        if not self.failed:
            try:
                self.fmu.terminate()
            except FMICallException:
                pass
            self._free()                # the library stays loaded (see scenarios/cosim/master.py)
        self.failed = True             # no call after this one


def close_all():
    while OPEN_HOSTS:
        OPEN_HOSTS.pop().close()


class As2:
    """An fmpy FMU3Slave under the FMI 2.0 names of fmpy's FMU2Slave that the tests call."""

    def __init__(self, fmu: FMU3Slave):
        self.fmu3 = fmu
        self.component = fmu.component

    def doStep(self, t, h):
        return self.fmu3.doStep(t, h, noSetFMUStatePriorToCurrentPoint=False)

    def exitInitializationMode(self):
        self.fmu3.exitInitializationMode()

    def terminate(self):
        self.fmu3.terminate()

    def setReal(self, vrs, values):
        self.fmu3.setFloat64(vrs, values)

    def getReal(self, vrs):
        return self.fmu3.getFloat64(vrs)

    def setInteger(self, vrs, values):
        self.fmu3.setInt32(vrs, values)

    def getBoolean(self, vrs):
        return self.fmu3.getBoolean(vrs)

    def getFMUstate(self):
        return self.fmu3.getFMUState()

    def setFMUstate(self, state):
        self.fmu3.setFMUState(state)

    def freeFMUstate(self, state):
        self.fmu3.freeFMUState(state)

    def serializeFMUstate(self, state):
        return self.fmu3.serializeFMUState(state)

    def deSerializeFMUstate(self, blob):
        return self.fmu3.deserializeFMUState(blob)
