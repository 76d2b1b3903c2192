"""A minimal FMI host for the tests: one FMU instance through fmpy, with its log kept.

Every Host is freed at the end of the test session (conftest.py), unless a call on it failed:
pythonfmu releases a failed instance's Python objects at once, so freeing it again would crash
the process, and a healthy instance left unfreed can corrupt the heap at interpreter exit.
"""
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from scenarios.master import LogCollector, extracted_fmu, release_at_exit

OPEN_HOSTS: list["Host"] = []


class Host:
    def __init__(self, path, name="inst"):
        unzip_dir, self.md = extracted_fmu(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.log = LogCollector()
        self.failed = False
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzip_dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        release_at_exit(self.fmu)
        self._watch_calls()
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=True)
        OPEN_HOSTS.append(self)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()

    def _watch_calls(self):
        """Mark the host failed when any FMI call on it fails (fmpy routes them all via _call)."""
        call = self.fmu._call

        def watched(name, *args):
            try:
                return call(name, *args)
            except FMICallException as err:
                # after fmi2Fatal no call is allowed; after Discard or Error terminate/free are
                self.failed = self.failed or "fatal" in str(err)
                raise
        self.fmu._call = watched

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
            self.fmu.fmi2FreeInstance(self.fmu.component)
        self.failed = True             # no call after this one


def close_all():
    while OPEN_HOSTS:
        OPEN_HOSTS.pop().close()
