"""The Dask cluster that batch commands (`sweep`) run their tasks on.

`dask_client(...)` is a context manager giving a `distributed.Client` (Dask's distributed
scheduler, https://distributed.dask.org):

- by default on a `LocalCluster` of this computer: worker processes (not threads: the numba
  kernels and numpy release the GIL only in parts, and a process per worker keeps each
  worker's memory its own), one thread each, `workers` of them (default: the number of CPU
  cores), the cores shared among them for numba's parallel kernels (NUMBA_NUM_THREADS), each
  paused and restarted by Dask's nanny beyond `memory_limit` bytes, its dashboard on a free
  port (`client.dashboard_link`: no clash with another cluster's 8787);
- or on an existing cluster by the address of its scheduler (`tcp://host:8786`): a
  `dask-scheduler` with `dask-worker` processes on other machines, or anything Dask can reach
  (Kubernetes with dask-kubernetes, SLURM/PBS with dask-jobqueue). Its workers need the same
  skyscatter installed; an unreachable scheduler is an InputError naming the address.

Dask is an optional dependency (`pip install "skyscatter[dask]"`), imported only here (the
others ask `import_distributed`), only when a cluster is wanted.

`map_in_order` runs one function over a sequence on the cluster and yields the results in
order, a bounded number ahead (the frames of a time-lapse, which are written in order).

Public names: `EXTRA`, `import_distributed`, `dask_client`, `checked_workers`, `map_in_order`.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator

from skyscatter.errors import InputError

__all__ = ["EXTRA", "checked_workers", "dask_client", "import_distributed", "map_in_order"]

EXTRA = 'pip install "skyscatter[dask]"'
CONNECT_TIMEOUT_S = 10.0  # s: a scheduler that does not answer in this time is unreachable
MAX_LOCAL_WORKERS = 1024  # worker processes on one computer: more than any has cores


def import_distributed():
    """The `distributed` module; InputError naming the extra that installs it when missing."""
    try:
        import distributed
    except ImportError:
        raise InputError(f"running on a Dask cluster needs dask.distributed: {EXTRA}",
                         key="dask", allowed=EXTRA) from None
    return distributed


def checked_workers(workers: int | None) -> int:
    """The number of local worker processes: `workers`, or this computer's CPU cores."""
    if workers is None:
        return os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or not (
            1 <= workers <= MAX_LOCAL_WORKERS):
        raise InputError(f"workers = {workers!r} is not allowed: a whole number of worker "
                         f"processes from 1 to {MAX_LOCAL_WORKERS}", key="workers", value=workers,
                         allowed=f"1-{MAX_LOCAL_WORKERS}")
    return workers


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None, *,
                memory_limit: str | int | None = None,
                timeout_s: float | None = None) -> Iterator:
    """A `distributed.Client` of the scheduler at `scheduler` (e.g. "tcp://host:8786"), or of
    a new `LocalCluster` of `workers` processes (default: the CPU cores) with one thread each
    and `memory_limit` per worker (bytes, or Dask's text such as "4GiB"; default: Dask's, the
    memory divided among the workers). Closed (and the local cluster shut down) on leaving.
    InputError for a scheduler that does not answer within `timeout_s` [s] (default
    `CONNECT_TIMEOUT_S`), or `workers` or
    `memory_limit` given with `scheduler` (its workers are its own)."""
    distributed = import_distributed()
    timeout_s = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
    if scheduler is not None:
        if workers is not None or memory_limit is not None:
            raise InputError("--workers and --memory-limit size a local cluster; the workers of "
                             f"the scheduler {scheduler} are started with it (dask-worker "
                             "--nworkers, --memory-limit)", key="workers", value=workers)
        try:
            client = distributed.Client(scheduler, timeout=timeout_s)
        except (OSError, TimeoutError, ValueError) as error:
            reason = str(error).splitlines()[0] if str(error) else type(error).__name__
            raise InputError(f"cannot reach the Dask scheduler {scheduler!r} within "
                             f"{timeout_s:g} s ({reason}); start it (dask-scheduler) or give "
                             "its address as tcp://HOST:PORT", key="scheduler",
                             value=scheduler, allowed="tcp://HOST:PORT") from None
        with client:
            yield client
        return
    count = checked_workers(workers)
    options = {} if memory_limit is None else {"memory_limit": memory_limit}
    # the cores shared among the workers: numba's parallel kernels would otherwise each start
    # a thread per core, `workers` times over (Dask's nanny does the same for OpenMP/BLAS)
    threads = max(1, (os.cpu_count() or 1) // count)
    try:
        cluster = distributed.LocalCluster(n_workers=count, threads_per_worker=1,
                                           processes=True, dashboard_address=":0",
                                           env={"NUMBA_NUM_THREADS": str(threads)}, **options)
    except ValueError as error:  # a memory limit Dask cannot read
        raise InputError(f"memory_limit = {memory_limit!r} is not allowed ({error}): give "
                         "bytes or text such as 4GiB", key="memory_limit", value=memory_limit,
                         allowed="bytes, or text such as 4GiB") from None
    with _quiet_dask(), cluster, distributed.Client(cluster) as client:
        client.run(_quiet_worker)
        yield client


@contextlib.contextmanager
def _quiet_dask() -> Iterator[None]:
    """Dask's own warnings of this process (the local cluster's nannies) at ERROR level while
    the cluster runs: an interrupted run says "interrupted", not four lines about cancelled
    tasks and workers killed on shutdown. Its worker processes get the same by
    `_quiet_worker`."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def map_in_order(client, function: Callable, items: Iterable, *arguments: object,
                 ahead: int | None = None) -> Iterator:
    """`function(item, *arguments)` for each of `items`, computed on `client`'s workers and
    yielded in the order of `items`, with at most `ahead` (default: twice the cluster's
    threads) submitted and not yet yielded, so that memory stays bounded. `arguments` may be
    futures (`client.scatter`). A task's exception is raised here."""
    if ahead is None:
        ahead = 2 * max(1, sum(client.nthreads().values()))
    pending: deque = deque()
    for item in items:
        pending.append(client.submit(function, item, *arguments, pure=False))
        if len(pending) >= ahead:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


def _quiet_worker() -> None:
    """Dask's warnings at ERROR level in a local worker process (run there by `client.run`)."""
    logging.getLogger("distributed").setLevel(logging.ERROR)
