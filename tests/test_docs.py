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

REPO = Path(__file__).resolve().parent.parent
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


def test_no_file_points_outside_the_repository():
    for path in REPO.rglob("*"):
        if (path.is_file() and path.suffix in (".py", ".md", ".toml", ".txt", ".cfg")
                and path != Path(__file__).resolve()
                and not {".venv", ".git", "fmus", "results"} & set(path.relative_to(REPO).parts)):
            text = path.read_text(encoding="utf-8", errors="replace")
            assert "../shared" not in text and "MECHANISMS.md" not in text, path
