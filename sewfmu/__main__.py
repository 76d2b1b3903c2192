"""`sewfmu` and `python -m sewfmu`: the command line, answering Ctrl-C from its first moment.

Until sewfmu.cli.main takes over (it turns SIGINT and SIGTERM into a clean stop of whatever
runs), a signal ends the process at once with one line: nothing has been run or written yet.
"""
import os
import signal
import sys


def _stopped_while_starting(signum, frame) -> None:
    sys.stderr.write(f"sewfmu: interrupted ({signal.Signals(signum).name}) while starting; "
                     f"nothing was run\n")
    os._exit(128 + signum)


def main(argv=None) -> int:
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _stopped_while_starting)
    from sewfmu.cli import main as command_line  # after the handlers: imports take a moment

    return command_line(argv, guard=_stopped_while_starting)


if __name__ == "__main__":
    sys.exit(main())
