"""Whatever a scenario file, an SSP archive or an FMU's modelDescription holds, sewfmu answers with
a scenario or with one ScenarioError line: never another exception (hypothesis writes the files;
the reference CSV and .opt parsers have theirs in tests/references/test_reference_files.py)."""
import zipfile

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.parse import from_dict
from sewfmu.scenarios.format.values import ScenarioError

FUZZ = settings(max_examples=60, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])

scalars = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True),
                    st.text(max_size=20))
tables = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=12), inner, max_size=4)),
    max_leaves=20)
keys = st.sampled_from(["description", "analysis", "roles", "connections", "record",
                        "experiment", "instances", "compare", "sweep", "x"])


def _answers(call):
    try:
        call()
    except ScenarioError as err:
        assert "\n" not in str(err).strip()


@FUZZ
@given(st.text(max_size=300))
def test_any_text_as_a_scenario_file(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_bytes(text.encode("utf-8", "replace"))
    _answers(lambda: load(str(path)))


@FUZZ
@given(st.dictionaries(keys, tables, max_size=6))
def test_any_tables_as_a_scenario(data):
    _answers(lambda: from_dict(data, "fuzz", "fuzz.toml"))


@FUZZ
@given(st.dictionaries(st.sampled_from(["step", "master", "revolutions", "stop_time", "shaft",
                                        "tolerance", "acceleration", "record_every", "fmi", "fmus",
                                        "accuracy", "accept_error"]), scalars, max_size=6))
def test_any_experiment_table(experiment):
    data = {"instances": {"shaft": {"fmu": "MainShaft"}}, "experiment": experiment}
    _answers(lambda: from_dict(data, "fuzz", "fuzz.toml"))


@FUZZ
@given(st.binary(max_size=400))
def test_any_bytes_as_an_ssp_system(tmp_path, blob):
    path = tmp_path / "s.ssp"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("SystemStructure.ssd", blob)
    _answers(lambda: load(str(path)))


@FUZZ
@given(st.binary(max_size=300))
def test_any_bytes_as_an_fmus_model_description(tmp_path, blob):
    ssd = ('<?xml version="1.0"?><ssd:SystemStructureDescription version="1.0" name="s" '
           'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">'
           '<ssd:System name="s"><ssd:Elements><ssd:Component name="c" '
           'source="resources/C.fmu"/></ssd:Elements></ssd:System>'
           '</ssd:SystemStructureDescription>')
    fmu = tmp_path / "C.fmu"
    with zipfile.ZipFile(fmu, "w") as archive:
        archive.writestr("modelDescription.xml", blob)
    path = tmp_path / "s.ssp"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        archive.write(fmu, "resources/C.fmu")
    _answers(lambda: load(str(path)))
