"""The cost of one integration step inside each engine's own loop, side by side in one
process (issue 29).

    python -m benchmarks.in_loop [--n-rfe 0 5 20 50] [--no-ur5] [--repeats 3]

Cases: the paper's crane at each n_rfe, free (no constraints, drive torque 0: the same
equations in every engine, no callback into Python) and programmed (gpme: the exact
GPME constraints with Baumgarte terms; MuJoCo: the auxiliary mechanism of
crosscheck.mujoco.mjcf with soft equalities, its own realisation of the same task), and
the UR5 example with its flexible forearm (models/ur5_flexible_forearm.toml), free.

Loops timed (each engine's own loop, no Python between steps where the engine has one):

* gpme RK4       : gpme_core.integrate.simulate(..., method="RK4", compiled=True), one
                   compiled call for the whole run (output only at the end)
* gpme RadauIIA  : the same with method="RadauIIA" (its own dt, below)
* MuJoCo RK4     : mujoco.rollout.rollout (C loop of mj_step), integrator RK4
* MuJoCo implicitfast : the same, MuJoCo's implicit-in-velocity Euler (first order)
* Pinocchio      : pin.aba (free) or pin.forwardDynamics with the constraint rows
                   (programmed; benchmarks.engines.PinocchioConstrained) inside a Python
                   RK4 loop: Pinocchio's Python bindings have no compiled loop of their
                   own, so this row carries Python's overhead and is reported as such

Cost per step = (wall time of a run of N2 steps - that of N1 = N2 / 5 steps) / (N2 - N1):
the marginal cost, without set-up, compilation or the first call; N2 is the steps of
MAX_SIMULATED_S, each run timed as the best of as many runs as fit in TIMED_S.  Best of ``--repeats``, the engines interleaved within
each repeat so the machine's load affects them alike; the 1-minute load average is
printed.  The same work: every engine starts from the same state (a seeded start
velocity, so every coordinate moves; projected onto the constraints when programmed) and
the states after COMPARED_STEPS steps are compared with gpme's RK4 (max |q - q_gpme|, rad
or m): RK4 against RK4 at the same step agrees to round-off (free), MuJoCo's programmed
run differs by its soft constraints' error, implicitfast by its first-order error.
"""
import argparse
import os
import time

import mujoco
import numpy as np
import pandas as pd
import pinocchio as pin
from mujoco import rollout

from benchmarks.engines import PinocchioConstrained, rk4_run
from crosscheck.mujoco import mechanism as mech
from crosscheck.mujoco.mjcf import mjcf_text
from crosscheck.mujoco.sim import chain_map, set_state
from crosscheck.pinocchio.model import from_gpme
from gpme_core.blas_threads import single_threaded_blas
from gpme_core.errors import GpmeError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.stability import suggest_rk4_step
from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_io.modelfile import load_model_files

RADAU_DT = 1e-3                                       # s, RadauIIA's step (docs/benchmarks.md)
COMPARED_STEPS = 2000        # the states are compared after this many steps
TIMED_S = 0.3                # s, each loop's timed runs take about this long per repeat
MAX_SIMULATED_S = 0.25       # s, no timed run goes further (the free crane's arm leaves its
                             # joint range after ~0.5 s from the seeded start)
MAX_DT = 1e-4                # s: the rigid crane's only spring (the support) would allow
                             # 0.095 s, far above what MuJoCo's soft constraints follow
DIVERGED = 1.0               # rad or m: a run whose state after COMPARED_STEPS differs from
                             # gpme's RK4 by this much has left the motion (diverged: MuJoCo's
                             # implicitfast on the programmed rigid crane ends 536 rad off)
MIN_STEPS = 500              # the longer timed run has at least this many steps (within
                             # MAX_SIMULATED_S: RadauIIA's 1 ms steps, 250)
START_SPEED = 0.3            # rad/s or m/s, largest entry of the seeded start velocity


def _load():
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return float("nan")


def gpme_final(system, q0, qd0, dt, steps, method="RK4"):
    """(q after ``steps`` steps (n,), wall time s) of gpme's compiled loop."""
    t_end = steps * dt
    start = time.perf_counter()
    run = simulate(system, t_end, q0, qd0, dt=dt, output_dt=t_end, method=method,
                   compiled=True)
    wall = time.perf_counter() - start
    if not run.attrs.get("compiled"):
        raise RuntimeError(f"{system.model.name}: the compiled loop did not run")
    return run[list(system.model.coordinate_names)].to_numpy(float)[-1], wall


class MujocoLoop:
    """MuJoCo's rollout of the model from one state."""

    def __init__(self, model, q0, qd0, dt, integrator, specs=None):
        self.mj = mujoco.MjModel.from_xml_string(mjcf_text(model, dt, specs))
        self.mj.opt.integrator = integrator
        self.mj.opt.timestep = dt
        # a diverged run must show as NaN, not restart from qpos0 (MuJoCo's autoreset)
        self.mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        self.data = mujoco.MjData(self.mj)
        self.cmap = chain_map(self.mj, model)
        aux = None
        if specs:
            programme = mech.read_programme(model, specs)
            p_e, v_e = mech.frame_motion(model, programme.frame, q0, qd0)
            aux = mech.auxiliary_state(programme, p_e, v_e, 0.0)
        set_state(self.mj, self.data, self.cmap, q0, qd0, 0.0, aux)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self.state0 = np.empty(mujoco.mj_stateSize(self.mj, spec))
        mujoco.mj_getState(self.mj, self.data, self.state0, spec)

    def final(self, steps):
        start = time.perf_counter()
        states, _ = rollout.rollout(self.mj, self.data, self.state0, nstep=steps)
        wall = time.perf_counter() - start
        # FULLPHYSICS: time, qpos, qvel, act, ...
        qpos = states[0, -1, 1:1 + self.mj.nq]
        return qpos[self.cmap.qpos], wall


def pinocchio_final(system, q0, qd0, dt, steps, free):
    """(q after ``steps`` RK4 steps, wall s) with Pinocchio's aba (free) or its constrained
    forward dynamics, in benchmarks.engines' Python RK4 loop."""
    if free:
        ps = from_gpme(system.model)
        pm, data = ps.model, ps.model.createData()

        def acc(t, q, v):
            return pin.aba(pm, data, q, v, ps.applied_forces(q, v, system.model.drive_forces(t)))
    else:
        acc = PinocchioConstrained(system).accelerations
    _, history, wall = rk4_run(acc, steps * dt, q0, qd0, dt, output_dt=steps * dt)
    return history[-1], wall


def start_velocity(n, seed=20261126):
    """(n,) seeded start velocity, entries uniform in +-START_SPEED (rad/s or m/s)."""
    return np.random.default_rng(seed).uniform(-START_SPEED, START_SPEED, n)


def rk4_dt(system, q):
    """s, the RK4 step of every engine: gpme's suggested step at q (half the stability limit
    of the stiffest spring mode, gpme_core.stability.suggest_rk4_step), at most MAX_DT."""
    return min(float(suggest_rk4_step(system.model, q)), MAX_DT)


def _cases(n_values, ur5):
    """(name, system, q0, qd0, rk4 dt, free) of every case."""
    params = CraneParameters(drive_torque=0.0)
    out = []
    for n in n_values:
        programmed = crane_system(n, params)
        q0, _ = initial_state(programmed.model, params)
        qd0 = start_velocity(len(q0))
        free = ProgrammedMotion(programmed.model, [])
        dt = rk4_dt(free, q0)
        out.append((f"crane n_rfe={n} free", free, q0, qd0, dt, True))
        qc, qdc = programmed.consistent_state(0.0, q0, qd0)
        out.append((f"crane n_rfe={n} programmed", programmed, qc, qdc, dt, False))
    if ur5:
        (scenario,) = load_model_files(["models/ur5_flexible_forearm.toml"])
        free = ProgrammedMotion(scenario.model, [])
        out.append(("ur5 flexible forearm free", free, scenario.q0,
                    start_velocity(len(scenario.q0)), rk4_dt(free, scenario.q0), True))
    return out


def _best_wall(f, steps):
    """s, the shortest wall time of f(steps) over as many calls as fit in TIMED_S / 2."""
    best, spent = np.inf, 0.0
    while spent < TIMED_S / 2 or best == np.inf:
        _, wall = f(steps)
        best, spent = min(best, wall), spent + wall
    return best


def measure(name, system, q0, qd0, dt, free, repeats):
    """Rows {engine, loop, us_per_step, max_state_difference} of one case."""
    specs = None if free else system.constraint_specs
    loops = {}
    loops[("gpme", f"RK4 dt={dt:g}")] = lambda s: gpme_final(system, q0, qd0, dt, s)
    loops[("gpme", f"RadauIIA dt={RADAU_DT:g}")] = lambda s: gpme_final(
        system, q0, qd0, RADAU_DT, s, "RadauIIA")
    for label, integrator in (("RK4", mujoco.mjtIntegrator.mjINT_RK4),
                              ("implicitfast", mujoco.mjtIntegrator.mjINT_IMPLICITFAST)):
        try:
            loop = MujocoLoop(system.model, q0, qd0, dt, integrator, specs)
            loops[("mujoco", f"{label} dt={dt:g}")] = loop.final
        except Exception as exc:      # a model MuJoCo's MJCF writer cannot realise
            print(f"  {name}: MuJoCo {label} not run: {type(exc).__name__}: {exc}")
    loops[("pinocchio", f"RK4 dt={dt:g} (Python loop)")] = lambda s: pinocchio_final(
        system, q0, qd0, dt, s, free)
    finals, counts = {}, {}
    for key, f in list(loops.items()):            # compile, load, first calls
        try:
            f(10)
        except GpmeError as exc:     # e.g. RadauIIA's 1 ms step on a violent start
            print(f"  {name}: {key[0]} {key[1]} not timed: {exc}")
            del loops[key]
            continue
        if "RadauIIA" not in key[1]:
            finals[key], wall = f(COMPARED_STEPS)
            per_step = wall / COMPARED_STEPS
        else:
            per_step = f(100)[1] / 100
        step = RADAU_DT if "RadauIIA" in key[1] else dt
        # N2: as many steps as take TIMED_S / 2 of wall time but at least MIN_STEPS, and
        # never beyond MAX_SIMULATED_S
        counts[key] = min(int(round(MAX_SIMULATED_S / step)),
                          max(MIN_STEPS, int(TIMED_S / 2 / max(per_step, 1e-9))))
    best = {k: np.inf for k in loops}
    for _ in range(repeats):
        for key, f in loops.items():
            n2 = counts[key]
            n1 = n2 // 5
            w1, w2 = _best_wall(f, n1), _best_wall(f, n2)
            best[key] = min(best[key], (w2 - w1) / (n2 - n1) * 1e6)
    ref = finals[("gpme", f"RK4 dt={dt:g}")]
    rows = []
    for key in loops:
        diff = float(np.max(np.abs(finals[key] - ref))) if key in finals else float("nan")
        if key in finals and not diff < DIVERGED:
            print(f"  {name}: {key[0]} {key[1]} diverged (|q - q_gpme| = {diff:.3g}); its time is "
                  "not a step's cost")
            best[key], diff = float("nan"), float("nan")
        rows.append({"case": name, "coordinates": len(q0), "engine": key[0], "loop": key[1],
                     "us_per_step": best[key], "max_state_difference": diff})
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n-rfe", type=int, nargs="+", default=[0, 5, 20, 50])
    parser.add_argument("--no-ur5", action="store_true")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"load average {_load():.2f}; gpme {_version('gpme')}, mujoco {mujoco.__version__}, "
          f"pinocchio {pin.__version__}")
    rows = []
    with single_threaded_blas():
        for case in _cases(args.n_rfe, not args.no_ur5):
            print(f"{case[0]} ...", flush=True)
            rows += measure(*case, args.repeats)
    table = pd.DataFrame(rows)
    for case, group in table.groupby("case", sort=False):
        mj = group[group["loop"].str.startswith("RK4") & (group["engine"] == "mujoco")]
        gp = group[group["loop"].str.startswith("RK4") & (group["engine"] == "gpme")]
        ratio = (gp["us_per_step"].iloc[0] / mj["us_per_step"].iloc[0]) if len(mj) else np.nan
        print(f"\n{case} ({group['coordinates'].iloc[0]} coordinates): gpme RK4 / MuJoCo RK4 "
              f"= {ratio:.2f}")
        print(group[["engine", "loop", "us_per_step", "max_state_difference"]]
              .to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    print(f"\nload average {_load():.2f}")
    return table


def _version(dist):
    from importlib import metadata
    return metadata.version(dist)


if __name__ == "__main__":
    main()
