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
    """Make `inst` take the inputs at these indices (of inst.inputs) converted: every
    algorithm, the rollback and the divergence check then see the input in its own unit."""
    inst.in_scales = [conversions.get(k, (1.0, 0.0)) for k in range(len(inst.inputs))]
