"""The Dask client a sweep or a verification runs its tasks through.

A local cluster (one single-threaded worker process per core, no set-up) or an existing
scheduler given by its address (``tcp://host:8786``), whose workers must import the same
gpme packages.  Dask is imported inside the functions: it is heavy (~0.5 s) and only a
run on a cluster needs it (`gpme verify --workers 1` and the library's in-process runs do not).
"""
import logging
import os
from contextlib import contextmanager

from gpme_core.errors import GpmeError

# s, how long a given --scheduler has to answer
CONNECT_TIMEOUT_S = 10.0


class ClusterError(GpmeError):
    """The work cannot run where it was asked to (a scheduler that does not answer)."""


def connect(scheduler, timeout_s=CONNECT_TIMEOUT_S):
    """(Dask client, None) of the scheduler at ``scheduler``, or (None, problem) when it
    cannot be reached: a bad address, or no scheduler answering within ``timeout_s``."""
    from dask.distributed import Client    # Dask: heavy, only for a cluster
    try:
        return Client(scheduler, timeout=f"{timeout_s:g}s"), None
    except (OSError, ValueError, TypeError, TimeoutError) as exc:
        return None, (f"--scheduler {scheduler!r} cannot be reached within {timeout_s:g} s "
                      f"({type(exc).__name__}: {exc}); give the address of a running "
                      "Dask scheduler (tcp://host:8786), or leave --scheduler out for a "
                      "local cluster")


def local_client(n_workers=None):
    """A client of a new local cluster of ``n_workers`` single-threaded worker processes
    (default: one per core); close it with :func:`close` (the cluster goes with it)."""
    from dask.distributed import Client, LocalCluster    # Dask: heavy, only for a cluster
    cluster = LocalCluster(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    client._gpme_own_cluster = cluster     # closed with the client by close()
    return client


def close(client):
    """Close ``client`` and, when :func:`local_client` started it, its cluster."""
    cluster = getattr(client, "_gpme_own_cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


@contextmanager
def client_for(scheduler=None, n_workers=None):
    """The client of ``scheduler`` (ClusterError when it does not answer) or of a new local
    cluster of ``n_workers`` processes, closed (with its cluster) when the block ends."""
    if scheduler:
        client, problem = connect(scheduler)
        if client is None:
            raise ClusterError(problem)
    else:
        client = local_client(n_workers)
    try:
        yield client
    finally:
        close(client)


def worker_count(client) -> int:
    """Number of workers the scheduler of ``client`` has now."""
    return len(client.scheduler_info().get("workers", {}))


def thread_count(client) -> int:
    """Number of tasks the workers of ``client``'s scheduler run at once now (the sum of
    their threads; at least 1)."""
    workers = client.scheduler_info().get("workers", {})
    return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))


def as_completed(futures):
    """Dask's as_completed over ``futures`` (an iterable of Dask futures)."""
    from dask.distributed import as_completed as completed    # Dask: heavy, cluster only
    return completed(futures)
