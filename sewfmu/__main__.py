"""`sewfmu` and `python -m sewfmu`: the command line, answering Ctrl-C from its first moment.

Until sewfmu.cli.main takes over (it turns SIGINT and SIGTERM into a clean stop of whatever
runs), a signal ends the process at once with one line: nothing has been run or written yet.
The handlers are put in place as this module is imported by the console script (before the rest
of its imports); what comes before it is Python's own start-up (the interpreter, site and the
editable install's finder: about 20 ms on this project's machine), where no code of sewfmu's can
answer a signal (docs/running.md, Reliability).
"""
import os
import signal
import sys


def _stopped_while_starting(signum, frame) -> None:
    os.write(2, f"sewfmu: interrupted ({signal.Signals(signum).name}) while starting; "
                f"nothing was run\n".encode())
    os._exit(128 + signum)


def _answer_from_now() -> None:
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _stopped_while_starting)


# the console script (`sewfmu`) and `python -m sewfmu`: from the first line of sewfmu's own code
# (a test importing this module keeps its handlers)
if __name__ == "__main__" or os.path.basename(sys.argv[0] if sys.argv else "") == "sewfmu":
    _answer_from_now()


def main(argv=None) -> int:
    _answer_from_now()
    from sewfmu.cli import main as command_line  # after the handlers: imports take a moment

    try:
        return command_line(argv, guard=_stopped_while_starting)
    finally:
        # the command is over (its line said): a signal now, a terminal's second Ctrl-C or the
        # guarding process's copy of the first, would only kill the exit half-way (Python puts
        # SIG_DFL back for its finalization; an ignored signal stays ignored)
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN)


if __name__ == "__main__":
    sys.exit(main())
