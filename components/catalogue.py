"""The FMUs sewfmu builds: model name -> (module in this package, slave class)."""

FMUS: dict[str, tuple[str, str]] = {
    "MainShaft": ("shaft_fmu", "MainShaftSlave"),
    "PunchLinkage": ("punch_fmus", "PunchLinkageSlave"),
    "PunchContact": ("punch_fmus", "PunchContactSlave"),
    "TakeupLinkage": ("takeup_fmu", "TakeupLinkageSlave"),
    "FeedLinkage": ("feed_fmu", "FeedLinkageSlave"),
    "CarriageDrive": ("carriage_fmus", "CarriageDriveSlave"),
    "CarriageModal": ("carriage_fmus", "CarriageModalSlave"),
}
