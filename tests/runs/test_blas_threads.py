"""`sewfmu run` asks numpy's OpenBLAS for one thread (sewfmu/cli.py: its thread pool busy-waits
about 0.1 s of CPU at import, and a run does no linear algebra), unless the user chose."""
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc/self/task"),
                                reason="counts threads in /proc (Linux)")

# the process's threads that Python did not start (BLAS's), plus the main one: sewfmu's own
# watchdog thread (scenarios/cosim/watchdog.py) is Python's and stays for the process's life
PROBE = ("import os, sys, threading\nfrom sewfmu.cli import main\n"
         "status = main(['run', 'punch_drive', '--set', 'experiment.revolutions=1', '--set', "
         "'experiment.accuracy=off', '--out', sys.argv[1]])\n"
         "print(status, len(os.listdir('/proc/self/task')) - len(threading.enumerate()) + 1)")


def _threads(tmp_path, **env) -> tuple[str, int]:
    base = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS",
                                                           "OMP_NUM_THREADS", "GOTO_NUM_THREADS")}
    done = subprocess.run([sys.executable, "-c", PROBE, str(tmp_path / "out")],
                          env={**base, **env}, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-1500:]
    status, threads = done.stdout.split()[-2:]
    return status, int(threads)


def test_a_run_has_no_blas_threads_but_where_the_user_asks(tmp_path):
    assert _threads(tmp_path) == ("0", 1)
    # the user's choice stands (numpy's OpenBLAS then starts its threads: more than one)
    assert _threads(tmp_path, OPENBLAS_NUM_THREADS="2")[1] > 1
