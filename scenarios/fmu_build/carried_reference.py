"""The reference an FMU carries (FMI's layered standard fmi-ls-ref, as the Modelica
Reference-FMUs ship it): the output of its default experiment, `<Model>_out.csv`, and the
manifest that names it, in `extra/org.fmi-standard.fmi-ls-ref/` inside the FMU. Any tool can run
the FMU's DefaultExperiment and compare (`sewfmu references --fmu X.fmu` does).

`sewfmu build` writes it: the slave class is run here, in the builder's process, through the
same Python methods the FMU's binary calls (exitInitializationMode, doStep, the getters), from
the start values, at the DefaultExperiment's step. Built, not copied into FMUs (scenarios/fmu_build/build.py
leaves this module out).
"""
from __future__ import annotations

import csv
import io
import math
import zipfile

LS_REF = "extra/org.fmi-standard.fmi-ls-ref"
MANIFEST = f"{LS_REF}/fmi-ls-manifest.xml"

_MANIFEST_XML = """<?xml version="1.0" encoding="UTF-8"?>
<fmiReferences
    xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
    xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref"
    fmi-ls:fmi-ls-version="1.0.0-alpha.1">
    <Related type="text/csv" source="{csv}" role="result" description="Output of the default experiment"/>
</fmiReferences>
"""


def default_experiment_output(slave_class, layer_class) -> str:
    """The CSV (time and every output) of the slave class, joined with the FMI 2.0 layer of the
    same copy of the code, run alone for its DefaultExperiment, one row per communication
    point."""
    cls = type(slave_class.model_name or slave_class.__name__, (slave_class, layer_class),
               {"__doc__": slave_class.__doc__})
    slave = cls(instance_name="reference", resources=None)
    stop, step = cls.whole_step_experiment()
    outputs = [v for v in slave.variables if v.causality == "output"]
    slave.setup_experiment(0.0, stop)
    slave.exit_initialization_mode()
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["time", *(v.name for v in outputs)])
    steps = max(1, math.ceil(stop / step * (1.0 - 1e-12)))
    times = [stop if k == steps else k * step for k in range(steps + 1)]
    for k, t in enumerate(times):
        writer.writerow([repr(t), *(_text(v.getter()) for v in outputs)])
        if k < steps and not slave.do_step(t, times[k + 1] - t):
            raise RuntimeError(f"{cls.__name__}: its default experiment failed at t = {t:g} s")
    return text.getvalue()


def _text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value))


def carry(fmu_path, model_name: str, output_csv: str) -> None:
    """Put the reference and its manifest into the FMU file."""
    name = f"{model_name}_out.csv"
    with zipfile.ZipFile(fmu_path, "a", compression=zipfile.ZIP_DEFLATED) as fmu:
        fmu.writestr(MANIFEST, _MANIFEST_XML.format(csv=name))
        fmu.writestr(f"{LS_REF}/{name}", output_csv)
