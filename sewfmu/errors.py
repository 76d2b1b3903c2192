"""sewfmu's one error family: every refusal of bad input and every failed run is an `Error`
whose message is one line that says what was wrong and what would be accepted.

    Error
      ScenarioError   a scenario, a value, an option or a file sewfmu was given
      CosimError      a co-simulation that failed (an FMU refused, a coupling diverged)
      OutputError     a folder or file sewfmu cannot write where it was asked to
      HostError       another FMI host that cannot run (interop)

The subclasses live beside the code that raises them; this module holds their base and
ScenarioError, which every wing raises, so that every wing can import them (it imports nothing).
"""


class Error(Exception):
    """A refusal or failure sewfmu explains in one line (str(err))."""


class ScenarioError(Error, ValueError):
    """A scenario that cannot run, with the file and key it comes from."""
