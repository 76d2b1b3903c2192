"""The FMUs sewfmu builds: model name -> (module in this package, slave class)."""
import importlib

FMUS: dict[str, tuple[str, str]] = {
    "MainShaft": ("shaft_fmu", "MainShaftSlave"),
    "PunchLinkage": ("punch_fmu", "PunchLinkageSlave"),
    "PunchContact": ("punch_fmu", "PunchContactSlave"),
    "TakeupLinkage": ("takeup_fmu", "TakeupLinkageSlave"),
    "FeedLinkage": ("feed_fmu", "FeedLinkageSlave"),
    "CarriageDrive": ("carriage_fmu", "CarriageDriveSlave"),
    "CarriageModal": ("carriage_fmu", "CarriageModalSlave"),
}


def parameters_of(fmu: str) -> list:
    """The declared parameters (ParameterInfo: name, default, unit, ...) of an FMU."""
    from .parameters import parameter_info

    module, slave = FMUS[fmu]
    slave_class = getattr(importlib.import_module(f"{__package__}.{module}"), slave)
    return parameter_info(slave_class.params_class) if slave_class.params_class else []
