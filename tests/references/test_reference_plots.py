"""`sewfmu references --fmu X --plot DIR` follows the output folder's one rule: a picture of a
name the user's own file has in DIR is refused in one line, the file left byte for byte; a
second check into DIR replaces the pictures the first drew there."""
import pytest

from tests.references.test_references import _sewfmu, _spring

pytestmark = pytest.mark.slow           # FMUs built by pythonfmu, and sewfmu in a subprocess


def test_a_users_picture_survives_and_a_second_check_replaces_its_own(tmp_path):
    original, changed = _spring(tmp_path, 40.0, "v1"), _spring(tmp_path, 40.4, "v2")
    refs, plots = tmp_path / "refs", tmp_path / "plots"
    assert _sewfmu("--fmu", original, "--refs", refs, "--regenerate", cwd=tmp_path).returncode == 0
    plots.mkdir()
    (plots / "Spring_differences.png").write_bytes(b"the user's own picture")
    caught = _sewfmu("--fmu", changed, "--refs", refs, "--plot", plots, cwd=tmp_path)
    assert caught.returncode == 1
    err = caught.stderr.strip().splitlines()
    assert len(err) == 1 and "Spring_differences.png there is not from sewfmu's last run" in err[0]
    assert (plots / "Spring_differences.png").read_bytes() == b"the user's own picture"
    (plots / "Spring_differences.png").unlink()
    for _ in range(2):                  # the second replaces the first's picture
        caught = _sewfmu("--fmu", changed, "--refs", refs, "--plot", plots, cwd=tmp_path)
        assert caught.stderr.strip() == "sewfmu: error: 2 variables deviate from their references"
        assert f"wrote {plots / 'Spring_differences.png'}" in caught.stdout
    assert sorted(p.name for p in plots.iterdir()) == [".sewfmu-outputs", "Spring_differences.png"]
