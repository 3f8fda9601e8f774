"""Ctrl-C and SIGTERM stop ``touchbench serve`` within a few seconds, whatever it computes.

uvicorn stops gracefully on the first signal: it stops accepting connections, waits for
the requests in flight, runs the service's shutdown (the dispatcher ends its job
processes), then raises the signal again, which :mod:`app.cli.signals` turns into exit
130 or 143.  A request computing in a worker thread cannot be interrupted, though, and
both uvicorn (by default) and asyncio (for a cancelled task whose thread goes on) would
wait for it, minutes for a heavy page.  So uvicorn waits at most :data:`GRACE` seconds for
requests in flight, and a watchdog started by the first signal ends the process
:data:`MARGIN` seconds later if it is still there; a second signal ends it at once.
With ``--workers N`` the supervisor does the same for its service processes: it stops
them, and kills those still there :data:`GRACE` + :data:`MARGIN` seconds after the
signal.  Either way the status is 128 + the first signal's number and stderr says
``touchbench: interrupted`` once, without a traceback: a request cancelled by the stop is
not logged as an error of the application.
"""

from __future__ import annotations

import asyncio
import logging
import os
import signal
import sys
import threading
from types import FrameType

import uvicorn
from uvicorn.main import STARTUP_FAILURE
from uvicorn.supervisors import Multiprocess

from touchbench.app.cli.exits import EXIT_INTERRUPTED

#: Seconds uvicorn waits for requests in flight before it cancels them.
GRACE = 2.0
#: Seconds after :data:`GRACE` before a process still busy is ended.
MARGIN = 3.0


#: Held by the one thread that ends the process (the main one or the watchdog).
_ENDING = threading.Lock()


class CancelledByStop(logging.Filter):
    """Drop the traceback uvicorn logs for a request it cancelled to stop (on the
    ``uvicorn.error`` logger, by ``serve``'s logging settings, in every service process):
    that is the stop at work, not an error of the application."""

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        return not isinstance(error, asyncio.CancelledError)


class StoppingServer(uvicorn.Server):
    """uvicorn's server, ended by a watchdog when a graceful stop takes too long."""

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        first = not self._captured_signals
        super().handle_exit(sig, frame)
        signum = self._captured_signals[0]
        if not first:  # the user insists: no more waiting
            end_now(signum)
        watchdog = threading.Timer(GRACE + MARGIN, end_now, args=(signum,))
        watchdog.daemon = True  # never what keeps the process alive
        watchdog.name = "stop-watchdog"
        watchdog.start()


class StoppingSupervisor(Multiprocess):
    """uvicorn's supervisor of ``--workers N`` service processes, which remembers the first
    signal and kills the processes a graceful stop leaves behind."""

    signum: int | None = None

    def handle_int(self) -> None:
        self._stopping(signal.SIGINT)
        super().handle_int()

    def handle_term(self) -> None:
        self._stopping(signal.SIGTERM)
        super().handle_term()

    def _stopping(self, signum: int) -> None:
        if self.signum is not None:  # the user insists: no more waiting
            self._kill_all()
            end_now(self.signum)
        self.signum = signum
        watchdog = threading.Timer(GRACE + MARGIN, self._kill_all, args=(True,))
        watchdog.daemon = True
        watchdog.name = "stop-watchdog"
        watchdog.start()

    def _kill_all(self, end: bool = False) -> None:
        for process in self.processes:
            process.kill()
        if end and self.signum is not None:
            end_now(self.signum)


def end_now(signum: int) -> None:
    """End the process at once with the status of ``signum`` (skipping the threads still
    computing, which would only be joined)."""
    code = 128 + signum if signum in (signal.SIGINT, signal.SIGTERM) else EXIT_INTERRUPTED
    _ENDING.acquire()  # the other thread, ending too, never returns from here
    try:
        sys.stdout.flush()
        print("touchbench: interrupted", file=sys.stderr, flush=True)
    finally:
        os._exit(code)


def serve(config: uvicorn.Config) -> None:
    """Run one service process with ``config`` until a signal stops it, then end the
    process with the signal's status.

    Raises
    ------
    SystemExit
        With uvicorn's start-up failure status when the service could not start.
    """
    if config.workers > 1:
        supervisor = StoppingSupervisor(config, sockets=[config.bind_socket()])
        supervisor.run()
        if supervisor.signum is not None:
            end_now(supervisor.signum)
        return
    server = StoppingServer(config)
    try:
        server.run()
    except KeyboardInterrupt as interrupt:  # the signal again, once uvicorn has stopped
        # ended here, not by returning: the interpreter would join the threads computing
        end_now(getattr(interrupt, "signum", signal.SIGINT))
    if not server.started:  # as uvicorn.run: the port is taken, the app failed to load
        sys.exit(STARTUP_FAILURE)
