"""One rollback, for every algorithm that takes a step again (iterative, adaptive) and for the run
loop's own save and restore: the FMU states of some instances and the inputs the master last set
on them, saved at a communication point and put back together.

The rule: an algorithm that may roll back declares it (Algorithm.rolls_back), and the run loop
then steps every FMU with noSetFMUStatePriorToCurrentPoint = false, in FMI 2.0 and 3.0 alike; an
algorithm that never rolls back steps with true, which lets an FMU drop its history.
"""
from __future__ import annotations

from sewfmu.scenarios.cosim.fmi_calls import CosimError, FmiCallError


def declares(instance, capability: str) -> bool:
    """What the instance's modelDescription says of a co-simulation capability (a description
    that says nothing, such as the tests' fakes, is taken as able)."""
    return bool(getattr(getattr(instance.md, "coSimulation", None), capability, True))


class Rollback:
    """Saved states of some instances; one slot each, reused from save to save."""

    def __init__(self, instances):
        self.instances = list(instances)
        unable = [i for i in self.instances if not declares(i, "canGetAndSetFMUstate")]
        if unable:                  # before any step: a refusal, not a failure at t = 0
            names = ", ".join(f"{i.name} ({i.md.modelName})" for i in unable)
            raise CosimError(f"{names} cannot save and restore its state (its modelDescription "
                             f"says canGetAndSetFMUstate = false), which taking a step again "
                             f"needs: run it with the jacobi or gauss-seidel master")
        self.slots = [inst.new_state_slot() for inst in self.instances]
        self.inputs: list[list[float]] = []

    def save(self) -> None:
        for inst, slot in zip(self.instances, self.slots):
            inst.check("getFMUState", inst.get_state(slot))
        self.inputs = [list(inst.in_buf) for inst in self.instances]

    def restore(self, read_outputs: bool = True) -> None:
        """The FMUs back to the saved point, with the inputs the master had set then; their
        outputs read again unless the caller steps and exchanges at once."""
        for inst, slot, values in zip(self.instances, self.slots, self.inputs):
            inst.check("setFMUState", inst.set_state(slot))
            inst.in_buf[:] = values
        if read_outputs:
            for inst in self.instances:
                inst.read_outputs()

    def free(self) -> None:
        for inst, slot in zip(self.instances, self.slots):
            if inst.instantiated and not inst.failed:
                try:
                    inst.free_state(slot)
                except (FmiCallError, OSError):
                    pass

