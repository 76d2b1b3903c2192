"""What a run does not do (issue 38): import the builders to check that its FMUs are current,
or repeat the punch six-bar's assembly check that the build made for the default parameters;
and the lean slave layer's tables give what its getters and setters gave."""
import subprocess
import sys
import zipfile

from sewfmu.components.punch_linkage import PunchLinkageParams, _top_of


def test_the_up_to_date_check_imports_no_builder(fmu_dir):
    """fmus_for_names on current FMUs: neither pythonfmu, pythonfmu3 nor build.py is imported."""
    code = ("import sys\n"
            "from pathlib import Path\n"
            "from sewfmu.scenarios.fmu_build.up_to_date import fmus_for_names\n"
            f"paths = fmus_for_names(['MainShaft', 'PunchLinkage'], Path({str(fmu_dir)!r}))\n"
            "assert all(p.exists() for p in paths.values())\n"
            "loaded = [m for m in ('pythonfmu', 'pythonfmu3', 'xml.dom.minidom',\n"
            "          'sewfmu.scenarios.fmu_build.build', 'sewfmu.scenarios.format.ssp_import')\n"
            "          if m in sys.modules]\n"
            "assert not loaded, loaded\n")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_fmu_carries_the_assembly_check_of_its_default_parameters(fmu_paths):
    """assembly_table.py in the FMU: exactly _top_of's answer for the defaults (repr: bit for
    bit), which an instance with those parameters takes instead of checking 3600 angles."""
    with zipfile.ZipFile(fmu_paths["PunchLinkage"]) as fmu:
        name = next(n for n in fmu.namelist() if n.endswith("/assembly_table.py"))
        table: dict = {}
        exec(fmu.read(name).decode(), table)
    params = PunchLinkageParams()
    assert table["BUILT_TOPS"] == {repr(params): _top_of.__wrapped__(params)}


def test_the_slave_tables_answer_as_the_getters(fmu_paths):
    """The row of outputs read through the value-reference tables, and the setters' one pass,
    against each variable's own getter and setter (a PunchContact, stepped)."""
    from sewfmu.components.fmi2_layer import Fmi2Layer
    from sewfmu.components.punch_fmu import PunchContactSlave

    cls = type("PunchContactTest", (PunchContactSlave, Fmi2Layer), {"__doc__": "test"})
    fast, slow = cls(instance_name="fast"), cls(instance_name="slow")
    inputs = [v.value_reference for v in fast.vars.values() if v.causality.name == "input"]
    outputs = [v.value_reference for v in fast.vars.values() if v.causality.name == "output"]
    reals = [vr for vr in outputs if fast._kinds[vr] == "Real"]
    booleans = [vr for vr in outputs if fast._kinds[vr] == "Boolean"]
    for s in (fast, slow):
        s.setup_experiment(0.0)
        s.exit_initialization_mode()
    for k in range(200):
        values = [4.5e-3 - 1e-3 * (k * 1e-4) ** 0.5, -0.05, -40.0]
        fast.set_real(inputs, values)
        for vr, x in zip(inputs, values):
            slow._setters[vr](x)
        assert fast.do_step(k * 1e-4, 1e-4) and slow.do_step(k * 1e-4, 1e-4)
        assert fast.get_real(reals) == [float(slow._getters[vr]()) for vr in reals]
        assert fast.get_boolean(booleans) == [bool(slow._getters[vr]()) for vr in booleans]
    assert fast._get_fmu_state() == slow._get_fmu_state()
