"""A fake FMU instance for unit tests of the run loop and the algorithms (libcosim's mock_slave):
plain Python models behind sewfmu's Instance interface, no FMU, no library, microseconds a step.
Their exact co-simulation results have closed forms, which the tests compare against.

    models = {"a": Integrator(gain=1.0), "b": Integrator(gain=-1.0, x0=0.0)}
    scenario = fake_scenario(models, ["b.x -> a.u", "a.x -> b.u"], stop_time=1.0, step=0.1)
    result = Master(scenario, {}, make_instance=maker(models)).run()
"""
from __future__ import annotations

from dataclasses import dataclass

from sewfmu.scenarios.cosim.fmi_calls import Status
from sewfmu.scenarios.cosim.instances import Instance
from sewfmu.scenarios.format.scenario import Connection, Scenario
from sewfmu.scenarios.format.scenario import Instance as Declaration


@dataclass
class FakeVariable:
    name: str
    causality: str
    valueReference: int
    type: str = "Real"
    unit: str | None = None
    start: float | None = 0.0
    min: str | None = None
    max: str | None = None
    variability: str = "continuous"


@dataclass
class FakeDescription:
    modelName: str
    modelVariables: list
    fmiVersion: str = "2.0"


class Model:
    """A model the fake instance runs: named real inputs, real and Boolean outputs, parameters,
    a state to save; `step` returns an FMI status."""

    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    booleans: tuple[str, ...] = ()
    parameters: tuple[str, ...] = ()

    def __init__(self):
        self.u = {name: 0.0 for name in self.inputs}

    def step(self, t: float, h: float) -> int:
        raise NotImplementedError

    def set_parameter(self, name: str, value: float) -> None:
        """An input given a value holds it; a parameter is the attribute of its name."""
        if name in self.u:
            self.u[name] = value
        else:
            setattr(self, name, value)

    def output(self, name: str):
        raise NotImplementedError

    def save(self):
        return dict(vars(self), u=dict(self.u))

    def restore(self, state) -> None:
        vars(self).update(state)
        self.u = dict(state["u"])


class Integrator(Model):
    """x' = gain·u, u extrapolated over a step from its rate u_dot (as sewfmu's FMUs extrapolate
    their inputs); outputs x and its rate x_dot = gain·u (direct feedthrough)."""

    inputs = ("u", "u_dot")
    outputs = ("x", "x_dot")
    parameters = ("x0",)

    def __init__(self, gain: float = 1.0, x0: float = 0.0):
        super().__init__()
        self.gain, self.x = gain, x0

    def set_parameter(self, name, value):
        super().set_parameter("x" if name == "x0" else name, value)

    def step(self, t, h):
        self.x += h * self.gain * (self.u["u"] + 0.5 * h * self.u["u_dot"])
        return Status.OK

    def output(self, name):
        return self.x if name == "x" else self.gain * self.u["u"]


class Gain(Model):
    """y = k·u at once: direct feedthrough and no state (a stiff spring's force from its
    stretch), so y read after a step says when u was set."""

    inputs = ("u",)
    outputs = ("y",)

    def __init__(self, k: float):
        super().__init__()
        self.k = k

    def step(self, t, h):
        return Status.OK

    def output(self, name):
        return self.k * self.u["u"]


class Switch(Model):
    """A Boolean output `on` that switches when its input u reaches `at`, evaluated on u (as
    a contact switches on the punch's position); also passes u on."""

    inputs = ("u", "u_dot")
    outputs = ("y",)
    booleans = ("on",)

    def __init__(self, at: float):
        super().__init__()
        self.at = at

    def step(self, t, h):
        self.u["u"] += h * self.u["u_dot"]        # where the input will be at the step's end
        return Status.OK

    def output(self, name):
        return self.u["u"] >= self.at if name == "on" else self.u["u"]


class Failing(Integrator):
    """An integrator that refuses every step from `at` on with `status`, logging why."""

    def __init__(self, at: float, status: int = Status.DISCARD, **kwargs):
        super().__init__(**kwargs)
        self.at, self.status = at, status
        self.log = None

    def step(self, t, h):
        if t >= self.at:
            self.log(Status.ERROR, "the fabric tore")
            return self.status
        return super().step(t, h)


class FakeInstance(Instance):
    """A Model behind the Instance interface; `calls` lists the life calls made on it and
    `no_set_prior` the noSetFMUStatePriorToCurrentPoint each step was given."""

    def __init__(self, name: str, model: Model, log):
        variables = [FakeVariable(n, "input", k) for k, n in enumerate(model.inputs)]
        variables += [FakeVariable(n, "output", 100 + k) for k, n in enumerate(model.outputs)]
        variables += [FakeVariable(n, "output", 200 + k, type="Boolean", start=None,
                                   variability="discrete") for k, n in enumerate(model.booleans)]
        variables += [FakeVariable(n, "parameter", 300 + k, variability="fixed")
                      for k, n in enumerate(model.parameters)]
        super().__init__(name, FakeDescription(type(model).__name__, variables), log)
        self.model = model
        self.by_vr = {v.valueReference: v.name for v in variables}
        self.calls: list[str] = []
        self.no_set_prior: set[bool] = set()
        model.log = lambda status, text: log.add(name, status, text)

    def _instantiate(self):
        self.calls.append("instantiate")

    def enter_initialization(self, stop):
        self.calls.append("enter initialization")

    def set_parameter(self, variable, value):
        self.model.set_parameter(variable.name, value)

    def exit_initialization(self):
        self.calls.append("exit initialization")

    def release(self):
        self.calls.append("free")
        self.instantiated = False

    def _set_reals(self):
        for vr, value in zip(self.in_vr, self.in_buf):
            self.model.u[self.by_vr[vr]] = value
        return Status.OK

    def _get_reals(self):
        for k, vr in enumerate(self.out_vr):
            self.out_buf[k] = self.model.output(self.by_vr[vr])
        return Status.OK

    def _get_booleans(self):
        for k, vr in enumerate(self.bool_vr):
            self.bool_buf[k] = self.model.output(self.by_vr[vr])
        return Status.OK

    def _do_step(self, t, h):
        self.no_set_prior.add(not self.may_roll_back)
        return self.model.step(t, h)

    def new_state_slot(self):
        return [None]

    def get_state(self, slot):
        slot[0] = self.model.save()
        return Status.OK

    def set_state(self, slot):
        self.model.restore(slot[0])
        return Status.OK

    def free_state(self, slot):
        slot[0] = None


def maker(models: dict[str, Model], made: dict | None = None):
    """The make_instance of Master for these models (instance name -> model); the instances made
    are put into `made`, if given."""
    def make(declaration, log):
        inst = FakeInstance(declaration.name, models[declaration.name], log)
        if made is not None:
            made[declaration.name] = inst
        return inst
    return make


def fake_scenario(models: dict[str, Model], connections: list[str], stop_time: float,
                  step: float, master: str = "jacobi", parameters: dict | None = None,
                  **experiment) -> Scenario:
    """A scenario over fake instances (the file format's checks of FMU names do not apply)."""
    parameters = parameters or {}
    cons = []
    for text in connections:
        src, dst = (side.strip().split(".") for side in text.split("->"))
        cons.append(Connection(src[0], src[1], dst[0], dst[1]))
    scenario = Scenario(
        name="fake", source="fake.toml", description="", analysis=None,
        instances={n: Declaration(n, type(m).__name__, dict(parameters.get(n, {})))
                   for n, m in models.items()},
        connections=cons, record=None, step=step, master=master, stop_time=stop_time,
        revolutions=None, shaft=None, compare=None)
    for key, value in experiment.items():
        setattr(scenario, key, value)
    return scenario
