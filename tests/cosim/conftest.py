"""What the tests of the way out of a stuck FMU share in this process."""
import time

import pytest

from sewfmu.scenarios.cosim import watchdog


@pytest.fixture
def hook():
    """The watchdog's end as a sewfmu process has it, recording instead of ending pytest: a list
    of (what it was handed, when); it releases the blocked models it is given."""
    handed, models = [], []

    def end(err):
        handed.append((err, time.monotonic()))
        for model in models:
            model.release.set()

    end.handed, end.models = handed, models
    watchdog.end_process_with(end)
    yield end
    watchdog.end_process_with(None)
