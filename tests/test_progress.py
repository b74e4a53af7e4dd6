"""Progress through a callback (issue 25, "the engine returns data, not files"): simulate
sends gpme_core.progress events and prints nothing; gpme_io.progress turns them into the
terminal's bar, a log's few lines and the compile notice."""
import pytest

from gpme_core import run_cost
from gpme_core.errors import ModelError
from gpme_core.integrate import SCIPY_PROGRESS_UNITS, simulate
from gpme_core.progress import Compiling, Progress
from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_io.progress import LOG_LINE_SECONDS, TerminalProgress, progress_callback

T_END = 0.02         # s of the rigid crane: 200 RK4 steps of the paper's 1e-4 s


def _crane():
    params = CraneParameters()
    system = crane_system(0, params)
    return system, *initial_state(system.model, params)


@pytest.mark.parametrize("method, compiled", [("RK4", True), ("RK4", False), ("RK45", True)],
                         ids=["rk4-compiled", "rk4-python", "rk45-solve_ivp"])
def test_a_run_sends_its_progress_and_prints_nothing(capfd, method, compiled):
    system, q0, q_dot0 = _crane()
    events = []
    simulate(system, T_END, q0, q_dot0, dt=1e-4, method=method, compiled=compiled,
             progress=events.append)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")
    runs = [e for e in events if isinstance(e, Progress)]
    compiling = [e for e in events if isinstance(e, Compiling)]
    assert all(isinstance(e, (Progress, Compiling)) for e in events)
    # a compilation (if this process had not compiled yet) is announced before the run, once
    assert [e.finished for e in compiling] in ([], [False, True])
    assert events[:len(compiling)] == compiling
    total = 200 if method == "RK4" else SCIPY_PROGRESS_UNITS
    assert runs[0].done == 0 and not runs[0].finished
    assert runs[-1].finished and all(not e.finished for e in runs[:-1])
    assert {(e.method, e.total, e.t_end) for e in runs} == {(method, total, T_END)}
    done = [e.done for e in runs]
    assert done == sorted(done) and done[-1] <= total
    if method == "RK4":
        assert done[-1] == total and runs[-1].t == pytest.approx(T_END)
    walls = [e.wall_s for e in runs]
    assert walls == sorted(walls) and walls[0] >= 0


def test_progress_is_none_or_a_callable():
    system, q0, q_dot0 = _crane()
    with pytest.raises(ModelError, match="progress must be None or a callable taking "
                                         "gpme_core.progress events, got True"):
        simulate(system, T_END, q0, q_dot0, dt=1e-4, progress=True)


def test_a_compilation_is_reported_before_and_after(monkeypatch):
    system, q0, q_dot0 = _crane()
    system = system.with_dependent(system.pivoted_dependent(0.0, q0, q_dot0))
    monkeypatch.setattr(run_cost, "kernels_compiled", lambda compiled=None: False)
    events = []
    run_cost.time_evaluation(system, q0, q_dot0, progress=events.append)
    assert [type(e) for e in events] == [Compiling, Compiling]
    assert not events[0].finished and events[1].finished and events[1].wall_s > 0


def _run(callback, total, wall_per_step, t_end=1.0, method="RK4"):
    """Feed ``callback`` the events of a run of ``total`` steps, each ``wall_per_step`` s."""
    def event(done, finished=False):
        return Progress(method, done, total, t_end * done / total, t_end,
                        done * wall_per_step, finished)
    for done in range(total + 1):
        callback(event(done))
    callback(event(total, finished=True))


def test_a_log_gets_the_compile_notice_and_at_most_ten_lines_per_run(capsys):
    show = TerminalProgress()          # capsys's stderr is not a terminal: lines, no bar
    show(Compiling(finished=False))
    show(Compiling(finished=True, wall_s=12.34))
    _run(show, 1000, 1.0)              # 1000 s: a line per tenth
    _run(show, 1000, 1e-3)             # 1 s: none
    _run(show, 1000, 0.5 * LOG_LINE_SECONDS / 100)    # 150 s: every other tenth
    err = capsys.readouterr().err.splitlines()
    assert err[:2] == ["compiling the numba kernels (first call in this process; cached on "
                       "disk for the next) ...", "  compiled in 12.3 s"]
    lines = err[2:]
    assert lines[:10] == [f"  RK4: {10 * k:3.0f} % (t = {k / 10:.4g} of 1 s), {100 * k} s "
                          f"elapsed, ~{100 * (10 - k)} s left" for k in range(1, 11)]
    assert len(lines) == 15            # the 150 s run: 30, 60, 90, 120, 150 s
    assert lines[10].startswith("  RK4:  20 % (t = 0.2 of 1 s), 30 s elapsed")


def test_the_commands_choice_becomes_a_callback():
    assert isinstance(progress_callback(True), TerminalProgress)
    assert progress_callback(False) is None and progress_callback(None) is None
    assert progress_callback(print) is print
