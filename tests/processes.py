"""The processes of a process group or a session, from Linux's /proc (zombies left out): what
the tests of `sewfmu app` look at to see that nothing the server started is left running."""
from pathlib import Path

# fields of /proc/PID/stat after the command's ")": state, ppid, pgrp, session
_FIELD = {"group": 2, "session": 3}


def processes_in(kind: str, ident: int) -> list[int]:
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[_FIELD[kind]]) == ident and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found
