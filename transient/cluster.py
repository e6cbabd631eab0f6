"""The Dask cluster a campaign's variants or the components path's parts run on: the embedded
LocalCluster of N one-thread worker processes (BLAS, MKL, OpenMP and Numba at one thread set
in their environment before they start, so that N of them share the cores), or an existing
scheduler's (dask-jobqueue on SLURM: docs/commands.md).
"""
import warnings

from .errors import CaseError

WHERE = "command line"
THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1"}


def check_cluster(scheduler, workers):
    """Refuse a scheduler address that is not one, or fewer than one worker, before any work
    (a Client would raise its own ValueError only once the variants are checked)."""
    if scheduler is None:
        if workers < 1:
            raise CaseError(WHERE, "--workers", f"expected at least 1, got {workers}")
        return
    try:
        from distributed.comm import get_address_host_port
    except ImportError:
        raise CaseError(WHERE, "--workers", "needs dask.distributed: pip install "
                        "\"transient[sweep]\" (or dask[distributed])") from None
    if scheduler.partition("://")[0] == "ucx":       # its own host and port rules
        return
    try:
        _, port = get_address_host_port(scheduler)
        if not 0 < port < 65536:
            raise ValueError(f"port {port} out of range")
    except ValueError as exc:
        raise CaseError(WHERE, "--scheduler", f"expected an address such as "
                        f"tcp://HOST:PORT, got '{scheduler}' ({exc})") from None


def client_for(scheduler, workers):
    """(client, cluster or None): a Client on the scheduler, or on a new LocalCluster."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise CaseError(WHERE, "--workers", "needs dask.distributed: pip install "
                        "\"transient[sweep]\" (or dask[distributed])") from None
    if scheduler is not None:
        try:
            return Client(scheduler, timeout="30s"), None
        except (OSError, TimeoutError, ValueError) as exc:
            raise CaseError(WHERE, "--scheduler", f"cannot reach {scheduler}: {exc}") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           env=THREAD_ENV, dashboard_address=":0", silence_logs=50)
    return Client(cluster), cluster


def submitted(client, fn, *args, **kwargs):
    """client.submit without Dask's warning of a large graph: a part's or a piece's task
    carries its inputs (its cells) on purpose, so that a lost worker's task runs again from
    them, where data scattered to that worker would be lost with it."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
        return client.submit(fn, *args, **kwargs)
