"""The display units the FMUs declare (components/units.py's DISPLAY_UNITS, written into every
modelDescription as <DisplayUnit factor=...>) against pint's own conversion, which shares no
code with sewfmu's table: a factor one digit off (rpm 9.55 for 9.5493, N.s/mm 1e-2 for 1e-3)
shows in another FMI tool as a value off by that much, however right the host's own runs are."""
import re
import xml.etree.ElementTree as ET
import zipfile

import pint
import pytest

from sewfmu.components.units import DISPLAY_UNITS

UREG = pint.UnitRegistry()
# sewfmu's spellings that are not pint's: a stitch a revolution of the main shaft
WORDS = {"rpm": "revolution/minute", "st/min": "revolution/minute", "rev": "revolution",
         "um": "micrometer"}


def _pint(unit: str) -> str:
    if unit in WORDS:
        return WORDS[unit]
    text = unit.replace(".", "*")
    return re.sub(r"([a-zA-Z])(\d)", r"\1**\2", text)          # m2 -> m**2


def _factor(si: str, display: str) -> float:
    return UREG.Quantity(1.0, _pint(si)).to(_pint(display)).magnitude


@pytest.mark.parametrize("si, display", [(si, d) for si, ds in DISPLAY_UNITS.items() for d in ds])
def test_every_display_factor_is_pints(si, display):
    assert DISPLAY_UNITS[si][display] == pytest.approx(_factor(si, display), rel=1e-12)


def test_every_fmu_declares_the_factors_pint_gives(fmu_paths):
    checked = 0
    for name, path in fmu_paths.items():
        with zipfile.ZipFile(path) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
        for unit in root.iter("Unit"):
            for shown in unit.iter("DisplayUnit"):
                factor = float(shown.get("factor", "1"))
                assert factor == pytest.approx(_factor(unit.get("name"), shown.get("name")),
                                               rel=1e-12), (name, unit.get("name"),
                                                            shown.get("name"))
                checked += 1
    assert checked >= 10
