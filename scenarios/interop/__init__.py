"""sewfmu with other tools: a scenario as an SSP archive or as one container FMU, the scenario run
in other FMI hosts (libcosim, ecos) and checked against sewfmu's own run."""
