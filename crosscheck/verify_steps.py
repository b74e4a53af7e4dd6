"""One step of `gpme verify` (gpme's own runs, or one engine's crosscheck) run in a
directory, as a unit another process can run: :func:`run_step` takes picklable arguments
and returns a :class:`StepOutcome` (its rows, the rows it made about another engine, how
long it took, and a crash as text), and everything the step writes lies under the
directory it is given.

Steps: gpme (each scenario's run and its checks; without --model the paper's two crane
runs, plus the paper's figures), pinocchio, mujoco, drake, exudyn and continuum (the
engines' crosschecks, crosscheck.<engine>.check.run).  No step reads another's results:
they may run in any order or at once (crosscheck.step_pool); the gpme runs several engines
compare against are computed once among them (crosscheck.run_memo).
"""
import importlib
import logging
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import pandas as pd

from gpme_core.errors import GpmeError, OutputWriteError
from gpme_examples import paper
from gpme_io.example_outputs import write_example_outputs
from gpme_io.runs import simulate_scenario, write_run_outputs

from . import rfem_reference
from .accurate_step import run_accurately
from .compare import CRASH_QUANTITY, Tolerance, compare
from .constraint_reference import with_reference_frames_of
from .crane_cases import crane_cases
from .engines import missing_message
from .reference_values import reference_rows
from .reports.rows import normalise, other_rows, own_rows, write_rows
from .run_checks import rows_frame, run_rows

STEPS = ("gpme", "pinocchio", "mujoco", "drake", "exudyn", "continuum")
OPTIONAL_STEPS = ("drake", "exudyn", "continuum")   # crosscheck.engines: optional extras
log = logging.getLogger("gpme.verify")


def default_scenarios(step, quick):
    """The paper's crane cases a step uses when no model file is given
    (crosscheck.crane_cases); none for an optional engine that is not installed."""
    if step in OPTIONAL_STEPS and missing_message(step):
        return []
    return crane_cases(step, quick)


@dataclass(frozen=True)
class Crash:
    """A step that stopped on an exception, as text (picklable whatever raised it).

    kind: the exception's class name;  message: str(exception);  traceback: the formatted
    traceback;  input_error: True for a gpme input or run error (gpme_core.errors.GpmeError),
    whose message says it all."""
    kind: str
    message: str
    traceback: str
    input_error: bool


@dataclass(frozen=True)
class StepOutcome:
    """What one step produced.

    step          : its name (one of STEPS)
    table         : its own comparison rows (a crash row when it crashed)
    prerequisites : rows it made about another engine's runs (gpme's observed order in
                    an engine's step: crosscheck.reports.rows.other_rows), possibly empty
    seconds       : s, its wall time (with parts run at once: the sum of the parts' times)
    crash         : Crash, or None
    """
    step: str
    table: pd.DataFrame
    prerequisites: pd.DataFrame
    seconds: float
    crash: Optional[Crash] = None


@dataclass(frozen=True)
class PartOutcome:
    """One scenario's share of a step (:func:`run_part`).

    step, index : the step and the scenario's place in :func:`step_scenarios`
    part        : what the step's module computed for it (picklable), None on a crash
    seconds     : s, its wall time;  crash: Crash, or None
    """
    step: str
    index: int
    part: object
    seconds: float
    crash: Optional[Crash] = None


def step_scenarios(step, scenarios, quick) -> Optional[list]:
    """The scenarios ``step`` runs, one part each: ``scenarios`` (model files) or the step's
    crane cases, with the reference frames the engines' models carry
    (crosscheck.constraint_reference); None for an optional engine that is not installed
    (the step is then one information row, :func:`missing_step`)."""
    if step in OPTIONAL_STEPS and missing_message(step):
        return None
    chosen = scenarios if scenarios is not None else default_scenarios(step, quick)
    if step == "gpme":
        return list(chosen)
    # the engines' models carry the auxiliary frames of the reference derivation of axis
    # alignments (crosscheck.constraint_reference)
    return [with_reference_frames_of(s) for s in chosen]


def missing_step(step, out_dir) -> StepOutcome:
    """The information row of an optional engine that is not installed, written."""
    log.info(f"[{step}] skipped: {missing_message(step)}")
    table = _missing_engine_row(step, missing_message(step))
    write_rows(normalise(table), out_dir, step)
    return StepOutcome(step, table, pd.DataFrame(), 0.0)


def _crash_of(exc) -> Crash:
    return Crash(type(exc).__name__, str(exc), "".join(traceback.format_exception(exc)),
                 isinstance(exc, GpmeError))


def crashed_part(step, index, exc) -> PartOutcome:
    """The outcome of a part that failed outside :func:`run_part` (its worker lost, say)."""
    return PartOutcome(step, index, None, 0.0, _crash_of(exc))


def run_part(step, index, out_dir, scenario, quick, progress=False,
             max_wall_s=None) -> PartOutcome:
    """``step`` on one ``scenario`` (the index-th of :func:`step_scenarios`), writing its
    files under ``out_dir``.  An exception is the part's Crash, except OutputWriteError
    (the report cannot be written: raised)."""
    start = time.perf_counter()
    try:
        if step == "gpme":
            part = _gpme_part(Path(out_dir), scenario, quick, progress, max_wall_s)
        elif step == "mujoco":
            part = _check_module(step).scenario_part(out_dir, scenario, quick, progress)
        else:
            part = _check_module(step).scenario_part(out_dir, scenario, quick)
    except OutputWriteError:
        raise                 # the report cannot be written: the run stops (exit 74)
    except Exception as exc:  # a crashed step is a failed check, reported in full
        return PartOutcome(step, index, None, time.perf_counter() - start, _crash_of(exc))
    return PartOutcome(step, index, part, time.perf_counter() - start)


def finish_step(step, out_dir, parts, quick) -> StepOutcome:
    """The step's table from its parts (PartOutcome list in scenario order): its page and
    rows written under ``out_dir``.  A crashed part makes the step one crash row (its
    first crash), as a crash of the step itself does."""
    out_dir = Path(out_dir)
    seconds = sum(p.seconds for p in parts)
    start = time.perf_counter()
    crash = next((p.crash for p in parts if p.crash is not None), None)
    prerequisites = pd.DataFrame()
    if crash is None:
        try:
            pieces = [p.part for p in parts]
            if step == "gpme":
                table = _gpme_finish(out_dir, pieces)
            else:
                full = _check_module(step).finish(out_dir, pieces, quick, seconds)
                # checks of gpme's own runs made on the way (its observed order) are gpme's
                prerequisites = other_rows(full, step)
                table = own_rows(full, step)
        except OutputWriteError:
            raise
        except Exception as exc:
            crash = _crash_of(exc)
    if crash is not None:
        table = _crash_row(step, crash.kind, crash.message)
        write_rows(normalise(table), out_dir, step)   # its row, linked by the index
    return StepOutcome(step, table, prerequisites, seconds + time.perf_counter() - start,
                       crash)


def run_step(step, out_dir, scenarios, quick, progress=False, max_wall_s=None) -> StepOutcome:
    """Run ``step`` on ``scenarios`` (gpme_io.scenario.Scenario list; None: the step's
    crane cases) here, part after part (stopping at a crashed one), writing its rows,
    pages and runs under ``out_dir``."""
    chosen = step_scenarios(step, scenarios, quick)
    if chosen is None:
        return missing_step(step, out_dir)
    parts = []
    for index, scenario in enumerate(chosen):
        parts.append(run_part(step, index, out_dir, scenario, quick, progress, max_wall_s))
        if parts[-1].crash is not None:
            break
    return finish_step(step, out_dir, parts, quick)


def _check_module(step):
    """crosscheck.<step>.check (an engine's crosscheck: scenario_part, finish)."""
    return importlib.import_module(f"crosscheck.{step}.check")


def _gpme_part(run_dir, scenario, quick, progress, max_wall_s=None) -> dict:
    """One scenario's own gpme run: history and figures (runs/) and its checks:
    {"rows", "rfem_rows", "run": (scenario, history)}."""
    log.info(f"  gpme: {scenario.name}, {scenario.t_run(quick):g} s ({scenario.integrator})")
    rfem_rows = rfem_reference.rfem_rows(scenario)     # RFEM vs beam theory

    def run(dt):
        return simulate_scenario(scenario, quick=quick, progress=progress, dt=dt,
                                 max_wall_s=max_wall_s)

    def checks(df):
        return run_rows(scenario, df)

    if scenario.integrator == "RK4":
        # the step `gpme simulate` chooses: halved until the run's own checks pass
        # (crosscheck/accurate_step.py), so both commands judge the same run
        choice = run_accurately(run, checks, report=lambda line: log.info(f"    {line}"),
                                start=paper.step_name(scenario) or "the model file's step")
        df, rows = choice.df, choice.rows
        log.info(f"    {choice.note}")
    else:
        df = run(None)
        rows = checks(df)
    log.info(f"    wall time {df.attrs['wall_time_s']:.1f} s")
    write_run_outputs(scenario, df, run_dir / "runs", compressed=True)
    return {"rows": rows + reference_rows(scenario, df), "rfem_rows": rfem_rows,
            "run": (scenario, df)}


def _gpme_finish(run_dir, parts) -> pd.DataFrame:
    """The gpme step's table from its parts, written; the figures a built-in example adds
    (paper/: the paper's crane, gpme_io.example_outputs)."""
    write_example_outputs([p["run"] for p in parts], run_dir / "paper")
    df = with_rfem_rows(rows_frame([r for p in parts for r in p["rows"]]),
                        [r for p in parts for r in p["rfem_rows"]])
    write_rows(df, run_dir, "gpme")
    return df


def with_rfem_rows(df, rfem_rows):
    """The gpme step's run rows and its rows of the RFEM discretisation against closed-form
    beam theory (crosscheck.rfem_reference, section "rfem"), one table."""
    if not rfem_rows:
        return df
    return pd.concat([df, rfem_reference.rows_frame(rfem_rows)], ignore_index=True)


def _missing_engine_row(step, message):
    """An information row: optional engine ``step`` is not installed (``message`` says what
    to install); the run's other steps go on."""
    row = compare(step, "-", "not run: engine not installed", "-", [0.0], [0.0],
                  Tolerance(float("inf"), 0.0, f"information: {message}"), ["-"])
    return pd.DataFrame([{**row, "section": "-"}])


def _crash_row(step, kind, message):
    """The failed row of a crashed step (exception class name ``kind``, its message)."""
    return pd.DataFrame([{
        "engine": step, "model": "-", "quantity": CRASH_QUANTITY,
        "case": "-", "entry": kind, "gpme_value": float("nan"),
        "engine_value": float("nan"), "abs_error": float("inf"), "rel_error": float("nan"),
        "scale": float("nan"), "tol_abs": 0.0, "tol_rel": 0.0, "passed": False,
        "status": "fail", "reason": f"{message}"[:500]}])
