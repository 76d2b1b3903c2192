"""The FMUs sewfmu builds: model name -> (module in this package, slave class)."""

import importlib

FMUS: dict[str, tuple[str, str]] = {
    "MainShaft": ("shaft_fmu", "MainShaftSlave"),
    "PunchLinkage": ("punch_fmu", "PunchLinkageSlave"),
    "PunchContact": ("punch_fmu", "PunchContactSlave"),
    "PunchBody": ("punch_fmu", "PunchBodySlave"),
    "Fabric": ("punch_fmu", "FabricSlave"),
    "TakeupLinkage": ("takeup_fmu", "TakeupLinkageSlave"),
    "FeedLinkage": ("feed_fmu", "FeedLinkageSlave"),
    "CarriageDrive": ("carriage_fmu", "CarriageDriveSlave"),
    "CarriageModal": ("carriage_fmu", "CarriageModalSlave"),
}


# the FMI versions each of them is built for (`sewfmu build --fmi 3`: fmus/fmi3/)
FMI_VERSIONS = (2, 3)


def parameter_units(fmu: str) -> dict[str, str]:
    """The declared unit of every parameter and input of one of sewfmu's FMUs, from its slave
    class (no FMU needs to be built to read them)."""
    from .parameters import parameter_info  # the registry is read without the models

    module, slave = FMUS[fmu]
    cls = getattr(importlib.import_module(f"{__package__}.{module}"), slave)
    units = {info.name: info.unit for info in parameter_info(cls.params_class)} \
        if cls.params_class else {}
    units.update({port.name: port.unit for port in cls.inputs})
    return units
