"""Where the time of one compiled GPME evaluation goes (a profile of gpme_core.kernels).

    python -m benchmarks.kernel_profile [--n-rfe 0 5 20 50] [--cholesky]

cProfile cannot see inside compiled code, so each part of gpme_core.kernels.evaluate is
timed on its own, called in a compiled loop (no Python between calls), on the crane at
a seeded off-equilibrium state: the chain kinematics (T, S), the trace-form terms (M, h,
g), the constraint rows (Phi, Phi_dot, A, kappa), the reduced solve (Gamma, N^T M N, its
Cholesky factor, q_ddot, multipliers), the whole evaluation, and one step of the compiled
RK4 loop (kernels.rk4_advance, four evaluations and the stage updates, a batch of steps in
one call as in a run; a step of 1e-8 s so that the state stays where the parts were
timed).  The last three columns are the free
crane (no constraints, the same state): its whole evaluation with the O(n) recursive solve
(gpme_core.fast.chain_solve, M not formed), the same with M formed and solved by the dense
Cholesky (kernels.OPT_DENSE_FREE_SOLVE), and its RK4 step.  Microseconds per call, best of 5
batches, LAPACK on one thread as in the compiled runs; the parts add up to the whole
within the spring, damper and drive forces and the workspace carving.

``--cholesky`` adds the table behind kernels.LAPACK_FROM: the factor of an r x r symmetric
positive definite matrix by kernels' own loops against LAPACK's (numpy.linalg.cholesky
inside numba: the call, a copy and the factor), microseconds per factor.
"""
import argparse
import timeit

import numba
import numpy as np

from gpme_core import blas_threads, compiled, fast, kernels
from gpme_core.gpme import ProgrammedMotion
from gpme_examples.crane import crane_system, initial_state

BATCH = 400


@numba.njit
def _loop_chain(count, md, q):
    parts = kernels.model_parts(md)
    origins, generators, is_revolute, parents = parts[0], parts[1], parts[2], parts[10]
    for _ in range(count):
        fast.chain(origins, generators, is_revolute, parents, q)


@numba.njit
def _loop_terms(count, md, t_all, s_all, q_dot):
    parts = kernels.model_parts(md)
    pseudo, gamma, parents, moves = parts[3], parts[4], parts[10], parts[11]
    for _ in range(count):
        fast.terms(t_all, s_all, pseudo, gamma, parents, moves, q_dot)


@numba.njit
def _loop_rows(count, t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot, a, kappa):
    ws = np.empty(kernels.rows_scratch_size(q.shape[0], cd[0][1]))
    for _ in range(count):
        kernels.constraint_rows(t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot, a, kappa,
                                ws)


@numba.njit
def _loop_reduced(count, m_mat, rhs, a, c, ic, dc, q_ddot, lam):
    ws = np.empty(kernels.reduced_scratch_size(q_ddot.shape[0], dc.shape[0]))
    for _ in range(count):
        kernels.reduced_solve(m_mat, rhs, a, c, ic, dc, 0.0, 1e-10, q_ddot, lam, ws)


@numba.njit
def _loop_evaluate(count, t, q, q_dot, md, cd, opts, ic, dc, q_ddot, lam, info):
    ws = np.empty(kernels.workspace_size(q.shape[0], dc.shape[0], cd[0][1]))
    for _ in range(count):
        kernels.evaluate(t, q, q_dot, md, cd, opts, ic, dc, q_ddot, lam, info, ws)


@numba.njit
def _loop_rk4(count, y, md, cd, opts, ic, dc, fail_y):
    # count steps in one call, as a run takes them (rk4_advance's work arrays are made once
    # per call: one call per step would time their allocation too)
    kernels.rk4_advance(0.0, y, RK4_STEP, count, md, cd, opts, ic, dc, fail_y)


@numba.njit
def _loop_factor_loops(count, mat, low):
    for _ in range(count):
        kernels._cholesky_factor(mat, low)


@numba.njit
def _loop_factor_lapack(count, mat):
    for _ in range(count):
        np.linalg.cholesky(mat)


RK4_STEP = 1e-8         # s: the RK4 column's step (the state hardly moves over a batch)
CHOLESKY_SIZES = (8, 16, 24, 32, 40, 48, 56, 64, 100, 152)


def _us(fn, *args):
    fn(1, *args)                                        # compile
    return 1e6 * min(timeit.repeat(lambda: fn(BATCH, *args), number=1, repeat=5)) / BATCH


def profile(n_rfe, t=0.37, seed=0):
    """{part: microseconds} of one evaluation of the crane with n_rfe segments."""
    system = crane_system(n_rfe)
    q, q_dot = system.consistent_state(0.0, *initial_state(system.model))
    q_dot = q_dot + 0.1 * np.random.default_rng(seed).standard_normal(q.size)
    cs, why = compiled.for_system(system)
    if cs is None:
        raise SystemExit(f"not compiled: {why}")
    md, cd = cs.md, cs.cd
    parts = kernels.model_parts(md)
    moves = parts[11]
    t_all, s_all, m_mat, h, g = fast.chain_and_terms(*parts[:5], parts[10], moves, q, q_dot)
    k, n = system.n_constraints, q.size
    phi, phi_dot, kappa, a = np.empty(k), np.empty(k), np.empty(k), np.empty((k, n))
    kernels.constraint_rows(t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot, a, kappa,
                            np.empty(kernels.rows_scratch_size(n, cs.n_points)))
    c = -kappa - 2 * system.alpha * phi_dot - system.beta ** 2 * phi
    out = np.empty(n), np.empty(k)
    y = np.concatenate([q, q_dot, np.zeros(kernels.N_WORK)])
    free = ProgrammedMotion(system.model)
    free_cs, why = compiled.for_system(free)
    if free_cs is None:
        raise SystemExit(f"free crane not compiled: {why}")
    free_out = np.empty(n), np.empty(0), np.empty(kernels.INFO_SIZE)
    dense_opts = np.zeros(kernels.OPT_DENSE_FREE_SOLVE + 1)
    dense_opts[:kernels.OPT_DENSE_FREE_SOLVE] = free_cs.options()[:kernels.OPT_DENSE_FREE_SOLVE]
    dense_opts[kernels.OPT_DENSE_FREE_SOLVE] = 1.0
    return {"n_rfe": n_rfe, "coordinates": n,
            "chain T, S": _us(_loop_chain, md, q),
            "terms M, h, g": _us(_loop_terms, md, t_all, s_all, q_dot),
            "constraint rows": _us(_loop_rows, t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot,
                                   a, kappa),
            "reduced solve": _us(_loop_reduced, m_mat, h - g, a, c, system.ic, system.dc, *out),
            "whole evaluate": _us(_loop_evaluate, t, q, q_dot, md, cd, cs.options(),
                                  system.ic, system.dc, *out, np.empty(kernels.INFO_SIZE)),
            "RK4 step": _us(_loop_rk4, y, md, cd, cs.options(), system.ic, system.dc,
                            np.empty_like(y)),
            "free evaluate": _us(_loop_evaluate, t, q, q_dot, free_cs.md, free_cs.cd,
                                 free_cs.options(), free.ic, free.dc, *free_out),
            "free evaluate, dense M": _us(_loop_evaluate, t, q, q_dot, free_cs.md, free_cs.cd,
                                          dense_opts, free.ic, free.dc, *free_out),
            "free RK4 step": _us(_loop_rk4, y.copy(), free_cs.md, free_cs.cd,
                                 free_cs.options(), free.ic, free.dc, np.empty_like(y))}


def cholesky_table(sizes=CHOLESKY_SIZES, seed=0):
    """[{r, loops, LAPACK}]: microseconds per Cholesky factor of an r x r SPD matrix."""
    rng = np.random.default_rng(seed)
    rows = []
    for r in sizes:
        half = rng.standard_normal((r, r))
        mat = half @ half.T + r * np.eye(r)
        rows.append({"r": r, "loops": _us(_loop_factor_loops, mat, np.zeros((r, r))),
                     "LAPACK": _us(_loop_factor_lapack, mat)})
    return rows


def _print_table(rows):
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{r[k]:.1f}" if isinstance(r[k], float) else str(r[k])
                                for k in keys) + " |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n-rfe", type=int, nargs="+", default=[0, 5, 20, 50])
    parser.add_argument("--cholesky", action="store_true",
                        help="also time the Cholesky factor: kernels' loops against LAPACK")
    args = parser.parse_args(argv)
    with blas_threads.single_threaded_blas():      # as in the compiled runs
        _print_table([profile(n) for n in args.n_rfe])
        if args.cholesky:
            print(f"\nCholesky factor of an r x r matrix, us (kernels.LAPACK_FROM = "
                  f"{kernels.LAPACK_FROM})")
            _print_table(cholesky_table())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
