"""The default memory cap of one task: what the machine has available, shared by the workers.

A classifier that allocates more than the machine holds makes it swap, or meets the
kernel's out-of-memory killer, which may kill any process (the engine's own, another
user's).  The engine caps each task instead (``RLIMIT_DATA`` in its worker): a task over
its cap fails with a ``MemoryError`` of its own, marked like a timeout, and the run goes on.
Unless the user gives a cap, it is derived here from ``/proc/meminfo`` when the run starts:

    cap = (MemAvailable - reserve - data) / workers - worker baseline - data

where the reserve is a tenth of MemTotal (at least 256 MB) kept for the rest of the
machine, ``data`` the run's features (held once by the parent, once by each worker) and
the worker baseline what an idle worker's interpreter and libraries hold.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Mapping
from dataclasses import dataclass

#: Bytes in a mebibyte.
MB = 2**20
#: Share of MemTotal kept for the rest of the machine, and its floor in bytes.
RESERVE_SHARE = 0.1
MIN_RESERVE = 256 * MB
#: Bytes an idle worker holds beyond its data (Python, NumPy, SciPy, scikit-learn).
WORKER_BASELINE = 300 * MB
#: The smallest cap derived: below it no classifier of the catalogue fits anything, and a
#: machine this short of memory is better told by the failures than by swapping.
MIN_CAP = 256 * MB


@dataclass(frozen=True)
class MemoryCap:
    """A derived cap and what it was derived from, for the run's stored options.

    Attributes
    ----------
    bytes : int
        Bytes of data memory one task may allocate beyond its worker's copy of the data.
    available, total : int
        The machine's MemAvailable and MemTotal when it was derived, in bytes.
    workers : int
        The worker processes that share it.
    """

    bytes: int
    available: int
    total: int
    workers: int

    def describe(self) -> str:
        """``22,360 MB available, 2 workers``: where the cap comes from."""
        share = "1 worker" if self.workers == 1 else f"{self.workers} workers"
        return f"{self.available / MB:,.0f} MB available of {self.total / MB:,.0f} MB, {share}"


def read_meminfo(path: str = "/proc/meminfo") -> dict[str, int]:
    """``/proc/meminfo``'s fields in bytes (``{"MemTotal": ..., "MemAvailable": ...}``);
    empty where the file does not exist (not Linux)."""
    fields: dict[str, int] = {}
    with contextlib.suppress(OSError), open(path) as info:
        for line in info:
            name, _, rest = line.partition(":")
            parts = rest.split()
            if parts and parts[0].isdigit():
                scale = 1024 if parts[1:] == ["kB"] else 1
                fields[name] = int(parts[0]) * scale
    return fields


def default_task_memory(
    workers: int, *, data_bytes: int = 0, meminfo: Mapping[str, int] | None = None
) -> MemoryCap | None:
    """The cap of one task when ``workers`` tasks run at once on this machine.

    Parameters
    ----------
    workers : int
        Worker processes running tasks at once (``--jobs``).
    data_bytes : int
        Bytes of the run's data (its features), which the parent and every worker hold.
    meminfo : mapping of str to int, optional
        MemAvailable and MemTotal in bytes; default: :func:`read_meminfo`.

    Returns
    -------
    MemoryCap or None
        None where the machine's memory cannot be read (no ``/proc/meminfo`` and no
        ``sysconf``): the run then has no cap unless one is given.
    """
    info = read_meminfo() if meminfo is None else meminfo
    total = info.get("MemTotal") or _sysconf_bytes("SC_PHYS_PAGES")
    available = info.get("MemAvailable") or _sysconf_bytes("SC_AVPHYS_PAGES")
    if not total or not available:
        return None
    workers = max(1, workers)
    reserve = max(int(RESERVE_SHARE * total), MIN_RESERVE)
    share = (min(available, total) - reserve - data_bytes) // workers
    cap = max(share - WORKER_BASELINE - data_bytes, MIN_CAP)
    return MemoryCap(int(cap), int(available), int(total), workers)


def _sysconf_bytes(name: str) -> int:
    try:
        return int(os.sysconf(name)) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 0
