"""Regression references: sewfmu's shipped ones (regression_references/), reference files of any
FMU (FMI Cross-Check layout, fmi-ls-ref), which references an FMU is checked against, the pytest
fixture fmu_reference."""
