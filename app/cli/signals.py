"""Ctrl-C and SIGTERM end a command the same way: as an interrupt the command can clean up
after (a run marked ``interrupted``, an import rolled back), then exit 130 or 143.

A process started in the background by a non-interactive shell (``touchbench bench ... &``
in a script) inherits SIGINT *ignored*, so Python never installs its Ctrl-C handler there
and ``kill -INT`` would do nothing; a command asked to stop by a signal sent on purpose
should stop, so the handler is installed whatever the inherited disposition.  SIGTERM
(``kill PID``, a CI time-out, systemd stopping a unit) would otherwise end the process at
once, leaving a run ``running`` until its heartbeat goes stale.

An interrupt raised while Python runs a finaliser (a ``__del__``, a weakref callback of the
cyclic collector) cannot propagate: Python prints it as "Exception ignored in ..." with a
traceback and carries on, and the Ctrl-C is lost.  :func:`redeliver_lost_interrupts` sends
such an interrupt again, so it lands in ordinary code a moment later and ends the command
as any other does.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

#: Signals that interrupt a command.
INTERRUPTS = (signal.SIGINT, signal.SIGTERM)

#: Seconds after which an interrupt a finaliser swallowed is sent again.
REDELIVERY_DELAY = 0.01


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
    _HEARD.clear()  # a command of its own (tests run many in one process)
    previous = {signum: signal.getsignal(signum) for signum in INTERRUPTS}
    for signum in INTERRUPTS:
        signal.signal(signum, _interrupt)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


#: The signals that interrupted a command of this process, first first: typer turns any
#: interrupt into the status 130, and :func:`interrupted_status` tells SIGTERM's apart.
_HEARD: list[int] = []


def _interrupt(signum: int, frame: FrameType | None) -> None:
    _HEARD.append(signum)
    raise Interrupted(signum)


def interrupted_status() -> int:
    """128 + the number of the first signal that interrupted a command of this process
    (130 when none is known: an interrupt Python raised itself is a Ctrl-C)."""
    return 128 + (_HEARD[0] if _HEARD else signal.SIGINT)


@contextmanager
def deferred_interrupts(on_interrupt: Callable[[], object]) -> Iterator[None]:
    """Within the block, the first SIGINT or SIGTERM only calls ``on_interrupt`` (which
    must not block: set a flag) and the block ends its work in its own time; at the end
    of the block it raises :class:`Interrupted` as :func:`interrupts` would have.  A
    second signal raises at once (a stuck command still stops on a second Ctrl-C).

    For a loop that must not be cut in the middle of an item (a ROS node between two
    messages: the audio already received is still processed and published).  In another
    thread than the main one nothing is installed.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    heard: list[int] = []

    def handler(signum: int, frame: FrameType | None) -> None:
        if heard:
            _interrupt(signum, frame)
        heard.append(signum)
        _HEARD.append(signum)
        on_interrupt()

    previous = {signum: signal.getsignal(signum) for signum in INTERRUPTS}
    for signum in INTERRUPTS:
        signal.signal(signum, handler)
    try:
        yield
    except Exception:
        if heard:  # what the interrupt cut short (a wait given up) is not the news
            raise Interrupted(heard[0]) from None
        raise
    finally:
        for signum, before in previous.items():
            signal.signal(signum, before if before is not None else signal.SIG_DFL)
    if heard:
        raise Interrupted(heard[0])


def redeliver_lost_interrupts() -> None:
    """Install a ``sys.unraisablehook`` that re-sends an interrupt a finaliser swallowed.

    Other unraisable exceptions go to the hook that was there before.
    """
    previous: Callable[[Any], object] = sys.unraisablehook

    def hook(unraisable: Any) -> None:
        error = unraisable.exc_value
        if isinstance(error, KeyboardInterrupt):
            # Sent from here, the signal's handler would run at once, inside the finaliser
            # again; sent from a timer thread a moment later, it runs in the main thread
            # once this hook has returned (should that be in another finaliser, it comes
            # back here).
            signum = getattr(error, "signum", signal.SIGINT)
            later = threading.Timer(REDELIVERY_DELAY, signal.raise_signal, args=(signum,))
            later.daemon = True
            later.start()
            return
        previous(unraisable)

    sys.unraisablehook = hook
