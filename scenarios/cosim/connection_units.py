"""A connection between two declared units: converted through the FMI unit definitions of the two
modelDescriptions, or refused in one line.

FMI 2.0 and 3.0 define a unit by its exponents of the SI base units and a factor and offset
(value in base units = factor · value + offset). Two units with the same exponents convert into
each other (an FMU from another tool may give a motor's speed in rpm, sewfmu's shaft in rad/s);
two with different exponents, or a unit a modelDescription does not define, cannot be converted
and the connection is refused before any FMU runs.
"""
from __future__ import annotations

from sewfmu.scenarios.format.fmu_file import unit_of
from sewfmu.scenarios.format.values import ScenarioError

_EXPONENTS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _base(md, unit: str):
    """The BaseUnit of `unit` as the modelDescription defines it, or None."""
    for definition in getattr(md, "unitDefinitions", None) or []:
        if definition.name == unit:
            return definition.baseUnit
    return None


def conversion(out_var, out_md, in_var, in_md, what: str) -> tuple[float, float] | None:
    """(factor, offset) taking the output's value to the input's unit, None where no conversion
    is needed (the same unit, or a side that declares none: it says nothing about its unit)."""
    out_unit, in_unit = unit_of(out_var), unit_of(in_var)
    if not out_unit or not in_unit or out_unit == in_unit:
        return None
    out_base, in_base = _base(out_md, out_unit), _base(in_md, in_unit)
    for unit, base, md in ((out_unit, out_base, out_md), (in_unit, in_base, in_md)):
        if base is None:
            raise ScenarioError(f"{what}: incompatible units {out_unit!r} -> {in_unit!r}: "
                                f"{md.modelName} does not define {unit!r} in its "
                                f"UnitDefinitions, so it cannot be converted")
    dims = [tuple(getattr(b, e, 0) or 0 for e in _EXPONENTS) for b in (out_base, in_base)]
    if dims[0] != dims[1]:
        raise ScenarioError(f"{what}: incompatible units {out_unit!r} -> {in_unit!r} (another "
                            f"quantity: {_dimension(out_base)} vs {_dimension(in_base)})")
    f_out, f_in = float(out_base.factor or 1.0), float(in_base.factor or 1.0)
    o_out, o_in = float(out_base.offset or 0.0), float(in_base.offset or 0.0)
    return f_out / f_in, (o_out - o_in) / f_in


def _dimension(base) -> str:
    parts = [f"{e}^{getattr(base, e)}" if getattr(base, e) != 1 else e
             for e in _EXPONENTS if getattr(base, e, 0)]
    return ".".join(parts) or "1"


def convert_inputs(inst, conversions: dict[int, tuple[float, float]]) -> None:
    """Make `inst` take the inputs at these indices (of inst.inputs) converted: its own
    pull_inputs and pull_changed_inputs replaced on the instance alone, so that every
    algorithm, the rollback and the divergence check see the input in its own unit, and an
    instance without converted inputs keeps the plain copy of cosim/instances.py."""
    scale = [conversions.get(k, (1.0, 0.0)) for k in range(len(inst.inputs))]

    def value(k: int, src, idx: int) -> float:
        a, b = scale[k]
        return a * src.out_buf[idx] + b

    def pull_inputs() -> None:
        if inst.n_in:
            buf = inst.in_buf
            for k, (src, idx) in enumerate(inst.in_sources):
                buf[k] = value(k, src, idx)
            inst.set_inputs()

    def pull_changed_inputs() -> bool:
        changed = False
        buf = inst.in_buf
        for k, (src, idx) in enumerate(inst.in_sources):
            new = value(k, src, idx)
            if buf[k] != new:
                buf[k] = new
                changed = True
        if changed:
            inst.set_inputs()
        return changed

    inst.pull_inputs = pull_inputs
    inst.pull_changed_inputs = pull_changed_inputs
