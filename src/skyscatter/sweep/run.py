"""The scheduling of a sweep on a Dask cluster: solvers once per atmosphere, chunks from them.

For each atmosphere with unfinished chunks one task builds its solver (`tasks.build_solver`);
its result stays on the worker that built it, and the atmosphere's chunk tasks
(`tasks.compute_chunk`) take that result as their input, so Dask runs them where the solver is
or copies it to the workers that need it; nothing builds it twice. At most `in_flight`
atmospheres are under way at once (default: one more than the cluster has threads, so no
worker waits); when the last chunk of an atmosphere is stored, its futures are dropped and
Dask frees its solver, then the next atmosphere starts. Memory per worker therefore stays
bounded by a few solvers and chunks, whatever the size of the sweep.

Each finished chunk comes back to this process and is stored at once (`store.ChunkStore`):
the store is on the computer that runs the sweep, whatever machines compute. A worker that
dies (killed, out of memory) loses nothing stored; Dask runs its tasks again elsewhere,
rebuilding a solver it held (`distributed.scheduler.allowed-failures`, 3 by default); a task
that raises is tried `retries` more times (a transient error: a full disk, a network share).

Public names: `run_sweep`.
"""

from __future__ import annotations

from collections.abc import Callable

from skyscatter.dask_cluster import import_distributed
from skyscatter.sweep.plan import SweepPlan
from skyscatter.sweep.store import ChunkStore
from skyscatter.sweep.tasks import build_solver, compute_chunk

__all__ = ["run_sweep"]

RETRIES = 2  # more tries of a task that raised


def run_sweep(client, plan: SweepPlan, store: ChunkStore, *, in_flight: int | None = None,
              on_chunk: Callable[[int], None] | None = None) -> int:
    """Compute on `client` (a `distributed.Client`) every chunk of `plan` that `store` does
    not hold, storing each as it finishes and calling `on_chunk(index)` after it is stored.
    Returns the number of chunks computed. A task's exception is raised here (the chunks
    stored until then stay)."""
    distributed = import_distributed()
    finished = store.finished()
    waiting = [a for a in range(plan.n_atmospheres)
               if any(c not in finished for c in plan.chunks_of(a))]
    if not waiting:
        return 0
    if in_flight is None:
        in_flight = sum(client.nthreads().values()) + 1
    tag = plan.fingerprint()[:12]
    # the plan goes into every task as an argument (a few kB), not scattered: scattered data
    # has no lineage, and once Dask's memory manager has dropped its extra copies a dead
    # worker could take the last one with it
    pending = iter(waiting)
    active: dict[int, list] = {}  # atmosphere -> [solver future, chunks left]
    chunk_of: dict[str, tuple[int, int]] = {}  # future key -> (atmosphere, chunk)
    completed = distributed.as_completed()

    def start_next() -> None:
        atmosphere = next(pending, None)
        if atmosphere is None:
            return
        priority = plan.n_atmospheres - atmosphere  # earlier atmospheres first: few in memory
        solver = client.submit(build_solver, plan, atmosphere, key=f"solver-{tag}-{atmosphere}",
                               retries=RETRIES, priority=priority, pure=False)
        chunks = [c for c in plan.chunks_of(atmosphere) if c not in finished]
        active[atmosphere] = [solver, len(chunks)]
        for chunk in chunks:
            future = client.submit(compute_chunk, solver, plan, chunk,
                                   key=f"chunk-{tag}-{chunk}", retries=RETRIES,
                                   priority=priority, pure=False)
            chunk_of[future.key] = (atmosphere, chunk)
            completed.add(future)

    for _ in range(max(1, in_flight)):
        start_next()
    computed = 0
    for future in completed:
        atmosphere, chunk = chunk_of.pop(future.key)
        store.write(chunk, future.result())
        computed += 1
        if on_chunk is not None:
            on_chunk(chunk)
        active[atmosphere][1] -= 1
        if active[atmosphere][1] == 0:
            del active[atmosphere]  # its solver future, the last reference: Dask frees it
            start_next()
    return computed
