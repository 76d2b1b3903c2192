"""The punch drive split at the fabric (PunchBody + Fabric): the same figures and plots as the
punch drive's, read from the body (y) and the fabric (F2, contact, its peak hold)."""
from . import Mechanism
from .punch import FIGURES, plot, summary_of_monolithic, summary_of_run  # noqa: F401

MECHANISM = Mechanism(
    roles={"shaft": "MainShaft", "linkage": "PunchLinkage", "body": "PunchBody",
           "fabric": "Fabric"},
    figures=FIGURES, animation="punch", monolithic=True)
