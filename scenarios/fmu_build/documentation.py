"""documentation/index.html, FMI's place for what a user of an FMU must know: what the FMU
models, its variables with units, and what a host needs to run it (a Python FMU: libpython
loaded, a Python home). Written by `sewfmu build`; not copied into FMUs as code."""
from __future__ import annotations

import html
import zipfile

from sewfmu.components.parameters import parameter_info

HOST_NEEDS = (
    "This FMU runs its model in Python (made with pythonfmu{suffix}). Its binary is not linked to "
    "libpython: the host process must have the Python library loaded (a host written in C or "
    "C++: <code>LD_PRELOAD=/path/to/libpython3.X.so</code>) and the environment must name a "
    "Python home (<code>PYTHONHOME</code>) of Python 3.10 to 3.13. Only the standard library is "
    "used; the FMU carries its own code. A host that is a Python process (fmpy, PyFMI) has both "
    "already. Binaries: Linux x86-64 (tried), Windows x86-64 (shipped, untried). "
    "<code>sewfmu host-env</code> prints the environment for this machine.")


def _rows(items) -> str:
    return "".join(f"<tr><td><code>{html.escape(n)}</code></td><td>{html.escape(u)}</td>"
                   f"<td>{html.escape(str(d))}</td><td>{html.escape(t)}</td></tr>"
                   for n, u, d, t in items)


def page(slave_class, fmi: int) -> str:
    # every text from the code is escaped as the tables' are: a page a browser opens must not
    # take a '<' of a docstring or a name for markup (HOST_NEEDS alone is markup, written here)
    name = html.escape(slave_class.model_name or slave_class.__name__)
    doc = (slave_class.__doc__ or "").strip()
    params = parameter_info(slave_class.params_class) if slave_class.params_class else []
    stop, step = slave_class.whole_step_experiment()
    table = ("<table><tr><th>name</th><th>unit</th><th>default / start</th><th>meaning</th></tr>"
             "{}</table>")
    return (
        f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>{name}</title></head><body>\n"
        f"<h1>{name}</h1>\n<p>{html.escape(doc)}</p>\n"
        f"<h2>What a host needs</h2>\n<p>{HOST_NEEDS.format(suffix='3' if fmi == 3 else '')}</p>\n"
        f"<h2>Parameters</h2>\n"
        + table.format(_rows((p.name, p.unit, p.default, p.description) for p in params))
        + "\n<h2>Inputs</h2>\n<p>A rate input (x_dot of x) counts only while the host sets it "
          "with its value; left unset it acts as zero.</p>\n"
        + table.format(_rows((p.name, p.unit, p.start, p.description)
                             for p in slave_class.inputs))
        + "\n<h2>Outputs</h2>\n"
        + table.format(_rows((p.name, p.unit, "", p.description)
                             for p in (*slave_class.outputs, *slave_class.calculated)))
        + f"\n<p>Default experiment: 0 to {stop:g} s at steps of {step:g} s; its output is the "
          f"reference this FMU carries (extra/org.fmi-standard.fmi-ls-ref).</p>\n"
          f"<p>Made by sewfmu.</p>\n</body></html>\n")


def write(fmu_path, slave_class, fmi: int) -> None:
    with zipfile.ZipFile(fmu_path, "a", compression=zipfile.ZIP_DEFLATED) as fmu:
        fmu.writestr("documentation/index.html", page(slave_class, fmi))
