"""Master's calls outside the run they belong to, refused in one line instead of reaching FMU
instances that are not there or no longer are (a step or a restore after the run closed, or a
close from another thread mid-step or mid-opening, ended the process with SIGSEGV in pythonfmu's
binary): before and after the run, another run's snapshot, a second opening, a run part-way
through a failed step; and the progress a run reports, to its end."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from sewfmu.scenarios.cosim.fmi_calls import CosimError, Status
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.format.values import ScenarioError
from tests.cosim.test_records_at_once import _system
from tests.fake_fmu import Failing, Integrator, fake_scenario, maker


def _in_a_process(script: str) -> str:
    """What a script with real FMUs prints in a process of its own, which must end normally (a
    call on a freed instance ends it with SIGSEGV)."""
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


@pytest.mark.parametrize("count", [2.5, "3", None, -1])
def test_a_number_of_steps_that_is_not_one_is_refused_in_one_line(count):
    master, _ = _system(None)
    with master:
        with pytest.raises(ScenarioError, match=r"Master\.steps\(.*\): the number of steps"):
            master.steps(count)
        master.steps(np.int64(3))          # numpy's whole numbers are whole numbers
        assert master.k == 3


def test_stepping_outside_the_open_run_is_refused_not_made():
    master, _ = _system(None)
    with pytest.raises(CosimError, match=r"Master\.step\(\): the run is not open"):
        master.step()
    with master:
        master.steps(3)
    for call in (master.step, master.save_state, lambda: master.steps(2)):
        with pytest.raises(CosimError, match=r"the run is not open"):
            call()
    assert master.k == 3 and len(master.result().time) == 4


def test_a_step_after_the_fmus_are_freed_is_refused_not_a_crash(fmu_paths):
    # a call on a freed pythonfmu instance ended the process with SIGSEGV
    script = """
        import sys
        import sewfmu
        from sewfmu.scenarios.cosim.master import Master
        from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
        sc = sewfmu.load("punch_drive")
        with Master(sc, fmus_for(sc)) as master:
            master.steps(10)
        try:
            master.step()
        except sewfmu.Error as err:
            print(err)
    """
    out = _in_a_process(script)
    assert "the run is not open" in out


def test_questions_before_the_run_is_opened_are_refused_and_answered_after_it_closed():
    master, _ = _system(None)
    for call in (master.result, master.progress_point, master.finished):
        with pytest.raises(CosimError, match=r"the run has not been opened"):
            call()
    with master:
        master.steps(4)
    assert master.progress_point() == (4, 70) and not master.finished()
    assert len(master.result().time) == 5


def test_a_snapshot_comes_back_only_in_its_own_open_run():
    master, _ = _system(None)
    with master:
        saved = master.save_state()
        master.steps(5)
    with master:                             # opened again: the old snapshot's states are freed
        master.steps(2)
        with pytest.raises(CosimError, match=r"snapshot was not saved in this open run"):
            master.restore_state(saved)
        assert master.k == 2
    a, _ = _system(None)
    b, _ = _system(None)
    with a, b:
        a.steps(10)
        from_a = a.save_state()
        b.steps(3)
        with pytest.raises(CosimError, match=r"snapshot was not saved in this open run"):
            b.restore_state(from_a)
        assert (b.k, a.k) == (3, 10)
        b.steps(2)
        a.restore_state(from_a)               # its own: comes back
        assert b.k == 5


@pytest.mark.slow
def test_a_restore_after_the_fmus_are_freed_is_refused_not_a_crash(fmu_paths):
    script = """
        import sewfmu
        from sewfmu.scenarios.cosim.master import Master
        from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
        sc = sewfmu.load("punch_drive")
        master = Master(sc, fmus_for(sc))
        with master:
            saved = master.save_state()
            master.steps(3)
        with master:
            master.steps(1)
            try:
                master.restore_state(saved)
            except sewfmu.Error as err:
                print(err)
    """
    out = _in_a_process(script)
    assert "not saved in this open run" in out


@pytest.mark.parametrize("master", ["jacobi", "adaptive"])
def test_the_progress_reported_reaches_the_end(master):
    heard = []
    run, _ = _system(None, master=master)
    run.run(lambda done, total: heard.append((done, total)))
    assert heard and heard[-1][0] == heard[-1][1]
    assert all(0 <= done <= total for done, total in heard)


def test_a_run_open_already_is_not_opened_again():
    master, made = _system(None)
    with master:
        master.steps(10)
        for second in (master.__enter__, master.open, master.run):
            with pytest.raises(CosimError, match=r"the run is open already"):
                second()
        assert master.k == 10                  # the run goes on where it was
        master.steps(5)
        assert master.k == 15
    assert all(inst.calls[-1] == "free" for inst in made.values())
    assert [inst.calls.count("instantiate") for inst in made.values()] == [1, 1, 1]


def test_after_a_failed_step_the_run_goes_on_only_from_a_state_saved_before():
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Failing(at=0.5, status=Status.DISCARD)}
    sc = fake_scenario(models, ["a.x -> b.u", "a.x_dot -> b.u_dot", "b.x -> a.u",
                                "b.x_dot -> a.u_dot"], 1.0, 0.1)
    master = Master(sc, {}, make_instance=maker(models))
    with master:
        master.steps(3)
        saved = master.save_state()
        with pytest.raises(CosimError, match=r"b failed during step from t = 0.5"):
            master.steps(10)
        with pytest.raises(CosimError, match=r"a step from t = 0.5 s failed; the run goes on "
                                             r"only from a state saved before it"):
            master.steps(1)
        master.restore_state(saved)
        master.steps(2)                        # up to t = 0.5 again: no failure before it
        assert master.k == 5


@pytest.mark.slow
def test_closing_from_another_thread_stops_the_stepping_between_two_steps(fmu_paths):
    # the stepping thread called an FMU instance the closing thread had freed: SIGSEGV
    script = """
        import threading, time
        import sewfmu
        from sewfmu.scenarios.cosim.master import Master
        from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
        sc = sewfmu.load("punch_drive")
        sc.set_value("experiment.revolutions", 2000)     # minutes of stepping: closed within
        master = Master(sc, fmus_for(sc))
        master.__enter__()
        told = []
        def stepping():
            try:
                master.steps(10**9)
            except sewfmu.Error as err:
                told.append(str(err))
        thread = threading.Thread(target=stepping)
        thread.start()
        time.sleep(0.05)
        master.close()
        thread.join()
        print(told, master.k < master.n_steps)
    """
    out = _in_a_process(script)
    assert "the run is not open" in out and "True" in out


@pytest.mark.slow
def test_closing_or_opening_from_two_threads_at_any_moment_neither_crashes_nor_leaks(fmu_paths):
    # close() while the other thread was still opening freed what the opening then stepped
    # (SIGSEGV); two threads opening at once both "opened", the first run's instances leaked
    script = """
        import threading, time
        import sewfmu
        from sewfmu.scenarios.cosim.master import Master
        from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
        sc = sewfmu.load("punch_drive")
        sc.set_value("experiment.revolutions", 20)
        paths = fmus_for(sc)
        outcomes = []
        for delay in (0.0, 0.005, 0.02, 0.04, 0.07, 0.1):
            master = Master(sc, paths)
            def stepping():
                try:
                    with master:
                        master.steps(10**9)
                    outcomes.append("ran")
                except sewfmu.Error as err:
                    outcomes.append("refused" if "not open" in str(err) else str(err))
            thread = threading.Thread(target=stepping)
            thread.start()
            time.sleep(delay)
            master.close()
            thread.join()
        opened = []
        master = Master(sc, paths)
        def opening():
            try:
                master.open()
                opened.append("opened")
            except sewfmu.Error as err:
                opened.append("open already" if "open already" in str(err) else str(err))
        threads = [threading.Thread(target=opening) for _ in range(2)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        master.close()
        print(sorted(set(outcomes)), sorted(opened))
    """
    out = _in_a_process(script)
    outcomes, opened = eval(out.strip().replace("] [", "], ["))
    assert set(outcomes) <= {"ran", "refused"}
    assert opened == ["open already", "opened"]


def test_no_state_is_saved_part_way_through_a_failed_step_nor_restored_after_a_fatal_one():
    for status in (Status.DISCARD, Status.FATAL):
        models = {"a": Integrator(gain=1.0, x0=1.0), "b": Failing(at=0.5, status=status)}
        sc = fake_scenario(models, ["a.x -> b.u", "a.x_dot -> b.u_dot", "b.x -> a.u",
                                    "b.x_dot -> a.u_dot"], 1.0, 0.1)
        master = Master(sc, {}, make_instance=maker(models))
        with master:
            saved = master.save_state()
            with pytest.raises(CosimError, match=r"failed during step from t = 0.5"):
                master.steps(10)
            with pytest.raises(CosimError, match=r"save_state\(\): a step from t = 0.5 s "
                                                 r"failed"):
                master.save_state()
            if status == Status.FATAL:
                with pytest.raises(CosimError, match=r"b failed fatally"):
                    master.restore_state(saved)
            else:
                master.restore_state(saved)
                master.steps(5)
                assert master.k == 5
