"""How much memory one task of a run may allocate: asked, or derived from this machine."""

from __future__ import annotations

# Imports inside functions: start-up time: the engine (scikit-learn) loads when a run
# derives its cap.


def task_memory(
    max_memory_mb: float | None, *, jobs: int, scheduler: str | None, data_bytes: int
) -> tuple[int | None, str]:
    """The bytes one task of a run may allocate, and where that cap comes from.

    Parameters
    ----------
    max_memory_mb : float or None
        The run's own cap in megabytes; 0: no limit; None: derived from what this machine
        has available, shared by ``jobs`` workers
        (:func:`benchmark.run.memory.default_task_memory`).  A run on a Dask cluster
        derives none: its workers' own memory limits apply.
    jobs : int
        Local worker processes (-1: one per core).
    scheduler : str or None
        The Dask scheduler the run uses, if any.
    data_bytes : int
        Bytes of the run's features.

    Returns
    -------
    tuple of (int or None, str)
        The cap (None: no limit) and a few words on its origin, stored with the run.
    """
    if max_memory_mb == 0:
        return None, "no limit asked"
    if max_memory_mb is not None:
        return int(max_memory_mb * 2**20), "asked"
    if scheduler is not None:
        return None, "the Dask workers' own memory limits"
    from touchbench.benchmark.run.engine import available_cores
    from touchbench.benchmark.run.memory import default_task_memory

    cap = default_task_memory(available_cores() if jobs == -1 else jobs, data_bytes=data_bytes)
    if cap is None:
        return None, "no limit: this machine's memory cannot be read"
    # whole megabytes: the figure the run's config and its failures' messages show
    return cap.bytes // 2**20 * 2**20, f"default: {cap.describe()}"
