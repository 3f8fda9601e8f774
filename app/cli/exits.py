"""Exit statuses of ``touchbench``, and the exception that ends a command with one of them.

A module of its own, importing nothing, so that ``app.cli.main`` knows them without loading
what printing needs (rich's tables, pydantic).
"""

from __future__ import annotations

#: Exit status of a command whose work failed (a run whose every task failed, a cancelled
#: run) or that met an unexpected error.
EXIT_FAILED = 1
#: Exit status of bad input or usage: one line on stderr names what and where.
EXIT_USAGE = 2
#: Exit status after Ctrl-C (128 + SIGINT), as shells expect.
EXIT_INTERRUPTED = 130


class ExitWith(Exception):  # noqa: N818 (an outcome that ends the command, not a bug)
    """End the command with one line on stderr and ``exit_code``.

    Parameters
    ----------
    message : str
        What happened and what to do next, e.g. how to resume an interrupted run.
    exit_code : int
        :data:`EXIT_INTERRUPTED` after Ctrl-C, :data:`EXIT_FAILED` when the work failed.
    """

    def __init__(self, message: str, exit_code: int) -> None:
        super().__init__(message)
        self.exit_code = exit_code
