"""Work on the next items of a stream done by a few threads ahead of its consumer, in order.

Arrow's CSV reader and numpy release the GIL for most of their work, so on a machine with
cores to spare, plain blocks of an ARFF file are parsed side by side while the consumer
(the store, for an import) takes the ones before; memory stays bounded by how far ahead
the threads may run.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

Item = TypeVar("Item")
Result = TypeVar("Result")

#: Threads that parse ahead, and how many items may be parsed or waiting at once.
WORKERS = 2
AHEAD = 3


def ordered_ahead(
    items: Iterable[Item],
    work: Callable[[Item], Result],
    wanted: Callable[[Item], bool],
    *,
    workers: int = WORKERS,
    ahead: int = AHEAD,
) -> Iterator[tuple[Item, Future[Result] | None]]:
    """Each item of ``items`` in order, with ``work(item)`` started in a thread if
    ``wanted(item)``.

    At most ``ahead`` items are taken from ``items`` before the consumer has taken theirs,
    so at most that many results wait in memory.  The threads start with the first wanted
    item (a stream with none starts none) and have ended when this generator ends: when
    the consumer stops early (or ``items`` raises), work not yet started is cancelled and
    work under way finishes first.

    Yields
    ------
    item : Item
    future : Future or None
        ``work(item)`` (its ``result()`` raises what ``work`` raised), ``None`` if the item
        was not wanted.
    """
    pool: ThreadPoolExecutor | None = None
    waiting: deque[tuple[Item, Future[Result] | None]] = deque()
    finished = False
    try:
        for item in items:
            future = None
            if wanted(item):
                if pool is None:
                    pool = ThreadPoolExecutor(workers, thread_name_prefix="read-ahead")
                future = pool.submit(work, item)
            waiting.append((item, future))
            if len(waiting) >= ahead:
                yield waiting.popleft()
        while waiting:
            yield waiting.popleft()
        finished = True
    finally:
        if pool is not None:
            # Every future was handed on when the stream ended: those are left to finish.
            pool.shutdown(wait=True, cancel_futures=not finished)
