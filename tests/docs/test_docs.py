"""The documentation stands alone and stays true to the code: every parameter of every FMU is in
its mechanism's page with its default, every link and picture resolves, and no file points
outside the repository."""
import math
import re
from pathlib import Path

import pytest

from sewfmu.components.carriage import CarriageDriveParams, CarriageParams
from sewfmu.components.feed import FeedParams
from sewfmu.components.parameters import parameter_info
from sewfmu.components.punch_contact import PunchContactParams
from sewfmu.components.punch_linkage import PunchLinkageParams
from sewfmu.components.punch_split import FabricParams, PunchBodyParams
from sewfmu.components.shaft import ShaftParams
from sewfmu.components.takeup import TakeupParams
from tests.paths import REPO

PAGES = {"punch_drive.md": (ShaftParams, PunchLinkageParams, PunchContactParams, PunchBodyParams,
                            FabricParams),
         "carriage.md": (CarriageParams, CarriageDriveParams),
         "feed.md": (FeedParams,), "takeup.md": (TakeupParams,)}


@pytest.mark.parametrize("page", list(PAGES))
def test_every_parameter_is_documented_with_its_default(page):
    text = (REPO / "docs" / page).read_text(encoding="utf-8")
    for params in PAGES[page]:
        for info in parameter_info(params):
            row = re.search(rf"^\| `{info.name}` \| ([^|]+) \|", text, re.M)
            assert row, (page, info.name)
            shown = float(row.group(1).split()[0])
            assert math.isclose(shown, info.default, rel_tol=1e-5, abs_tol=1e-12), \
                (page, info.name, row.group(1))


def test_links_and_pictures_resolve():
    for doc in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for target in re.findall(r"\]\(([^)#]+)\)", doc.read_text(encoding="utf-8")):
            if "://" in target:
                continue
            assert (doc.parent / target).exists(), (doc.name, target)


@pytest.mark.slow
def test_no_file_points_outside_the_repository():
    # the team's specification folder beside the repository, named without writing its path
    # here (this file would otherwise point there itself)
    outside = "/".join(("..", "shared"))
    for path in REPO.rglob("*"):
        if (path.is_file() and path.suffix in (".py", ".md", ".toml", ".txt", ".cfg")
                and path != Path(__file__).resolve()
                and not {".venv", ".git", "fmus", "results"} & set(path.relative_to(REPO).parts)):
            text = path.read_text(encoding="utf-8", errors="replace")
            assert outside not in text and "MECHANISMS.md" not in text, path


def python_blocks(page: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"), re.M | re.S)


@pytest.mark.slow
def test_the_example_notebook_runs(tmp_path, fmu_paths):
    """examples/punch_drive.ipynb executed as Jupyter would (nbclient, a Python kernel), in an
    empty folder: a run, a sweep and their plots, with the checks in its last cell."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.read(REPO / "examples" / "punch_drive.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    images = [o for cell in notebook.cells for o in cell.get("outputs", [])
              if "image/png" in o.get("data", {})]
    assert len(images) == 2


def _documented_keys(section: str) -> set[str]:
    text = (REPO / "docs" / "scenarios.md").read_text(encoding="utf-8")
    part = text.split(f"## {section}\n", 1)[1].split("\n## ", 1)[0]
    return set(re.findall(r"^\| `([a-z_]+)` \|", part, re.M))


def test_every_key_of_the_scenario_format_is_documented():
    """docs/scenarios.md has a row (meaning, default, example) for every key the format reads,
    and none it does not."""
    from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS
    from sewfmu.scenarios.format.parse import COMPARE_KEYS, INSTANCE_KEYS, SWEEP_KEYS, TOP_KEYS

    assert _documented_keys("The top level") == set(TOP_KEYS)
    assert _documented_keys("[experiment]") == set(EXPERIMENT_KEYS)
    assert _documented_keys("[instances.NAME]") == set(INSTANCE_KEYS)
    assert _documented_keys("[compare]") == set(COMPARE_KEYS)
    assert _documented_keys("[sweep]") == set(SWEEP_KEYS)


def test_the_scenario_pages_example_runs_with_its_units(tmp_path, fmu_paths):
    """The example of docs/scenarios.md, with values in rpm, ms and N/mm, runs as the same
    scenario written in SI units."""
    import sewfmu

    text = (REPO / "docs" / "scenarios.md").read_text(encoding="utf-8")
    example = re.search(r"^```toml\n(.*?)^```", text, re.M | re.S).group(1)
    (tmp_path / "example.toml").write_text(example)
    si = (example.replace('"955 rpm"', repr(955 * 2 * math.pi / 60))
          .replace('"0.25 ms"', "0.25e-3").replace('"150 N/mm"', "150e3"))
    (tmp_path / "si.toml").write_text(si)
    with_units = sewfmu.run(tmp_path / "example.toml")
    plain = sewfmu.run(tmp_path / "si.toml")
    assert with_units.figures["F2_peak"] == plain.figures["F2_peak"]
    assert with_units.units["F2_peak"] == "N"
