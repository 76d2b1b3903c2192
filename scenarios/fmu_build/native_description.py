"""What a native FMU declares, made from the Python FMU of the same name and FMI version: its
modelDescription.xml (the same variables, units, ranges and DefaultExperiment, a token of its
own, the capabilities of the C runtime, its sources) and description.c, the table
SEW_DESCRIPTION the runtime reads (native/runtime/sew_model.h), from that XML and the Python
slave class (which of the model's arrays each variable is in, the Taylor chains)."""
from __future__ import annotations

import datetime
import math
import uuid
from xml.etree import ElementTree
from xml.etree.ElementTree import Element, SubElement

from sewfmu.components.parameters import parameter_info

TOKEN_PLACEHOLDER = "@TOKEN@"
_KINDS = {"Real": "SEW_REAL", "Float64": "SEW_REAL", "Integer": "SEW_INTEGER",
          "Int32": "SEW_INTEGER", "Boolean": "SEW_BOOLEAN"}
_CAUSALITIES = {"parameter": "SEW_PARAMETER", "input": "SEW_INPUT", "output": "SEW_OUTPUT",
                "calculatedParameter": "SEW_CALCULATED", "independent": "SEW_INDEPENDENT"}


def token_of(digest: bytes, fmi: int) -> str:
    """The FMU's GUID (FMI 2.0) or instantiationToken (FMI 3.0, in braces as the Python FMUs
    write it) from the hash of what it is made of: the same sources give the same token."""
    text = str(uuid.UUID(bytes=digest[:16], version=5))
    return f"{{{text}}}" if fmi == 3 else text


def variables_of(root: Element, fmi: int) -> list[dict]:
    """Each variable of a modelDescription as a dict: name, vr, type, causality, start, min,
    max, unit (the attributes as written)."""
    found = []
    for sv in root.find("ModelVariables"):
        if fmi == 2:
            typed = next(iter(sv))
            attrib = {**typed.attrib, **sv.attrib}
            kind = typed.tag
        else:
            attrib, kind = dict(sv.attrib), sv.tag
        found.append({"name": attrib["name"], "vr": int(attrib["valueReference"]), "type": kind,
                      "causality": attrib.get("causality", "local"),
                      "start": attrib.get("start"), "min": attrib.get("min"),
                      "max": attrib.get("max"), "unit": attrib.get("unit", "")})
    return found


def _places(slave_class) -> dict[str, tuple[str, int]]:
    """name -> (causality, index in the model's array) from the slave class's declarations."""
    params = parameter_info(slave_class.params_class) if slave_class.params_class else []
    places = {p.name: ("parameter", i) for i, p in enumerate(params)}
    places.update({p.name: ("input", i) for i, p in enumerate(slave_class.inputs)})
    places.update({p.name: ("output", i) for i, p in enumerate(slave_class.outputs)})
    n_out = len(slave_class.outputs)
    places.update({p.name: ("calculatedParameter", n_out + i)
                   for i, p in enumerate(slave_class.calculated)})
    return places


def _c_string(text: str) -> str:
    """A C string literal of the text's UTF-8 bytes (octal escapes beyond printable ASCII)."""
    out = []
    for byte in text.encode("utf-8"):
        char = chr(byte)
        out.append(f"\\{byte:03o}" if byte > 126 or byte < 32 or char in '"\\?' else char)
    return '"' + "".join(out) + '"'


def _c_double(text: str | None, default: str) -> str:
    if text is None:
        return default
    value = float(text)
    if not math.isfinite(value):
        return "HUGE_VAL" if value > 0 else "-HUGE_VAL"
    return repr(value)          # the shortest text that reads back as the same double


def description_c(root: Element, fmi: int, slave_class, model_symbol: str) -> str:
    """description.c for one FMU, with TOKEN_PLACEHOLDER where the token goes (the token is a
    hash of this text and the other sources)."""
    places = _places(slave_class)
    rows = []
    for v in variables_of(root, fmi):
        if v["causality"] == "independent":
            index = 0
        else:
            declared, index = places[v["name"]]
            if declared != v["causality"]:
                raise ValueError(f"{v['name']}: the modelDescription says {v['causality']}, "
                                 f"the slave class {declared}")
        if v["type"] not in _KINDS:
            raise ValueError(f"{v['name']}: type {v['type']} has no place in the C runtime")
        start = _c_double(v["start"] if v["start"] not in ("true", "false") else None, "0.0")
        rows.append(f"    {{{_c_string(v['name'])}, {v['vr']}u, {_KINDS[v['type']]}, "
                    f"{_CAUSALITIES[v['causality']]}, {index}, {start}, "
                    f"{_c_double(v['min'], '-HUGE_VAL')}, {_c_double(v['max'], 'HUGE_VAL')}, "
                    f"{_c_string(v['unit'])}}},")
    inputs = [p.name for p in slave_class.inputs]
    chains = [[inputs.index(n) for n in chain] + [-1] * (3 - len(chain))
              for chain in slave_class.taylor_inputs]
    if any(len(c) != 3 for c in chains):
        raise ValueError(f"{slave_class.__name__}: a Taylor chain longer than 3 inputs")
    chain_rows = "".join(f"    {{{a}, {b}, {c}}},\n" for a, b, c in chains) or "    {-1, -1, -1},\n"
    params = parameter_info(slave_class.params_class) if slave_class.params_class else []
    n_row = len(slave_class.outputs) + len(slave_class.calculated)
    name = slave_class.model_name
    return (f"/* Written by sewfmu build --native from the modelDescription of the Python FMU "
            f"{name}:\n   its variables, where each is in the model's arrays, its Taylor chains "
            f"(sew_model.h). */\n"
            "#include <math.h>\n\n#include \"sew_model.h\"\n\n"
            f"extern const SewModel {model_symbol};\n\n"
            "static const SewVariable VARIABLES[] = {\n" + "\n".join(rows) + "\n};\n\n"
            f"static const int CHAINS[][3] = {{\n{chain_rows}}};\n\n"
            "const SewDescription SEW_DESCRIPTION = {\n"
            f"    {_c_string(name)}, \"{TOKEN_PLACEHOLDER}\", &{model_symbol},\n"
            f"    {len(rows)}, VARIABLES,\n"
            f"    {len(params)}, {len(inputs)}, {n_row},\n"
            f"    {len(chains)}, CHAINS,\n}};\n")


def native_model_description(python_xml: bytes, fmi: int, token: str, version: str,
                             sources: list[str]) -> bytes:
    """The Python FMU's modelDescription with the native FMU's own token, version, tool and
    capabilities (and, for FMI 2.0, its source files): everything a host reads of the
    variables stays as it was."""
    root = ElementTree.fromstring(python_xml)
    root.set("guid" if fmi == 2 else "instantiationToken", token)
    root.set("version", version)
    root.set("generationTool", "sewfmu build --native (C99)")
    root.set("generationDateAndTime",
             datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"))
    cs = root.find("CoSimulation")
    identifier = cs.get("modelIdentifier")
    cs.clear()
    if fmi == 2:
        cs.attrib.update({
            "modelIdentifier": identifier, "needsExecutionTool": "false",
            "canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "false",
            "canBeInstantiatedOnlyOncePerProcess": "false",
            "canNotUseMemoryManagementFunctions": "true", "canGetAndSetFMUstate": "true",
            "canSerializeFMUstate": "true"})
        files = SubElement(cs, "SourceFiles")
        for name in sources:
            if name.endswith(".c"):
                SubElement(files, "File", name=name)
    else:
        cs.attrib.update({
            "modelIdentifier": identifier, "needsExecutionTool": "false",
            "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
            "canSerializeFMUState": "true", "canHandleVariableCommunicationStepSize": "true"})
    ElementTree.indent(root, space="\t")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ElementTree.tostring(root,
                                                                              encoding="utf-8")


def build_description_xml(model_identifier: str, sources: list[str]) -> str:
    """FMI 3.0's sources/buildDescription.xml: the C files of the FMU, compiled together."""
    files = "".join(f'      <SourceFile name="{name}"/>\n' for name in sources
                    if name.endswith(".c"))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiBuildDescription fmiVersion="3.0">
  <BuildConfiguration modelIdentifier="{model_identifier}" description="C99, the C library and \
libm only; compile with floating-point contraction off (-ffp-contract=off) for the Python \
FMU's numbers">
    <SourceFileSet language="C99" compilerOptions="-ffp-contract=off">
{files}    </SourceFileSet>
    <Library name="m"/>
  </BuildConfiguration>
</fmiBuildDescription>
"""
