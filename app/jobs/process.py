"""A worker process for one queued run or job: ``python -m app.jobs.process run 5``.

The store's URL comes from ``TOUCHBENCH_DATABASE_URL``, as the dispatcher passes it: a
command line is readable by any user on the host, and the URL may hold a password.  A
person running the module by hand may give ``--db URL`` instead.

It first lowers its CPU priority (``--nice``, the setting ``job_nice``: its engine
processes inherit it), so that a heavy run shares the cores with the service's predictions
rather than starving them.  It claims the item (another process claiming it first is not
an error: it exits quietly), carries it out, records how it ended, and exits.  It ends
itself, mid-run included, once the service that started it has died, so that a crashed
service leaves no orphan work; the run is then found ``interrupted`` and can be resumed.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time

from touchbench.app.environment import DATABASE_URL_VARIABLE

#: Seconds between checks that the parent service is alive.
PARENT_CHECK_INTERVAL = 1.0


def _exit_with_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_INTERVAL)
    os._exit(1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.jobs.process")
    parser.add_argument(
        "--db", metavar="URL", help=f"The store (default: ${DATABASE_URL_VARIABLE})."
    )
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--scheduler", default=None)
    parser.add_argument(
        "--nice", type=int, default=0, help="Raise this process's niceness by this much."
    )
    parser.add_argument("kind", choices=["run", "job"])
    parser.add_argument("id", type=int)
    args = parser.parse_args(argv)
    url = args.db or os.environ.get(DATABASE_URL_VARIABLE)
    if not url:
        parser.error(f"no store: set {DATABASE_URL_VARIABLE} or pass --db")
    if args.nice > 0:  # before the imports and the work: all of it at the lower priority
        os.nice(args.nice)
    threading.Thread(target=_exit_with_parent, args=(os.getppid(),), daemon=True).start()
    # A cancel interrupts the work as Ctrl-C does (app.services.jobs), and so does the
    # service stopping it with SIGTERM: the item is recorded cancelled or interrupted, not
    # left running.  Set whatever the service's own disposition was (it may ignore SIGINT).
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.default_int_handler)

    # loaded once the arguments are read and the parent is watched: start-up time (``--help``
    # and a bad argument need none of it; a service that dies meanwhile ends this process)
    from touchbench.app.errors import AppError
    from touchbench.app.services.jobs import execute_job
    from touchbench.app.services.runs import RunCancelled, execute_run
    from touchbench.app.store.database import Store

    try:
        store = Store(url)
    except AppError as error:  # the message shows the URL without its password
        print(f"{args.kind} {args.id}: {error}", file=sys.stderr)
        return 1
    try:
        if args.kind == "job":
            execute_job(store, args.id)
            return 0
        try:
            execute_run(store, args.id, jobs=args.jobs, scheduler=args.scheduler)
        except RunCancelled:
            return 0
        except AppError as error:  # claimed by another process, or refused: recorded there
            print(f"run {args.id}: {error}", file=sys.stderr)
            return 0
        except Exception as error:  # recorded as failed by execute_run where it could be
            print(f"run {args.id}: {type(error).__name__}: {error}", file=sys.stderr)
            return 1
        return 0
    finally:
        store.dispose()


if __name__ == "__main__":
    sys.exit(main())
