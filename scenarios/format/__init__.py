"""The scenario format: the Scenario data model and its clock, the TOML parser and its checks,
values with units, the experiment's keys and each master's settings, where scenarios come from
(the catalogue, a file, an SSP system). Imports nothing of the engine, runs or interop."""
