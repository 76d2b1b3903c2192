"""Building .fmu files from components/: each FMU's uniquely named copy of the model code, the
reference it carries (fmi-ls-ref) and its documentation page."""
