"""Progress of a long answer (a learning curve, an ablation) told at most so often.

Such an answer hears of every finished task, but its summary so far is built from every
result yet (quadratic over the job) and is written to the job's row each time, so a large
learning curve spent most of its CPU on summaries.  Told at most every
:data:`PROGRESS_SECONDS`, that work follows the job's duration, not its number of tasks
squared.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TypeVar

#: Least seconds between two progress reports of one answer.
PROGRESS_SECONDS = 1.0

T = TypeVar("T")


def throttled(
    on_progress: Callable[[T], None], summary: Callable[[], T], seconds: float = PROGRESS_SECONDS
) -> Callable[[], None]:
    """A function that calls ``on_progress(summary())`` if ``seconds`` passed since it last
    did (the first call always does); ``summary`` is built only then."""
    last = -math.inf

    def tell() -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= seconds:
            last = now
            on_progress(summary())

    return tell
