"""A minimal FMI host for the tests: one FMU instance through fmpy, with its log kept."""
from fmpy.fmi2 import FMU2Slave

from scenarios.master import _extracted, _LogCollector


class Host:
    def __init__(self, path, name="inst"):
        unzip_dir, self.md = _extracted(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.log = _LogCollector()
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzip_dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()

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
