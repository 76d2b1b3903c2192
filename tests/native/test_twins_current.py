"""Each native model is the C twin of Python files in components/ (docs/architecture.md): its
`twin-of` lines name them with the hash of their bytes when the twin was last brought along. A
Python model that changed without its twin fails here, naming both files."""
import hashlib
import re

import pytest

from tests.paths import REPO

TWIN_OF = re.compile(r"twin-of: (components/\S+\.py) sha256:([0-9a-f]{16})")
# what each native model file is the twin of, at the least (a twin may name more files)
EXPECTED = {
    "shaft.c": {"components/shaft.py"},
    "oscillator.c": {"components/oscillator.py"},
    "punch_contact.c": {"components/punch_contact.py", "components/punch_split.py"},
    "fabric.c": {"components/punch_split.py"},
    "kinematics.c": {"components/kinematics.py"},
    "punch_linkage.c": {"components/punch_linkage.py"},
    "takeup.c": {"components/takeup.py"},
    "feed.c": {"components/feed.py"},
    "carriage.c": {"components/carriage.py"},
    "parameters.c": {"components/parameters.py", "components/units.py"},
}


def _twins(path):
    return dict(TWIN_OF.findall(path.read_text()))


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_the_twin_names_the_python_files_as_they_are(name):
    path = REPO / "native" / "models" / name
    if not path.exists():
        pytest.skip(f"native/models/{name} is not written yet")
    twins = _twins(path)
    missing = EXPECTED[name] - set(twins)
    assert not missing, f"native/models/{name} does not say it is the twin of {sorted(missing)}"
    for python, recorded in twins.items():
        now = hashlib.sha256((REPO / python).read_bytes()).hexdigest()[:16]
        assert now == recorded, (
            f"{python} changed (sha256 {now}) since native/models/{name} was brought along "
            f"({recorded}): change the C twin the same way, run tests/native, then update its "
            f"twin-of line")


def test_every_native_model_is_listed():
    written = {p.name for p in (REPO / "native" / "models").glob("*.c")}
    assert written <= set(EXPECTED), f"list {sorted(written - set(EXPECTED))} in EXPECTED"
