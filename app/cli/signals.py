"""Ctrl-C and SIGTERM end a command the same way: as an interrupt the command can clean up
after (a run marked ``interrupted``, an import rolled back), then exit 130 or 143.

A process started in the background by a non-interactive shell (``touchbench bench ... &``
in a script) inherits SIGINT *ignored*, so Python never installs its Ctrl-C handler there
and ``kill -INT`` would do nothing; a command asked to stop by a signal sent on purpose
should stop, so the handler is installed whatever the inherited disposition.  SIGTERM
(``kill PID``, a CI time-out, systemd stopping a unit) would otherwise end the process at
once, leaving a run ``running`` until its heartbeat goes stale.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

#: Signals that interrupt a command.
INTERRUPTS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """A command was interrupted by ``signum`` (a KeyboardInterrupt, so everything that
    cleans up after Ctrl-C cleans up after it too)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        """128 + the signal's number, as shells report a process ended by it."""
        return 128 + self.signum


@contextmanager
def interrupts() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`Interrupted` in the main thread.

    The previous handlers come back at the end (tests run many commands in one process).
    Outside the main thread nothing can be installed and nothing is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in INTERRUPTS}
    for signum in INTERRUPTS:
        signal.signal(signum, _interrupt)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


def _interrupt(signum: int, frame: FrameType | None) -> None:
    raise Interrupted(signum)
