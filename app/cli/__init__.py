"""touchbench: app/cli.

A Ctrl-C that comes before a command handles interrupts itself (while Python loads the CLI's
modules, in its first few tenths of a second, or as it exits) ends the process with one
line and the status of an interrupt, not with a traceback of whatever module was loading:
nothing has been done yet that needs cleaning up.  This package is imported before any of
those modules, so the hook is in place from the start.
"""

from __future__ import annotations

import sys
from types import TracebackType


def _interrupted_quietly(
    kind: type[BaseException], value: BaseException, trace: TracebackType | None
) -> None:
    """``sys.excepthook``: one line for an interrupt nobody caught, as before otherwise."""
    if issubclass(kind, KeyboardInterrupt):
        print("touchbench: interrupted", file=sys.stderr)
        return
    _previous_hook(kind, value, trace)


_previous_hook = sys.excepthook
sys.excepthook = _interrupted_quietly

from touchbench.app.cli.signals import redeliver_lost_interrupts  # noqa: E402 (after the hook: see above)

redeliver_lost_interrupts()
