"""The FMUs sewfmu builds: model name -> (module in this package, slave class)."""

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
