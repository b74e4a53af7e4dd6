"""BLAS and LAPACK on one thread around the compiled kernels (gpme_core.kernels): used by
the compiled runs (gpme_core.compiled_runs) and the timing of one evaluation
(gpme_core.run_cost), which need it without loading the kernels themselves."""
from contextlib import contextmanager

from threadpoolctl import threadpool_limits


@contextmanager
def single_threaded_blas():
    """BLAS and LAPACK on one thread inside the block (restored after it).

    The kernels call LAPACK only for the Cholesky factor of N^T M N above
    kernels.LAPACK_FROM coordinates, far too small to gain from threads: on this 2-core
    machine with one other busy process, the n_rfe = 50 crane's reduced solve took 1112 us
    with OpenBLAS's two threads waiting on each other and 170 us on one thread
    (benchmarks.kernel_profile, OPENBLAS_NUM_THREADS=2 vs 1).  The compiled runs and the
    benchmark's evaluations run inside this block."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
